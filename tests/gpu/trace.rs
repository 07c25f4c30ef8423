//! The GPU's shadow-ray tracer (`render::passes::trace`) against the CPU's
//! (`geometry::bvh::Bvh`'s tolerant any-hit query, the oracle's), ray by ray, and the reference
//! it traces (`render::gpu_reference`, `compare --reference gpu`) against the CPU reference, on
//! every built-in scene at a small size; and its two paths, hardware ray queries and the BVH
//! traversed in WGSL, against each other on one device.
//!
//! The WGSL traversal runs the CPU's test on the same flattened numbers, so the two disagree
//! only where rounding decides: a ray that grazes an edge, a corner or a segment's end within a
//! few ulps (the GPU's `f32` arithmetic may fuse or reorder what the CPU rounds step by step).
//! The driver's ray queries run its own triangle test (watertight, no rounding allowance), which
//! again decides otherwise only there. A ray is called grazing here when the CPU's own answer
//! changes as the ray is moved by 1e-5 of its length (either end nudged along an axis, or the
//! interval's ends moved); every disagreement must be a grazing ray, and how many there are is
//! printed.
//!
//! The ray-query tests run where the adapter has ray queries (Mesa 25's lavapipe has, 22.3's
//! has not); elsewhere they say so and check nothing more, unless `DBUFFER_REQUIRE_RAY_QUERY=1`
//! (CI's run under Mesa 25, scripts/test.sh), which makes an adapter without them a failure.

use dbuffer::geometry::bvh::Bvh;
use dbuffer::geometry::oracle::{Oracle, SELF_EPS};
use dbuffer::geometry::view;
use dbuffer::render::gpu_reference;
use dbuffer::render::offline::Offline;
use dbuffer::render::passes::trace::{self, Path, Ray, RayCounts, TraceScene};
use dbuffer::render::truth::{self, Engine};
use dbuffer::render::{reference, FrameRequest, GpuContext, Knobs};
use dbuffer::scene::{self, builtin, Scene};
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

/// The CPU's exact answer: Möller–Trumbore without the rounding allowance, which lets a ray
/// through a shared edge slip between its two triangles, as a driver's test may.
fn cpu_blocked_exact(bvh: &Bvh, r: &Ray) -> bool {
    bvh.any_hit(r.origin, r.dir, r.t_min, r.t_max)
}

/// Whether the CPU's answer for `r` changes when the ray moves by 1e-5 of its length: the
/// tolerant test's answer, and with `exact` the exact test's too (a ray that slips through a
/// crack of the exact test, between two triangles sharing an edge, grazes that edge, though the
/// tolerant test, made to close such cracks, blocks it however it is moved).
fn grazing(bvh: &Bvh, r: &Ray, exact: bool) -> bool {
    let answer = cpu_blocked(bvh, r);
    let exact_answer = exact && cpu_blocked_exact(bvh, r);
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
    variants.iter().any(|v| {
        cpu_blocked(bvh, v) != answer || (exact && cpu_blocked_exact(bvh, v) != exact_answer)
    })
}

/// Whether the segment of `r` (`t_min ..= t_max`) passes within `eps` × its direction's length
/// of an edge of one of `triangles`: a ray through an edge or a corner, or along a face, whose
/// answer the last bits of each test decide (the exact test, nudged, may not see it: at a
/// corner every nudge can still catch one of the faces that meet there).
fn near_an_edge(triangles: &[[Vec3; 3]], r: &Ray, eps: f64) -> bool {
    let f = |v: Vec3| v.as_dvec3();
    let (o, d) = (f(r.origin), f(r.dir));
    let (p0, p1) = (o + d * f64::from(r.t_min), o + d * f64::from(r.t_max));
    let limit = eps * d.length();
    triangles
        .iter()
        .any(|t| (0..3).any(|e| segment_distance(p0, p1, f(t[e]), f(t[(e + 1) % 3])) <= limit))
}

