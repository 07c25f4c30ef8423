//! The ray-cast reference traced on the GPU (`compare --reference gpu`): the CPU reference's
//! points under the pixels (`reference::pixel_points`, primary rays through the CPU's BVH), its
//! light samples in its progressive order (`geometry::progressive::progressive_order`) and its
//! conventions (`geometry::oracle`: which points get rays, the segment's `SELF_EPS`), with the
//! shadow rays traced by `passes::trace` against the same triangles, a batch of samples per
//! dispatch, by one of its two paths: hardware ray queries where the device has them, else the
//! same BVH flattened into a storage buffer and traversed in WGSL with the CPU's tolerant
//! triangle test ([`Path`]). Only the shadow rays move to the GPU, so the references differ
//! only where a ray grazes an edge within rounding (`tests/gpu/trace.rs` measures how often,
//! for both paths).

use std::time::Instant;

use glam::Vec3;

use super::adapter::{Capabilities, Verdict};
use super::methods::AdapterNeeds;
use super::passes::trace::{max_points, Path, ReferenceRays, TraceScene};
use super::reference::{self, Computed};
use super::{GpuContext, RenderError};
use crate::geometry::oracle::Oracle;
use crate::geometry::progressive::progressive_order;
use crate::scene::Scene;

/// What the GPU reference needs of the adapter: compute shaders, and the tracer's storage
/// buffers in the compute stage (the BVH path's, which every adapter with these takes; ray
/// queries are used where there are any, [`Path::best`]).
pub const NEEDS: AdapterNeeds = AdapterNeeds {
    downlevel: wgpu::DownlevelFlags::COMPUTE_SHADERS,
    storage_buffers_per_stage: super::passes::trace::STORAGE_BUFFERS,
    ..AdapterNeeds::NONE
};

/// Shadow rays per dispatch, about: a batch of samples per pixel is as many as keeps one
/// dispatch near this (at least one sample), so no dispatch runs long on any device.
const RAYS_PER_DISPATCH: u64 = 1 << 22;

/// Why the GPU reference cannot run on `caps`, if it cannot.
pub fn refuses_on(caps: &Capabilities) -> Option<String> {
    match NEEDS.check(caps) {
        Verdict::Cannot(missing) => Some(format!(
            "the GPU reference cannot run on {}: it needs {}",
            caps.adapter,
            missing.join(", ")
        )),
        _ => None,
    }
}

/// How the GPU's shadow rays were traced and what they cost, summed over every ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cost {
    /// The tracer's path.
    pub path: Path,
    /// Shadow rays traced.
    pub rays: u64,
    /// BVH boxes tested (0 on [`Path::RayQuery`]: the driver does not say).
    pub box_tests: u64,
    /// Triangles tested (0 on [`Path::RayQuery`]).
    pub triangle_tests: u64,
}

/// The whole reference of a `width`×`height` view of `scene` at `samples` per pixel, its shadow
/// rays traced on the GPU by [`Path::auto`]; `progress` hears (samples done, total) after each
/// batch. V per pixel is `visible / K` exactly as the CPU reference computes it.
pub fn compute(
    ctx: &GpuContext,
    scene: &Scene,
    width: u32,
    height: u32,
    samples: u32,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Computed, Cost), RenderError> {
    let piece = max_points(ctx);
    let path = Path::auto(ctx)?;
    compute_in_pieces(ctx, scene, (width, height), samples, path, piece, progress)
}

/// [`compute`] by `path`, with the image traced in pieces of at most `piece` pixels (at least
/// 1), each its own buffers and dispatches: [`compute`] takes the most one storage binding of
/// the device holds; a test, fewer, to see that the pieces make the same image, or names the
/// path, to hold one to the other on one device.
pub fn compute_in_pieces(
    ctx: &GpuContext,
    scene: &Scene,
    (width, height): (u32, u32),
    samples: u32,
    path: Path,
    piece: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Computed, Cost), RenderError> {
    if let Some(why) = refuses_on(&ctx.caps) {
        return Err(RenderError::Request(why));
    }
    let oracle = Oracle::from_scene(scene, samples as usize);
    let points = reference::pixel_points(scene, oracle.bvh(), width, height);
    let hit_pixels = points.iter().filter(|p| p.is_some()).count();
    let traced: Vec<Option<Vec3>> = points
        .iter()
        .map(|p| p.filter(|&x| oracle.casts_from(x)))
        .collect();
    let order = progressive_order(oracle.sample_points());
    let t = Instant::now();
    let trace_scene = TraceScene::new(ctx, oracle.bvh(), path)?;
    // An image larger than one storage binding holds is traced in pieces, side by side.
    let mut pieces = traced
        .chunks(piece.clamp(1, max_points(ctx)))
        .map(|points| ReferenceRays::new(ctx, &trace_scene, points, &order))
        .collect::<Result<Vec<_>, _>>()?;
    let total = pieces.first().map_or(0, ReferenceRays::samples_total);
    let lit = traced.iter().filter(|p| p.is_some()).count().max(1) as u64;
    let batch = (RAYS_PER_DISPATCH / lit).clamp(1, u64::from(total.max(1))) as u32;
    let mut done = 0;
    while done < total {
        for piece in &mut pieces {
            piece.step(ctx, batch);
        }
        super::readback::map_now(&ctx.device)?;
        done = pieces.first().map_or(total, ReferenceRays::samples_done);
        progress(done as usize, total as usize);
    }
    let mut counts = Vec::with_capacity(traced.len());
    for piece in &pieces {
        counts.extend(piece.read(ctx)?);
    }
    let rays_ms = t.elapsed().as_secs_f64() * 1e3;
    let k = total.max(1) as f32;
    let visibility = counts
        .iter()
        .zip(&traced)
        .map(|(c, p)| if p.is_some() { c.count as f32 / k } else { 0.0 })
        .collect();
    let mut cost = Cost {
        path,
        rays: 0,
        box_tests: 0,
        triangle_tests: 0,
    };
    for (c, p) in counts.iter().zip(&traced) {
        if p.is_some() {
            cost.rays += u64::from(total);
            cost.box_tests += u64::from(c.box_tests);
            cost.triangle_tests += u64::from(c.triangle_tests);
        }
    }
    Ok((
        Computed {
            visibility,
            rays_ms,
            hit_pixels,
        },
        cost,
    ))
}
