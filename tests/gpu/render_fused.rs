//! `dbuffer-fused` on the GPU (lavapipe) against its CPU twin (`geometry::fused::FusedTwin` with
//! the GPU's look-up tables, `MaskEval::Lut`), its overflow rule, and the ray-cast oracle.
//!
//! **GPU against twin.** Per pixel the twin is evaluated at the world position the GPU shaded.
//! Both compute the same things in the same order in `f32` (the twin's exact areas in `f64`), so
//! they agree except where a rounding decides something discrete:
//! - a disk sample on a chord or a sector line, or a chord on the edge of a look-up bin: one
//!   sample of 128, 1/128 of V where the disk is more than one layer deep;
//! - where the disk is one layer deep V is exact on both sides, in `f64` and in `f32`: ~1e-5;
//! - at an outline of the casters seen from the light centre, the light pass's texels decide:
//!   the GPU rasterises the caster crossings and `|cx_o|` per texel (vertices snapped to the
//!   rasteriser's sub-pixel grid), the twin casts exact rays through the texel centres and tests
//!   the point itself against the centre (as for `dbuffer`, `gpu::render_gpu`). Where those
//!   differ, `L(c)` can differ by a layer and V by anything.
//!
//! So: mean |ΔV| < 0.002; at most 1 % of the pixels differ by more than 2/128; at most 0.1 % by
//! more than 0.1, and each of those at an outline seen from `c` (the twin's crossing counts differ
//! among the 3×3 D-buffer texels around the pixel's, or the GPU's texel disagrees with the twin's
//! ray about the crossings or about `|cx_o|`).

use crate::support::wgsl_layout::{self, assert_wgsl_layout};

use dbuffer::geometry::fused::{FusedParams, FusedPath, FusedTwin, MaskEval};
use dbuffer::geometry::metrics;
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::{PreparedCasters, VolumeParams, VtVariant};
use dbuffer::render::frame::FrameTargets;
use dbuffer::render::methods::dbuffer_fused::{LIST_CAP, LIST_SIZE};
use dbuffer::render::passes::fused_layers::FusedUniforms;
use dbuffer::render::session::FrameJob;
use dbuffer::render::{Frame, FrameRequest, GpuContext, Knobs, Method, RenderError, Session};
use dbuffer::scene::{self, Scene};
use dbuffer::shader_source;
use glam::Vec3;

const SIZE: u32 = 160;
const DBUFFER: u32 = 1024;
const LIST: u32 = 256;

fn context() -> GpuContext {
    match GpuContext::headless() {
        Ok(ctx) => ctx,
        Err(e) => {
            panic!("the render tests need a wgpu adapter (./scripts/test.sh installs Mesa's): {e}")
        }
    }
}