/// The least distance between the segments `p0 p1` and `q0 q1` (Ericson, Real-Time Collision
/// Detection, 5.1.9).
fn segment_distance(p0: glam::DVec3, p1: glam::DVec3, q0: glam::DVec3, q1: glam::DVec3) -> f64 {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let (s, t) = if a <= 1e-30 && e <= 1e-30 {
        (0.0, 0.0)
    } else if a <= 1e-30 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= 1e-30 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > 1e-30 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    ((p0 + d1 * s) - (q0 + d2 * t)).length()
}

/// `DBUFFER_REQUIRE_RAY_QUERY=1`: an adapter without ray queries fails the ray-query tests
/// instead of skipping them (CI's run under Mesa 25).
const REQUIRE_RAY_QUERY: &str = "DBUFFER_REQUIRE_RAY_QUERY";

/// Whether `ctx` has ray queries; where it has none, says so, and fails where they are required.
fn has_ray_queries(ctx: &GpuContext, test: &str) -> bool {
    if Path::RayQuery.runs_on(&ctx.caps) {
        assert_eq!(
            Path::best(&ctx.caps),
            Path::RayQuery,
            "ray queries are preferred"
        );
        return true;
    }
    let required = std::env::var(REQUIRE_RAY_QUERY).is_ok_and(|v| v.trim() == "1");
    assert!(
        !required,
        "{REQUIRE_RAY_QUERY}=1 but {} has no hardware ray queries \
         (Features::EXPERIMENTAL_RAY_QUERY): {test} cannot run",
        ctx.adapter_description()
    );
    eprintln!(
        "{test}: {} has no hardware ray queries; only the BVH traversed in WGSL is checked \
         (set {REQUIRE_RAY_QUERY}=1 to make this a failure)",
        ctx.adapter_description()
    );
    assert_eq!(Path::best(&ctx.caps), Path::WgslBvh);
    false
}

/// The rays both tracers answer on `scene`: shadow rays as the reference casts them, rays
/// through triangles' edges and corners, and rays between random points of the scene's bounds.
fn test_rays(scene: &Scene, oracle: &Oracle, rng: &mut Rng) -> Vec<Ray> {
    let bvh = oracle.bvh();
    let points: Vec<Vec3> = view::points(scene, bvh, 24, 24)
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
        let (a, b) = (at(rng), at(rng));
        let (t_min, t_max) = if i % 2 == 0 { (0.0, 1.0) } else { (0.25, 0.75) };
        rays.push(Ray {
            origin: a,
            dir: b - a,
            t_min,
            t_max,
        });
    }
    rays
}

