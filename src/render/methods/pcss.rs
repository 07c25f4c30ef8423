//! `pcss`: percentage-closer soft shadows (Fernando 2005) sized by the disk, on the centre's
//! shadow map: a blocker search in the cone from the point to the disk, then a filter as wide as
//! the penumbra the blockers' mean distance predicts, both over a rotated Poisson disk
//! (`shaders/methods/pcss.wgsl`).

use super::shadow_mapped::{Bound, MapProducts, ShadowMapped};
use super::Cost;
use super::{FrameInputs, Knob, MethodSpec, Quality};
use crate::render::passes::shadow_map::ShadowMapTargets;
use crate::render::timer::Recorder;
use crate::render::{buffer_entry, uniform_entry, GpuContext, RenderError};
use crate::scene::Scene;

pub static BLOCKER_TAPS: Knob = Knob::int(
    "blocker-taps",
    "pcss: blocker-search taps (rotated Poisson disk)",
    1..=POISSON_POINTS as u32,
    16,
);

pub static FILTER_TAPS: Knob = Knob::int(
    "filter-taps",
    "pcss: filter taps (rotated Poisson disk)",
    1..=POISSON_POINTS as u32,
    32,
);

pub static PCSS: MethodSpec = MethodSpec::new("pcss", SHADER, |ctx| {
    Box::new(ShadowMapped::new(
        ctx,
        SHADER,
        PoissonDisk::new(ctx),
        PcssParams::new,
    ))
})
.adapter(super::SHADOW_MAPPED)
.about("percentage-closer soft shadows (Fernando 2005)")
.knobs(&[&BLOCKER_TAPS, &FILTER_TAPS])
// A blocker search over a disk; under a rectangle or polygon, over the disk of the same area
// about its centroid (docs/method/README.md#pcss).
.lights(super::AREA_LIGHTS)
.bench("pcss 16/32", &[(&BLOCKER_TAPS, 16), (&FILTER_TAPS, 32)])
.cost(
    Cost::counted("shadow-map taps (blocker search and filter)").paths(&[
        "not searched: nearer the light than the nearest caster, off the map, or dark",
        "no blocker found: lit",
        "blockers found: filtered",
    ]),
)
// Engines' presets: PlayCanvas 8/12 and 28/42, Unity HDRP 16/24.
.sweep(
    &[Quality::Knob(&BLOCKER_TAPS), Quality::Knob(&FILTER_TAPS)],
    &[&[8, 12], &[16, 24], &[16, 32], &[28, 42], &[32, 64]],
);

/// Points of the Poisson disk (`PoissonDisk` of the shader: two per vec4).
pub const POISSON_POINTS: usize = 64;

const SHADER: &str = "methods/pcss.wgsl";

/// `PcssParams` of `shaders/methods/pcss.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PcssParams {
    pub blocker_taps: u32,
    pub filter_taps: u32,
    /// The nearest caster's distance from the light centre ([`nearest_caster`]).
    pub nearest_caster: f32,
    pub _pad0: u32,
}

impl PcssParams {
    pub fn new(f: &FrameInputs<'_>) -> PcssParams {
        PcssParams {
            blocker_taps: f.knobs.get(&BLOCKER_TAPS),
            filter_taps: f.knobs.get(&FILTER_TAPS),
            nearest_caster: nearest_caster(f.scene),
            _pad0: 0,
        }
    }
}

/// The Poisson disk's points, bound at 3 (`PoissonDisk` of the shader), made once.
pub struct PoissonDisk {
    buffer: wgpu::Buffer,
}

impl PoissonDisk {
    fn new(ctx: &GpuContext) -> PoissonDisk {
        use wgpu::util::DeviceExt;
        let points: Vec<f32> = poisson_disk(POISSON_POINTS)
            .iter()
            .flat_map(|p| [p.x, p.y])
            .collect();
        let buffer = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("PoissonDisk"),
                contents: bytemuck::cast_slice(&points),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        PoissonDisk { buffer }
    }
}

impl MapProducts for PoissonDisk {
    type Key = ();

    fn layout(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        vec![uniform_entry(3, wgpu::ShaderStages::FRAGMENT)]
    }

    fn key(&self, _: &FrameInputs<'_>) {}

    fn record(&mut self, _: &FrameInputs<'_>, _: &mut Recorder<'_>, _: &ShadowMapTargets, _: ()) {}

    fn entries(&mut self, _: &FrameInputs<'_>) -> Result<Bound<'_>, RenderError> {
        Ok(Bound {
            generations: Vec::new(),
            entries: vec![buffer_entry(3, &self.buffer)],
        })
    }
}

/// The distance from the light centre to the nearest caster vertex in front of the light: where
/// the blocker search stops.
fn nearest_caster(scene: &Scene) -> f32 {
    let light = scene.light;
    scene
        .casters()
        .flat_map(|o| o.mesh.positions.iter())
        .filter(|v| light.reaches(**v))
        .map(|v| (*v - light.center()).length())
        .filter(|d| d.is_finite() && *d > 0.0)
        .fold(f32::MAX, f32::min)
        .min(1e30)
}

/// `n` points in the unit disk by Mitchell's best-candidate algorithm (deterministic): each new
/// point is the farthest of a few candidates from those before it, so every prefix is spread over
/// the disk and a method may use the first k taps of one table.
pub fn poisson_disk(n: usize) -> Vec<glam::Vec2> {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        // SplitMix64.
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut points: Vec<glam::Vec2> = Vec::with_capacity(n);
    while points.len() < n {
        let candidates = 8 * (points.len() + 1);
        let mut best = glam::Vec2::ZERO;
        let mut best_d = -1.0f32;
        for _ in 0..candidates {
            let p = crate::geometry::oracle::concentric(next(), next());
            let d = points
                .iter()
                .map(|q| q.distance_squared(p))
                .fold(f32::MAX, f32::min);
            if d > best_d {
                best_d = d;
                best = p;
            }
        }
        points.push(best);
    }
    points
}