fn load(name: &str) -> Scene {
    scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// A frame of `method` in `session`, read back with the method's own light maps.
fn render_in(
    ctx: &GpuContext,
    session: &mut Session,
    method: Method,
    knobs: Knobs,
) -> Result<Frame, RenderError> {
    let request = FrameRequest {
        width: SIZE,
        height: SIZE,
        dbuffer_size: DBUFFER,
        method,
        vt: VtVariant::Exact,
        knobs,
        read_dbuffer: false,
        read_cost: false,
        colour_only: false,
    };
    let mut targets = FrameTargets::new();
    session.submit(
        ctx,
        &mut [FrameJob {
            targets: &mut targets,
            request,
            view: None,
            render: true,
            probes: Vec::new(),
        }],
    )?;
    session.read(ctx, &mut targets, Some(method))
}

fn render(ctx: &GpuContext, scene: &Scene, method: Method, knobs: Knobs) -> Frame {
    let mut session = Session::new(ctx, scene.clone());
    render_in(ctx, &mut session, method, knobs).unwrap_or_else(|e| panic!("{}: {e}", scene.name))
}

fn twin(scene: &Scene, cap: usize) -> FusedTwin {
    let prepared = PreparedCasters::new(scene);
    let geometry = prepared.build(
        &scene.light.area_or_centre(),
        &VolumeParams::for_scene(scene),
    );
    let params = FusedParams {
        size: DBUFFER,
        list_size: LIST,
        cap,
        eval: MaskEval::Lut,
        vt: VtVariant::Exact,
        ..FusedParams::default()
    };
    FusedTwin::new(scene, &prepared, &geometry, params)
}

fn knobs(cap: u32) -> Knobs {
    Knobs::default().with(&LIST_SIZE, LIST).with(&LIST_CAP, cap)
}

/// Pixels that show a receiver facing the light (the pixels every metric uses), with their
/// world positions as the GPU shaded them. Pixels where the GPU's rasteriser and the CPU's camera
/// ray see different surfaces (at a caster's outline seen from the camera, where one may shade a
/// side turned away from the light) are left out: the twin knows no surface normal.
fn receivers(scene: &Scene, frame: &Frame) -> Vec<(usize, Vec3)> {
    let r = dbuffer::geometry::view::receivers(
        scene,
        &dbuffer::geometry::bvh::Bvh::build(scene.all_triangles()),
        SIZE,
        SIZE,
    );
    (0..frame.visibility.len())
        .filter_map(|i| {
            let x = frame.position(i)?;
            let on_it = r[i].is_some_and(|r| {
                r.faces_light && r.position.distance(x) < 1e-3 * (1.0 + x.length())
            });
            (frame.hit(i) && on_it).then_some((i, x))
        })
        .collect()
}

/// The GPU's light maps at the D-buffer texel of `x`: (crossings, farthest crossing height, list
/// count, overflow) and `|cx_o|`.
fn maps_at(frame: &Frame, texel: [u32; 2]) -> ([f32; 4], f32) {
    let maps = frame
        .maps
        .as_ref()
        .expect("the method's light maps were read");
    let t = maps
        .texel(texel[0], texel[1])
        .expect("a texel inside the maps");
    (t[1], t[0][0])
}

/// Whether `x` lies at an outline of the casters seen from the light centre, where the GPU's
/// texels and the twin's rays may decide `L(c)` or the hidden-from-centre test differently.
fn at_outline(twin: &FusedTwin, frame: &Frame, x: Vec3) -> bool {
    let Some(t) = twin.texel_of(x, DBUFFER) else {
        return true;
    };
    let count = twin.crossings_of(t).count;
    let neighbours_differ = (-1i64..=1).any(|dy| {
        (-1i64..=1).any(|dx| {
            let (nx, ny) = (i64::from(t[0]) + dx, i64::from(t[1]) + dy);
            (0..i64::from(DBUFFER)).contains(&nx)
                && (0..i64::from(DBUFFER)).contains(&ny)
                && twin.crossings_of([nx as u32, ny as u32]).count != count
        })
    });
    let (gpu, d_o) = maps_at(frame, t);
    let s = twin.sample(x);
    let o_differs = s
        .dbuffer
        .texel
        .o
        .is_none_or(|o| (o - d_o).abs() > 1e-3 * s.dbuffer.d);
    neighbours_differ || gpu[0] != count as f32 || o_differs
}

#[test]
fn gpu_agrees_with_the_cpu_twin() {
    let ctx = context();
    for name in [
        "fig8c-complex",
        "overlap",
        "fusion-cross",
        "fusion-links",
        "fusion-many",
        "table1-960",
        "fig7-concave",
    ] {
        let scene = load(name);
        let frame = render(&ctx, &scene, Method::DBUFFER_FUSED, knobs(128));
        let twin = twin(&scene, 128);
        let (mut n, mut sum, mut over_step, mut penumbra, mut masked) = (0, 0.0, 0, 0, 0);
        let mut large = Vec::new();
        for (i, x) in receivers(&scene, &frame) {
            let s = twin.sample(x);
            let v = f64::from(frame.visibility[i]);
            let dv = (v - s.v).abs();
            n += 1;
            sum += dv;
            penumbra += usize::from(s.v > 0.01 && s.v < 0.99);
            masked += usize::from(s.path == FusedPath::Mask);
            over_step += usize::from(dv > 2.0 / 128.0);
            if dv > 0.1 {
                large.push((i, x, v, s.v, at_outline(&twin, &frame, x)));
            }
        }
        let mean = sum / n.max(1) as f64;
        let away: Vec<_> = large.iter().filter(|l| !l.4).collect();
        println!(
            "{name:<16} {n} px ({penumbra} penumbra, {masked} through the mask): mean |dV| \
             {mean:.6}, > 2/128: {over_step}, > 0.1: {} ({} away from an outline)",
            large.len(),
            away.len()
        );
        assert!(
            n > 2000 && penumbra > 100 && masked > 500,
            "{name}: the view must show the shadow"
        );
        assert!(mean < 0.002, "{name}: mean |dV| {mean}");
        assert!(
            over_step * 100 <= n,
            "{name}: {over_step} of {n} px differ by more than 2/128"
        );
        assert!(
            large.len() * 1000 <= n,
            "{name}: {} of {n} px differ by more than 0.1",
            large.len()
        );
        assert!(
            away.is_empty(),
            "{name}: GPU and twin disagree away from an outline at (pixel, x, GPU, twin): {:?}",
            &away[..away.len().min(4)]
        );
    }
}

/// A small cap makes lists overflow: the light pass counts every edge all the same (its counts
/// are the twin's), flags exactly the lists over the cap, and their pixels walk every candidate
/// edge instead: the V of a cap that holds every list (up to the order the chords' areas are
/// added in), not the paper's.
#[test]
fn overflowing_lists_walk_every_candidate_edge() {
    let ctx = context();
    let cap = 12;
    let scene = load("fig8c-complex");
    let mut session = Session::new(&ctx, scene.clone());
    let fused = render_in(&ctx, &mut session, Method::DBUFFER_FUSED, knobs(cap))
        .unwrap_or_else(|e| panic!("{e}"));
    let long = render_in(&ctx, &mut session, Method::DBUFFER_FUSED, knobs(400))
        .unwrap_or_else(|e| panic!("{e}"));
    let one_chord = Knobs::default().with(&dbuffer::render::methods::dbuffer::CORNERS, 0);
    let paper =
        render_in(&ctx, &mut session, Method::DBUFFER, one_chord).unwrap_or_else(|e| panic!("{e}"));
    let twin = twin(&scene, cap as usize);
    let (mut n, mut same_count, mut overflowed, mut unlike_paper, mut same_v) = (0, 0, 0, 0, 0);
    for (i, x) in receivers(&scene, &fused) {
        let (Some(t), Some(lt)) = (twin.texel_of(x, DBUFFER), twin.texel_of(x, LIST)) else {
            continue;
        };
        let (gpu, _) = maps_at(&fused, t);
        let (all, _) = maps_at(&long, t);
        let list = twin.texel_list(lt);
        n += 1;
        same_count += usize::from(gpu[2] == list.count as f32);
        if gpu[2] == list.count as f32 {
            assert_eq!(
                gpu[3] == 1.0,
                list.overflow,
                "pixel {i}: a list of {} and cap {cap}",
                list.count
            );
        }
        if gpu[3] == 1.0 {
            overflowed += 1;
            assert_eq!(all[3], 0.0, "pixel {i}: a cap of 400 holds the list");
            // Edges that no list keeps (they change nothing there) may still cut the disk
            // seen from the pixel and change which of the exact paths or the mask gives V: no
            // more than the mask's two steps apart.
            let (v, w) = (fused.visibility[i], long.visibility[i]);
            assert!(
                (v - w).abs() <= 2.0 / 128.0,
                "pixel {i} overflowed: V {v}, with every list held {w}"
            );
            same_v += usize::from((v - w).abs() < 1e-4);
            unlike_paper += usize::from((v - paper.visibility[i]).abs() > 0.01);
        }
    }
    println!(
        "{n} px, {same_count} with the twin's count, {overflowed} overflowed ({same_v} with the \
         V of lists held whole, {unlike_paper} more than 0.01 from the paper's V)"
    );
    assert!(
        same_v * 100 >= overflowed * 95,
        "{same_v} of {overflowed} overflowing px have the V of lists held whole"
    );
    assert!(
        same_count * 100 >= n * 99,
        "{same_count} of {n} counts agree"
    );
    assert!(overflowed > 500, "only {overflowed} px overflowed");
    assert!(
        unlike_paper > 50,
        "only {unlike_paper} overflowing px differ from the paper's V: is the walk taken?"
    );
}

/// Lists over the budget are refused before anything is drawn, naming both flags.
#[test]
fn lists_over_the_budget_are_refused() {
    let ctx = context();
    let mut session = Session::new(&ctx, load("table1-224"));
    let knobs = Knobs::default().with(&LIST_SIZE, 2048).with(&LIST_CAP, 64);
    let Err(e) = render_in(&ctx, &mut session, Method::DBUFFER_FUSED, knobs) else {
        panic!("a 1 GiB list buffer was accepted");
    };
    let msg = e.to_string();
    assert!(
        msg.contains("--list-size 2048")
            && msg.contains("--list-cap 64")
            && msg.contains("MAX_FUSED_LIST_BYTES"),
        "{msg}"
    );
}

/// Against the ray-cast oracle where occluders fuse: the GPU's penumbra error is a fraction of
/// the paper's and small in itself (K = 256: the oracle's own noise is about 0.005).
#[test]
fn fused_shadows_match_the_oracle_where_dbuffer_does_not() {
    let ctx = context();
    for name in ["fig8c-complex", "overlap", "fusion-many"] {
        let scene = load(name);
        let fused = render(&ctx, &scene, Method::DBUFFER_FUSED, Knobs::default());
        let paper = render(&ctx, &scene, Method::DBUFFER, Knobs::default());
        let oracle = Oracle::from_scene(&scene, 256);
        let pixels = receivers(&scene, &fused);
        let mut mask = vec![false; fused.visibility.len()];
        let mut reference = vec![0.0f32; fused.visibility.len()];
        for &(i, x) in &pixels {
            mask[i] = true;
            reference[i] = oracle.visibility(x);
        }
        let f = metrics::compare(&reference, &fused.visibility, &mask);
        let p = metrics::compare(&reference, &paper.visibility, &mask);
        println!(
            "{name:<16} dbuffer-fused: penumbra MAE {:.4} p99 {:.3} class {:.2} % | dbuffer: {:.4} {:.3} {:.2} %",
            f.penumbra_mae, f.p99, f.class_mismatch_pct, p.penumbra_mae, p.p99, p.class_mismatch_pct
        );
        assert!(f.penumbra_pixels > 300, "{name}: {}", f.penumbra_pixels);
        assert!(f.penumbra_mae < 0.012, "{name}: {}", f.penumbra_mae);
        assert!(f.p99 < 0.06, "{name}: p99 {}", f.p99);
        assert!(
            f.penumbra_mae < 0.5 * p.penumbra_mae,
            "{name}: {} against the paper's {}",
            f.penumbra_mae,
            p.penumbra_mae
        );
    }
}

/// A small caster of many edges under a large light (a torus a twelfth of the light's width):
/// every edge of its silhouette seen from the ground is a chord of the disk, so its lists are
/// long, and at a cap of 64 a quarter of its penumbra overflows. Those pixels walk every
/// candidate edge; against the oracle the shadow holds either way. (Before, they got the paper's
/// V, whose p99 on this scene is 0.4.)
#[test]
fn a_small_caster_of_many_edges_under_a_large_light() {
    use glam::{Affine3A, EulerRot, Quat};
    let mut scene = load("fig1-large-light");
    let caster = scene
        .objects
        .iter()
        .position(|o| o.casts_shadow)
        .expect("a caster");
    let torus = scene::shapes::build("torus").unwrap_or_else(|e| panic!("{e}"));
    let place = Affine3A::from_scale_rotation_translation(
        Vec3::splat(0.1),
        Quat::from_euler(EulerRot::XYZ, 0.35, 0.52, 0.17),
        Vec3::new(0.0, 1.5, 0.0),
    );
    scene.objects[caster].mesh = torus.transformed(&place);
    scene.name = "small torus under fig1's light".into();
    let ctx = context();
    let oracle = Oracle::from_scene(&scene, 256);
    for cap in [64, LIST_CAP.default] {
        let fused = render(&ctx, &scene, Method::DBUFFER_FUSED, knobs(cap));
        let pixels = receivers(&scene, &fused);
        let mut mask = vec![false; fused.visibility.len()];
        let mut reference = vec![0.0f32; fused.visibility.len()];
        let twin = twin(&scene, cap as usize);
        let mut overflowed = 0;
        for &(i, x) in &pixels {
            mask[i] = true;
            reference[i] = oracle.visibility(x);
            if let Some(t) = twin.texel_of(x, DBUFFER) {
                overflowed += usize::from(maps_at(&fused, t).0[3] == 1.0);
            }
        }
        let f = metrics::compare(&reference, &fused.visibility, &mask);
        println!(
            "cap {cap}: penumbra MAE {:.4} p99 {:.3} over {} px, {overflowed} px on an overflowing list",
            f.penumbra_mae, f.p99, f.penumbra_pixels
        );
        assert!(f.penumbra_pixels > 1000, "cap {cap}: {}", f.penumbra_pixels);
        if cap == 64 {
            assert!(
                overflowed * 10 > f.penumbra_pixels,
                "cap 64: only {overflowed} px overflowed"
            );
        }
        assert!(f.penumbra_mae < 0.012, "cap {cap}: {}", f.penumbra_mae);
        assert!(f.p99 < 0.06, "cap {cap}: p99 {}", f.p99);
    }
}

#[test]
fn uniforms_match_their_wgsl() {
    for shader in [
        "passes/fused_layers.wgsl",
        "passes/fused_lists.wgsl",
        "methods/dbuffer_fused.wgsl",
    ] {
        let source = shader_source::load(shader).unwrap_or_else(|e| panic!("{shader}: {e}"));
        assert_wgsl_layout!(
            FusedUniforms,
            &source,
            "FusedUniforms",
            view_proj,
            inv_view_proj,
            center,
            radius,
            normal,
            inv_far,
            e1,
            list_size,
            e2,
            half_slope,
            map_size,
            cap,
            samples,
            edge_count,
            h_max,
            caster_albedo,
            all_overflow,
            _pad
        );
        // The edge record and the merged ray are flat arrays of vec4 on the Rust side.
        let (edge, _) = wgsl_layout::struct_layout(&source, "FusedEdge").expect("FusedEdge");
        assert_eq!(
            u64::from(edge),
            dbuffer::render::passes::fused_lists::EDGE_BYTES
        );
        let (ray, _) = wgsl_layout::struct_layout(&source, "TexelRay").expect("TexelRay");
        assert_eq!(
            u64::from(ray),
            dbuffer::render::passes::fused_lists::TEXEL_RAY_BYTES
        );
    }
}

/// Past `WHOLE_WALK_EDGES` candidate edges an overflowing list's pixels get the paper's V (the
/// only pixels that read the paper's volume channels, which are drawn only then): the knot of
/// `fig8c-complex` at eight times its triangles, with a cap small enough to overflow.
#[test]
fn past_the_whole_walk_overflowing_lists_get_the_papers_v() {
    let ctx = context();
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/fig8c-complex.toml"),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let dense = text.replace("torus-knot:240x12", "torus-knot:960x24");
    assert_ne!(dense, text, "the knot's mesh line");
    let dir = std::env::temp_dir().join(format!("dbuffer-dense-knot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let path = dir.join("dense-knot.toml");
    std::fs::write(&path, dense).unwrap_or_else(|e| panic!("{e}"));
    let scene = scene::load(&path.to_string_lossy()).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_dir_all(&dir);
    let candidates = twin(&scene, 12).edges().len();
    assert!(
        candidates > dbuffer::geometry::fused::WHOLE_WALK_EDGES,
        "{candidates} candidate edges"
    );
    let mut session = Session::new(&ctx, scene.clone());
    let fused = render_in(&ctx, &mut session, Method::DBUFFER_FUSED, knobs(12))
        .unwrap_or_else(|e| panic!("{e}"));
    let one_chord = Knobs::default().with(&dbuffer::render::methods::dbuffer::CORNERS, 0);
    let paper =
        render_in(&ctx, &mut session, Method::DBUFFER, one_chord).unwrap_or_else(|e| panic!("{e}"));
    let twin = twin(&scene, 12);
    let (mut overflowed, mut same) = (0, 0);
    for (i, x) in receivers(&scene, &fused) {
        let Some(t) = twin.texel_of(x, DBUFFER) else {
            continue;
        };
        if maps_at(&fused, t).0[3] == 1.0 {
            overflowed += 1;
            same += usize::from((fused.visibility[i] - paper.visibility[i]).abs() <= 1e-5);
        }
    }
    println!("{candidates} candidate edges; {overflowed} px overflowed, {same} with the paper's V");
    assert!(overflowed > 200, "only {overflowed} px overflowed");
    assert_eq!(same, overflowed, "overflowing pixels with the paper's V");
}
