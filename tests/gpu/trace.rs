//! The GPU's shadow-ray tracer (`render::passes::trace`, the scene's BVH traversed in WGSL)
//! against the CPU's (`geometry::bvh::Bvh`'s tolerant any-hit query, the oracle's), ray by ray,
//! and the reference it traces (`render::gpu_reference`, `compare --reference gpu`) against the
//! CPU reference, on every built-in scene at a small size.
//!
//! Both tracers run the same test on the same flattened numbers, so they disagree only where
//! rounding decides: a ray that grazes an edge, a corner or a segment's end within a few ulps
//! (the GPU's `f32` arithmetic may fuse or reorder what the CPU rounds step by step). A ray is
//! called grazing here when the CPU's own answer changes as the ray is moved by 1e-5 of its
//! length (either end nudged along an axis, or the interval's ends moved); every disagreement
//! must be a grazing ray, and how many there are is printed.

use dbuffer::geometry::bvh::Bvh;
use dbuffer::geometry::oracle::{Oracle, SELF_EPS};
use dbuffer::geometry::view;
use dbuffer::render::gpu_reference;
use dbuffer::render::offline::Offline;
use dbuffer::render::passes::trace::{self, GpuBvh, Ray};
use dbuffer::render::truth::{self, Engine};
use dbuffer::render::{reference, FrameRequest, GpuContext, Knobs};
use dbuffer::scene::{self, builtin};
use glam::Vec3;

use crate::support::rng::Rng;
use crate::support::wgsl_layout::assert_wgsl_layout;

fn ctx() -> GpuContext {
    GpuContext::headless().unwrap_or_else(|e| panic!("{e}"))
}

/// The CPU's answer: the oracle's query.
fn cpu_blocked(bvh: &Bvh, r: &Ray) -> bool {
    bvh.find_any_hit_tolerant(r.origin, r.dir, r.t_min, r.t_max)
        .is_some()
}

/// Whether the CPU's answer for `r` changes when the ray moves by 1e-5 of its length.
fn grazing(bvh: &Bvh, r: &Ray) -> bool {
    let answer = cpu_blocked(bvh, r);
    let d = 1e-5 * r.dir.length();
    let end = r.origin + r.dir;
    let mut variants = vec![
        Ray {
            t_min: r.t_min - 1e-5,
            t_max: r.t_max + 1e-5,
            ..*r
        },
        Ray {
            t_min: r.t_min + 1e-5,
            t_max: r.t_max - 1e-5,
            ..*r
        },
    ];
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        for s in [-d, d] {
            variants.push(Ray {
                dir: end + axis * s - r.origin,
                ..*r
            });
            variants.push(Ray {
                origin: r.origin + axis * s,
                dir: end - (r.origin + axis * s),
                ..*r
            });
        }
    }
    variants.iter().any(|v| cpu_blocked(bvh, v) != answer)
}