/// `path`'s answers for the test rays of every built-in against the CPU's (and, where given,
/// against `other`'s on the same device): every disagreement grazing, fewer than 1 in 1000.
fn any_hit_agrees(ctx: &GpuContext, path: Path, other: Option<Path>) {
    let mut rng = Rng(45);
    let (mut total, mut blocked, mut differ, mut grazing_rays) = (0usize, 0usize, 0usize, 0usize);
    let mut by_edge = 0usize;
    // Disagreements with the CPU, and with the other path, among the rays built through edges
    // and corners (all of them grazing) and among the others.
    let (mut differ_kind, mut between_kind) = ([0usize; 2], [0usize; 2]);
    for name in builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let oracle = Oracle::from_scene(&scene, 64);
        let bvh = oracle.bvh();
        let rays = test_rays(&scene, &oracle, &mut rng);
        let trace_by = |path: Path| -> Vec<RayCounts> {
            let trace_scene = TraceScene::new(ctx, bvh, path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(trace_scene.path(), path);
            let answers =
                trace::any_hit(ctx, &trace_scene, &rays).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(answers.len(), rays.len());
            answers
        };
        let gpu = trace_by(path);
        let others = other.map(trace_by);
        let mut here = 0;
        for (i, (r, g)) in rays.iter().zip(&gpu).enumerate() {
            let cpu = cpu_blocked(bvh, r);
            // The driver's test is not the CPU's: a ray it answers otherwise may graze by the
            // exact test, or pass through an edge or corner (checked only where it matters).
            let mut graze = grazing(bvh, r, path == Path::RayQuery);
            let differs =
                cpu != (g.count == 1) || others.as_ref().is_some_and(|o| o[i].count != g.count);
            if differs && !graze && path == Path::RayQuery && near_an_edge(bvh.triangles(), r, 1e-5)
            {
                graze = true;
                by_edge += 1;
            }
            blocked += usize::from(cpu);
            grazing_rays += usize::from(graze);
            if cpu != (g.count == 1) {
                here += 1;
                differ_kind[kind(i)] += 1;
                assert!(
                    graze,
                    "{name}: {path} says blocked = {}, the CPU {cpu}, for a ray that does not \
                     graze anything: {r:?}",
                    g.count == 1
                );
            }
            if let (Some(o), Some(other)) = (&others, other) {
                if o[i].count != g.count {
                    between_kind[kind(i)] += 1;
                    assert!(
                        graze,
                        "{name}: {path} says blocked = {}, {other} {}, for a ray that does not \
                         graze anything: {r:?}",
                        g.count == 1,
                        o[i].count == 1
                    );
                }
            }
            match path {
                Path::WgslBvh => {
                    assert!(g.box_tests >= 1, "{name}: every ray tests the root's box")
                }
                Path::RayQuery => assert_eq!(
                    (g.box_tests, g.triangle_tests),
                    (0, 0),
                    "{name}: the ray-query path counts no tests"
                ),
            }
        }
        differ += here;
        total += rays.len();
        if here > 0 {
            eprintln!(
                "{name}: {here} of {} rays differ on {path}, all grazing",
                rays.len()
            );
        }
    }
    eprintln!(
        "{path} against CPU any-hit: {total} rays on {} built-ins, {blocked} blocked on the CPU, \
         {grazing_rays} grazing ({:.2} %); {differ} answered otherwise on the GPU ({:.4} %), \
         every one of them grazing ({})",
        builtin::names().len(),
        100.0 * grazing_rays as f64 / total as f64,
        100.0 * differ as f64 / total as f64,
        ctx.adapter_description()
    );
    // Of 2500 test rays a scene, 1500 .. 2000 are built through an edge or a corner.
    let (edge_rays, other_rays) = (total / 5, total - total / 5);
    eprintln!(
        "{path}: {} of {edge_rays} rays built through edges and corners differ from the CPU, {} \
         of the {other_rays} others; {by_edge} of them grazing only by passing within 1e-5 of \
         an edge",
        differ_kind[0], differ_kind[1]
    );
    if let Some(other) = other {
        eprintln!(
            "{path} against {other}: {} of {edge_rays} rays built through edges and corners \
             answered otherwise, {} of the {other_rays} others, every one of them grazing",
            between_kind[0], between_kind[1]
        );
        assert!(
            (between_kind[1] as f64) < 1e-3 * other_rays as f64,
            "{} of {other_rays} rays not built through an edge differ between the paths",
            between_kind[1]
        );
    }
    assert!(
        blocked > total / 10,
        "the rays test something: {blocked} blocked"
    );
    match path {
        // The CPU's test on the CPU's numbers: only rounding differs, rarely.
        Path::WgslBvh => assert!(
            (differ as f64) < 1e-3 * total as f64,
            "{differ} of {total} rays differ"
        ),
        // The driver's own test, without the CPU's rounding allowance: a ray built through an
        // edge is blocked by the CPU's tolerant test and by the driver's only as its rounding
        // falls (a silhouette edge's rays, or a shared edge's where the test has cracks), so
        // only the other rays are held to a rate.
        Path::RayQuery => assert!(
            (differ_kind[1] as f64) < 1e-3 * other_rays as f64,
            "{} of {other_rays} rays not built through an edge differ",
            differ_kind[1]
        ),
    }
}

/// 0 for the rays [`test_rays`] builds through an edge or a corner (1500 .. 2000 of each
/// scene's 2500), 1 for the others.
fn kind(i: usize) -> usize {
    usize::from(!(1500..2000).contains(&i))
}