#[test]
fn gpu_any_hit_agrees_with_the_cpu_but_for_grazing_rays() {
    let ctx = ctx();
    let mut rng = Rng(45);
    let (mut total, mut blocked, mut differ, mut grazing_rays) = (0usize, 0usize, 0usize, 0usize);
    for name in builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let oracle = Oracle::from_scene(&scene, 64);
        let bvh = oracle.bvh();
        let points: Vec<Vec3> = view::points(&scene, bvh, 24, 24)
            .into_iter()
            .flatten()
            .collect();
        let samples = oracle.sample_points();
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for t in scene.all_triangles() {
            for p in t {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        let mut rays = Vec::new();
        // Shadow rays as the reference casts them: from the points under pixels to the light.
        for _ in 0..1500 {
            let x = points[rng.below(points.len())];
            let s = samples[rng.below(samples.len())];
            rays.push(Ray {
                origin: x,
                dir: s - x,
                t_min: SELF_EPS,
                t_max: 1.0 - SELF_EPS,
            });
        }
        // Rays through a point of a triangle's edge or at its corner, extended past it: the
        // rays rounding decides, where two triangles share the edge.
        let triangles = scene.all_triangles();
        for i in 0..500 {
            let t = &triangles[rng.below(triangles.len())];
            let e = rng.below(3);
            let f = if i % 5 == 0 { 0.0 } else { rng.next() };
            let p = t[e].lerp(t[(e + 1) % 3], f);
            let x = points[rng.below(points.len())];
            rays.push(Ray {
                origin: x,
                dir: (p - x) * 1.5,
                t_min: SELF_EPS,
                t_max: 1.0 - SELF_EPS,
            });
        }
        // Rays between random points of the scene's bounds, whole and in part.
        let at = |rng: &mut Rng| {
            Vec3::new(
                rng.range(lo.x, hi.x),
                rng.range(lo.y, hi.y),
                rng.range(lo.z, hi.z),
            )
        };
        for i in 0..500 {
            let (a, b) = (at(&mut rng), at(&mut rng));
            let (t_min, t_max) = if i % 2 == 0 { (0.0, 1.0) } else { (0.25, 0.75) };
            rays.push(Ray {
                origin: a,
                dir: b - a,
                t_min,
                t_max,
            });
        }
        let gpu_bvh = GpuBvh::new(&ctx, &bvh.flatten()).unwrap_or_else(|e| panic!("{e}"));
        let gpu = trace::any_hit(&ctx, &gpu_bvh, &rays).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(gpu.len(), rays.len());
        let mut here = 0;
        for (r, g) in rays.iter().zip(&gpu) {
            let cpu = cpu_blocked(bvh, r);
            let graze = grazing(bvh, r);
            blocked += usize::from(cpu);
            grazing_rays += usize::from(graze);
            if cpu != (g.count == 1) {
                here += 1;
                assert!(
                    graze,
                    "{name}: the GPU says blocked = {}, the CPU {cpu}, for a ray that does not \
                     graze anything: {r:?}",
                    g.count == 1
                );
            }
            assert!(g.box_tests >= 1, "{name}: every ray tests the root's box");
        }
        differ += here;
        total += rays.len();
        if here > 0 {
            eprintln!("{name}: {here} of {} rays differ, all grazing", rays.len());
        }
    }
    eprintln!(
        "GPU against CPU any-hit: {total} rays on {} built-ins, {blocked} blocked on the CPU, \
         {grazing_rays} grazing ({:.2} %); {differ} answered otherwise on the GPU ({:.4} %), \
         every one of them grazing",
        builtin::names().len(),
        100.0 * grazing_rays as f64 / total as f64,
        100.0 * differ as f64 / total as f64
    );
    assert!(
        blocked > total / 10,
        "the rays test something: {blocked} blocked"
    );
    assert!(
        (differ as f64) < 1e-3 * total as f64,
        "{differ} of {total} rays differ"
    );
}

/// Sampling noise of the difference of two K-sample estimates of V at `v`: the binomial
/// standard deviation of one, √(V(1 − V)/K), times √2.
fn noise(v: f32, k: u32) -> f32 {
    (2.0 * v * (1.0 - v) / k as f32).sqrt()
}

/// The GPU reference against the CPU one on every built-in at 48² and K = 64. They take the
/// same samples from the same points, so they differ only where a ray grazes; the bound held is
/// the one their sampling noise states: per pixel |ΔV| within 4 standard deviations of the
/// difference of two K-sample estimates (plus one sample, 1/K, for a pixel at V = 0 or 1 whose
/// binomial deviation is 0), and the mean |ΔV| over the pixels below 0.001.
#[test]
fn gpu_reference_matches_the_cpu_reference_on_every_builtin() {
    let ctx = ctx();
    let (w, h, k) = (48u32, 48u32, 64u32);
    let (mut pixels, mut differ, mut worst_mean) = (0usize, 0usize, 0.0f64);
    let (mut cpu_ms, mut gpu_ms) = (0.0, 0.0);
    for name in builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let cpu = reference::compute(&scene, w, h, k, &mut |_, _| {});
        let (gpu, cost) = gpu_reference::compute(&ctx, &scene, w, h, k, &mut |_, _| {})
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        cpu_ms += cpu.rays_ms;
        gpu_ms += gpu.rays_ms;
        assert_eq!(gpu.hit_pixels, cpu.hit_pixels, "{name}: the same points");
        assert_eq!(gpu.visibility.len(), cpu.visibility.len());
        let mut sum = 0.0f64;
        for (i, (a, b)) in cpu.visibility.iter().zip(&gpu.visibility).enumerate() {
            let d = (a - b).abs();
            sum += f64::from(d);
            differ += usize::from(d > 0.0);
            let bound = 4.0 * noise(0.5 * (a + b), k) + 1.0 / k as f32;
            assert!(
                d <= bound,
                "{name}: pixel {i} has V {a} on the CPU and {b} on the GPU (bound {bound})"
            );
        }
        let mean = sum / cpu.visibility.len() as f64;
        worst_mean = worst_mean.max(mean);
        pixels += cpu.visibility.len();
        assert!(mean < 1e-3, "{name}: mean |ΔV| {mean}");
        assert!(
            cost.rays == 0 || cost.box_tests >= cost.rays,
            "{name}: every ray tests a box"
        );
    }
    eprintln!(
        "GPU against CPU reference, {w}x{h}, K = {k}, {} built-ins: {differ} of {pixels} pixels \
         differ, worst mean |ΔV| {worst_mean:.2e}; shadow rays {cpu_ms:.0} ms on the CPU, \
         {gpu_ms:.0} ms on the GPU ({})",
        builtin::names().len(),
        ctx.adapter_description()
    );
}

/// An image larger than one storage binding is traced in pieces: the pieces make the image the
/// whole does.
#[test]
fn the_reference_in_pieces_is_the_whole_reference() {
    let ctx = ctx();
    let scene = scene::load("rect-fig7").unwrap_or_else(|e| panic!("{e}"));
    let (w, h, k) = (40u32, 30u32, 32u32);
    let (whole, _) = gpu_reference::compute(&ctx, &scene, w, h, k, &mut |_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let mut steps = Vec::new();
    let (pieces, cost) =
        gpu_reference::compute_in_pieces(&ctx, &scene, (w, h), k, 257, &mut |done, total| {
            steps.push((done, total))
        })
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(pieces.visibility, whole.visibility);
    assert_eq!(steps.last(), Some(&(k as usize, k as usize)));
    assert!(cost.rays > 0 && cost.triangle_tests > 0, "{cost:?}");
}

/// `compare --reference gpu` goes through the session: a frame of the reference with the GPU's
/// engine shows the same V as with the CPU's, within the same bound.
#[test]
fn the_session_casts_the_reference_with_the_engine_it_is_given() {
    let scene = scene::load("fig8c-complex").unwrap_or_else(|e| panic!("{e}"));
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let request = FrameRequest {
        width: 40,
        height: 32,
        method: truth::SOFT,
        knobs: truth::with_samples(Knobs::default(), 64),
        ..FrameRequest::default()
    };
    let mut frames = Vec::new();
    for engine in [Engine::Cpu, Engine::Gpu] {
        offline.reference = engine;
        let mut session = offline.session(scene.clone());
        assert_eq!(session.truth_engine(), engine);
        let (frame, report) = offline
            .render_in(&mut session, &request)
            .unwrap_or_else(|e| panic!("{engine}: {e}"));
        assert_eq!(report.reference_rays.map(|(k, _)| k), Some(64));
        frames.push(frame.visibility);
    }
    let mean = frames[0]
        .iter()
        .zip(&frames[1])
        .map(|(a, b)| f64::from((a - b).abs()))
        .sum::<f64>()
        / frames[0].len() as f64;
    assert!(mean < 1e-3, "mean |ΔV| {mean}");
}

#[test]
fn an_adapter_without_storage_buffers_is_refused_up_front() {
    let ctx = ctx();
    assert_eq!(
        gpu_reference::refuses_on(&ctx.caps),
        None,
        "lavapipe runs it"
    );
    let limits = wgpu::Limits {
        max_storage_buffers_per_shader_stage: 0,
        ..wgpu::Limits::downlevel_webgl2_defaults()
    };
    let caps = dbuffer::render::adapter::Capabilities::webgpu(
        &ctx.adapter,
        wgpu::Features::empty(),
        limits,
    );
    let why = gpu_reference::refuses_on(&caps).unwrap_or_default();
    assert!(
        why.contains("4 storage buffers per shader stage"),
        "refused as: {why}"
    );
}

#[test]
fn trace_uniforms_match_their_wgsl() {
    use dbuffer::render::passes::trace::TraceUniforms;
    let source =
        dbuffer::shader_source::load("passes/trace.wgsl").unwrap_or_else(|e| panic!("{e}"));
    assert_wgsl_layout!(
        TraceUniforms,
        &source,
        "TraceUniforms",
        count,
        first,
        samples,
        row,
        node_count,
        triangle_count,
        offset,
        _pad1
    );
}