#[test]
fn gpu_any_hit_agrees_with_the_cpu_but_for_grazing_rays() {
    any_hit_agrees(&ctx(), Path::WgslBvh, None);
}

/// Both paths trace the same rays on one device: the ray queries agree with the CPU and with
/// the BVH traversed in WGSL but for grazing rays.
#[test]
fn ray_queries_agree_with_the_cpu_and_the_wgsl_bvh_but_for_grazing_rays() {
    let ctx = ctx();
    if has_ray_queries(&ctx, "ray-query any-hit") {
        any_hit_agrees(&ctx, Path::RayQuery, Some(Path::WgslBvh));
    } else {
        any_hit_agrees(&ctx, Path::WgslBvh, None);
    }
}

/// Without ray queries a ray-query scene is refused in words, before anything is made.
#[test]
fn a_ray_query_scene_needs_ray_queries() {
    let ctx = ctx();
    let scene = scene::load("rect-fig7").unwrap_or_else(|e| panic!("{e}"));
    let oracle = Oracle::from_scene(&scene, 4);
    let made = TraceScene::new(&ctx, oracle.bvh(), Path::RayQuery);
    if has_ray_queries(&ctx, "ray-query scene") {
        assert!(made.is_ok_and(|s| s.path() == Path::RayQuery));
    } else {
        let why = made.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(why.contains("ray queries are not available"), "{why}");
    }
    assert_eq!(Path::parse("wgsl"), Some(Path::WgslBvh));
    assert_eq!(Path::parse("RayQuery"), Some(Path::RayQuery));
    assert_eq!(Path::parse("cpu"), None);
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
            cost.path != Path::WgslBvh || cost.rays == 0 || cost.box_tests >= cost.rays,
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
    let (pieces, cost) = gpu_reference::compute_in_pieces(
        &ctx,
        &scene,
        (w, h),
        k,
        Path::best(&ctx.caps),
        257,
        &mut |done, total| steps.push((done, total)),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(pieces.visibility, whole.visibility);
    assert_eq!(steps.last(), Some(&(k as usize, k as usize)));
    assert!(cost.rays > 0, "{cost:?}");
    assert_eq!(
        cost.triangle_tests > 0,
        cost.path == Path::WgslBvh,
        "only the BVH path counts its tests: {cost:?}"
    );
}

/// The GPU reference by both paths on one device, every built-in at 48² and K = 64: the same
/// points, samples and segments, so they differ only where a ray grazes; mean |ΔV| below 0.001
/// on each, and the per-pixel bound of the CPU comparison above.
#[test]
fn the_gpu_reference_is_the_same_by_both_paths() {
    let ctx = ctx();
    if !has_ray_queries(&ctx, "the GPU reference by both paths") {
        return;
    }
    let (w, h, k) = (48u32, 48u32, 64u32);
    let mut ms = [0.0f64; 2];
    let mut rays = 0u64;
    for name in builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let by = |path: Path| {
            let piece = trace::max_points(&ctx);
            gpu_reference::compute_in_pieces(&ctx, &scene, (w, h), k, path, piece, &mut |_, _| {})
                .unwrap_or_else(|e| panic!("{name}, {path}: {e}"))
        };
        let (rq, rq_cost) = by(Path::RayQuery);
        let (bvh, bvh_cost) = by(Path::WgslBvh);
        assert_eq!(
            (rq_cost.path, bvh_cost.path),
            (Path::RayQuery, Path::WgslBvh)
        );
        assert_eq!(rq_cost.rays, bvh_cost.rays, "{name}: the same rays");
        assert_eq!(rq.hit_pixels, bvh.hit_pixels);
        ms[0] += rq.rays_ms;
        ms[1] += bvh.rays_ms;
        rays += rq_cost.rays;
        let (mut sum, mut differ) = (0.0f64, 0usize);
        for (i, (a, b)) in rq.visibility.iter().zip(&bvh.visibility).enumerate() {
            let d = (a - b).abs();
            sum += f64::from(d);
            differ += usize::from(d > 0.0);
            let bound = 4.0 * noise(0.5 * (a + b), k) + 1.0 / k as f32;
            assert!(
                d <= bound,
                "{name}: pixel {i} has V {a} by ray queries and {b} by the WGSL BVH (bound {bound})"
            );
        }
        let mean = sum / rq.visibility.len() as f64;
        eprintln!(
            "{name}: ray queries against the WGSL BVH, {w}x{h}, K = {k}: mean |ΔV| {mean:.2e}, \
             {differ} of {} pixels differ; {:.0} ms against {:.0} ms",
            rq.visibility.len(),
            rq.rays_ms,
            bvh.rays_ms
        );
        assert!(mean < 1e-3, "{name}: mean |ΔV| {mean} between the paths");
    }
    eprintln!(
        "{rays} shadow rays on {} built-ins: ray queries {:.0} ms ({:.2} Mrays/s), WGSL BVH {:.0} \
         ms ({:.2} Mrays/s) ({})",
        builtin::names().len(),
        ms[0],
        rays as f64 / ms[0].max(1e-9) * 1e-3,
        ms[1],
        rays as f64 / ms[1].max(1e-9) * 1e-3,
        ctx.adapter_description()
    );
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
    for shader in ["passes/trace.wgsl", "passes/trace_rq.wgsl"] {
        let source = dbuffer::shader_source::load(shader).unwrap_or_else(|e| panic!("{e}"));
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
}

/// By hand, on a device with ray queries (`scripts/mesa25.sh cargo test --locked --test gpu
/// time_both_paths -- --ignored --nocapture`): the GPU reference of `fig7-concave` (or
/// `DBUFFER_TIME_SCENE`) at 256², K = 256, by each path in turn (the WGSL BVH alone without
/// ray queries), three times, with the time to
/// put the scene on the GPU (the flattened BVH's upload, or the driver's acceleration structure
/// build) apart.
#[test]
#[ignore = "a timing, by hand"]
fn time_both_paths() {
    let ctx = ctx();
    let paths: &[Path] = if has_ray_queries(&ctx, "time_both_paths") {
        &Path::ALL
    } else {
        &[Path::WgslBvh]
    };
    let name = std::env::var("DBUFFER_TIME_SCENE").unwrap_or_else(|_| "fig7-concave".into());
    let scene = scene::load(&name).unwrap_or_else(|e| panic!("{e}"));
    let (w, h, k) = (256u32, 256u32, 256u32);
    let oracle = Oracle::from_scene(&scene, k as usize);
    let mut results: Vec<Vec<f32>> = Vec::new();
    for round in 0..3 {
        for &path in paths {
            let t = std::time::Instant::now();
            let trace_scene =
                TraceScene::new(&ctx, oracle.bvh(), path).unwrap_or_else(|e| panic!("{e}"));
            // Wait for the upload or the build.
            let _ = trace::any_hit(&ctx, &trace_scene, &[]).unwrap_or_else(|e| panic!("{e}"));
            let build_ms = t.elapsed().as_secs_f64() * 1e3;
            let piece = trace::max_points(&ctx);
            let (r, cost) = gpu_reference::compute_in_pieces(
                &ctx,
                &scene,
                (w, h),
                k,
                path,
                piece,
                &mut |_, _| {},
            )
            .unwrap_or_else(|e| panic!("{e}"));
            eprintln!(
                "{name} {w}x{h} K = {k}, round {round}, {path}: {} rays in {:.0} ms, {:.2} Mrays/s \
                 (scene on the GPU: {build_ms:.1} ms, counted in the rays' time)",
                cost.rays,
                r.rays_ms,
                cost.rays as f64 / r.rays_ms.max(1e-9) * 1e-3
            );
            results.push(r.visibility);
        }
    }
    let last = &results[results.len() - 1];
    let mean = results[0]
        .iter()
        .zip(last)
        .map(|(a, b)| f64::from((a - b).abs()))
        .sum::<f64>()
        / results[0].len() as f64;
    eprintln!(
        "{name}: mean |ΔV| between the paths {mean:.2e} ({})",
        ctx.adapter_description()
    );
    assert!(mean < 1e-3);
}
