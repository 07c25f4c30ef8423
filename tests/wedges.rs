//! `wedges` (penumbra wedges, Akenine-Möller & Assarsson 2002/2003): the CPU twin against the
//! ray-cast oracle, the wedge hulls holding every point an edge covers, the GPU against the twin,
//! and the errors the papers admit showing where they should.

use dbuffer::geometry::hard_volume::OpenMeshes;
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::wedges::{wedge_hull, wedge_reach, WedgeTwin};
use dbuffer::geometry::PreparedCasters;
use dbuffer::scene::{self, Camera, DiskLight, Object, Scene};
use glam::{Affine3A, Vec3};

fn light(radius: f32) -> DiskLight {
    DiskLight {
        center: Vec3::new(0.0, 4.0, 0.0),
        normal: Vec3::NEG_Y,
        radius,
        intensity: 1.0,
    }
}

/// A box caster of `size` at height 2 over a ground plane, under `light`.
fn box_scene(size: Vec3, light: DiskLight) -> Scene {
    let cube = scene::shapes::build("cube").unwrap();
    let ground = scene::shapes::build("plane").unwrap();
    Scene {
        name: "box".into(),
        camera: Camera {
            eye: Vec3::new(0.0, 4.0, 6.0),
            target: Vec3::ZERO,
            fov_y_deg: 45.0,
        },
        light: light.into(),
        objects: vec![
            Object {
                name: "ground".into(),
                mesh: ground.transformed(&Affine3A::from_scale(Vec3::new(10.0, 1.0, 10.0))),
                casts_shadow: false,
            },
            Object {
                name: "box".into(),
                mesh: cube.transformed(&Affine3A::from_scale_rotation_translation(
                    size,
                    glam::Quat::from_rotation_y(0.4),
                    Vec3::new(0.1, 2.0, -0.05),
                )),
                casts_shadow: true,
            },
        ],
    }
}

/// Ground points over the shadow, V by the twin and by the oracle.
fn twin_against_oracle(scene: &Scene) -> (f64, f64, usize) {
    let disk = *scene.light.as_disk().unwrap();
    let twin = WedgeTwin::new(&PreparedCasters::new(scene), &disk, OpenMeshes::TwoSided);
    let oracle = Oracle::from_scene(scene, 4096);
    let (mut sum, mut worst, mut penumbra) = (0.0f64, 0.0f64, 0usize);
    let n = 40;
    for i in 0..n {
        for j in 0..n {
            let x = Vec3::new(
                -2.0 + 4.0 * (i as f32 + 0.5) / n as f32,
                0.0,
                -2.0 + 4.0 * (j as f32 + 0.5) / n as f32,
            );
            let exact = f64::from(oracle.visibility(x));
            let v = twin.visibility(x);
            sum += (v - exact).abs();
            worst = worst.max((v - exact).abs());
            penumbra += usize::from(exact > 0.01 && exact < 0.99);
        }
    }
    (sum / (n * n) as f64, worst, penumbra)
}

/// A thin square caster: its silhouette from the centre is its silhouette from every point of
/// the light, so the wedges are exact up to the oracle's sampling.
#[test]
fn a_thin_caster_matches_the_oracle() {
    let scene = box_scene(Vec3::new(1.0, 0.01, 1.0), light(0.6));
    let (mean, worst, penumbra) = twin_against_oracle(&scene);
    println!("thin box: mean |ΔV| {mean:.5}, max {worst:.4}, {penumbra} penumbra points");
    assert!(penumbra > 300, "{penumbra}");
    assert!(mean <= 0.005, "mean |ΔV| {mean}");
    assert!(worst <= 0.03, "max |ΔV| {worst}");
}

/// A thick box under a large light: the centre's silhouette is not the one the disk's rim sees
/// (the box's sides hide part of the light from points beside it): the error the papers admit.
#[test]
fn a_thick_caster_shows_the_centre_silhouette_error() {
    let thin = twin_against_oracle(&box_scene(Vec3::new(1.0, 0.01, 1.0), light(0.6)));
    let thick = twin_against_oracle(&box_scene(Vec3::new(1.0, 0.5, 1.0), light(0.6)));
    println!("thick box: mean |ΔV| {:.5}, max {:.4}", thick.0, thick.1);
    assert!(
        thick.1 > 0.025 && thick.1 > 5.0 * thin.1,
        "thick {thick:?} thin {thin:?}"
    );
}

/// Every ground point an edge covers part of the light for lies inside that edge's wedge.
#[test]
fn wedges_hold_every_point_their_edge_covers() {
    let scene = box_scene(Vec3::new(1.0, 0.5, 1.0), light(0.6));
    let disk = *scene.light.as_disk().unwrap();
    let twin = WedgeTwin::new(&PreparedCasters::new(&scene), &disk, OpenMeshes::TwoSided);
    let reach = wedge_reach(&scene);
    let mut checked = 0;
    {
        for &[e0, e1] in &twin.edges {
            let hull = wedge_hull(&disk, e0, e1, reach);
            let inside = |x: Vec3| {
                hull.iter().all(|[a, b, c]| {
                    let n = (*b - *a).cross(*c - *a);
                    n.dot(x - *a) <= 1e-4 * n.length()
                })
            };
            for i in 0..60 {
                for j in 0..60 {
                    let x = Vec3::new(-3.0 + i as f32 / 10.0, 0.0, -3.0 + j as f32 / 10.0);
                    if twin.frame.edge_coverage(x, e0, e1).abs() > 1e-9 {
                        checked += 1;
                        assert!(
                            inside(x),
                            "{x} covered by {e0} → {e1} but outside its wedge"
                        );
                    }
                }
            }
        }
    }
    assert!(checked > 1000, "{checked}");
}

use dbuffer::geometry::bvh::Bvh;
use dbuffer::geometry::metrics;
use dbuffer::geometry::{view, VtVariant};
use dbuffer::render::methods::reference::SAMPLES;
use dbuffer::render::offline::Offline;
use dbuffer::render::{Frame, FrameRequest, Knobs, Method};

const SIZE: u32 = 96;

fn wedges() -> Method {
    "wedges".parse().unwrap()
}

fn render(offline: &mut Offline, scene: &Scene, method: Method, size: u32) -> Frame {
    let request = FrameRequest {
        width: size,
        height: size,
        dbuffer_size: 1024,
        method,
        vt: VtVariant::Exact,
        knobs: Knobs::default().with(&SAMPLES, 256),
        read_dbuffer: false,
    };
    offline
        .render(scene, &request)
        .unwrap_or_else(|e| panic!("{method}: {e}"))
        .0
}

/// The GPU's V is its CPU twin's at the point each pixel shows (pixels facing the light).
#[test]
fn gpu_wedges_match_their_twin() {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    for name in ["fig8a-distance", "overlap", "table1-224", "bunny"] {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        let frame = render(&mut offline, &scene, wedges(), SIZE);
        let disk = *scene.light.as_disk().unwrap();
        let twin = WedgeTwin::new(&PreparedCasters::new(&scene), &disk, OpenMeshes::TwoSided);
        let receivers = view::receivers(&scene, &Bvh::build(scene.all_triangles()), SIZE, SIZE);
        let (mut sum, mut n, mut soft) = (0.0f64, 0usize, 0usize);
        for (i, r) in receivers.iter().enumerate() {
            let Some(r) = r.filter(|r| r.faces_light && frame.hit(i)) else {
                continue;
            };
            let v = twin.surface_visibility(r.position, r.normal);
            sum += (f64::from(frame.visibility[i]) - v).abs();
            n += 1;
            soft += usize::from(v > 0.01 && v < 0.99);
        }
        let mean = sum / n as f64;
        println!("{name}: GPU against the twin, mean |ΔV| {mean:.5} over {n} px ({soft} soft)");
        assert!(soft > 200, "{name}: {soft} penumbra pixels");
        assert!(mean <= 0.005, "{name}: mean |ΔV| {mean}");
    }
}

/// Against the reference on every disk built-in: the bound, penumbra MAE ≤ 0.06 on the
/// convex ones, and the admitted centre-silhouette error where it belongs. On `table1-224`
/// (a 16×8 sphere) the bound holds on the ground but not over every pixel: the sphere's own lit
/// faces just above the centre's terminator see part of the disk hidden by the sphere, which no
/// wedge holds (they are on the light's side of every silhouette edge), so they read 1 where the
/// reference has a penumbra, as `dbuffer-center` does.
#[test]
fn wedges_against_the_reference_on_the_built_ins() {
    let convex = [
        "fig8a-distance",
        "fig8b-light-size",
        "table1-224",
        "table1-960",
        "table1-1440",
        "table1-5760",
    ];
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    println!(
        "| scene | wedges class % | penumbra MAE | on the ground | p99 | dbuffer class % | penumbra MAE |"
    );
    for &name in dbuffer::scene::builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        if scene.light.as_disk().is_none() {
            continue;
        }
        let reference = render(&mut offline, &scene, Method::REFERENCE, SIZE);
        let receivers = view::receivers(&scene, &Bvh::build(scene.all_triangles()), SIZE, SIZE);
        let mask: Vec<bool> = receivers
            .iter()
            .enumerate()
            .map(|(i, r)| reference.hit(i) && r.is_some_and(|r| r.faces_light))
            .collect();
        // The built-ins' grounds are the plane y = 0.
        let ground: Vec<bool> = mask
            .iter()
            .enumerate()
            .map(|(i, &m)| m && reference.position(i).is_some_and(|p| p.y.abs() < 1e-3))
            .collect();
        let w = render(&mut offline, &scene, wedges(), SIZE);
        let d = render(&mut offline, &scene, Method::DBUFFER, SIZE);
        let mw = metrics::compare(&reference.visibility, &w.visibility, &mask);
        let mg = metrics::compare(&reference.visibility, &w.visibility, &ground);
        let md = metrics::compare(&reference.visibility, &d.visibility, &mask);
        println!(
            "| {name} | {:.2} | {:.4} | {:.4} | {:.3} | {:.2} | {:.4} |",
            mw.class_mismatch_pct,
            mw.penumbra_mae,
            mg.penumbra_mae,
            mw.p99,
            md.class_mismatch_pct,
            md.penumbra_mae
        );
        if !convex.contains(&name) {
            continue;
        }
        assert!(mw.penumbra_pixels > 100, "{name}: {mw:?}");
        assert!(mg.penumbra_mae <= 0.06, "{name} on the ground: {mg:?}");
        if name == "table1-224" {
            // The excess is on the sphere itself (see above), not on the ground.
            assert!(mw.penumbra_mae > 0.06 && mg.penumbra_mae < 0.5 * mw.penumbra_mae);
        } else {
            assert!(mw.penumbra_mae <= 0.06, "{name}: {mw:?}");
        }
    }
}

/// Two thin plates at different heights whose edges cover the same side of the disk: each
/// edge's coverage is added, not combined (the papers' admitted overlap error; they suggested
/// blending, not done here). Where both cover the light the twin is too dark; inside both hard
/// shadows (`H` is one bit) each edge uncovers its part again and the sum lights what is umbra.
#[test]
fn overlapping_edges_are_summed_not_combined() {
    let plate = |x0: f32, x1: f32, y: f32| {
        let p = |x: f32, z: f32| Vec3::new(x, y, z);
        dbuffer::scene::Mesh::new(
            vec![
                p(x0, -3.0),
                p(x1, -3.0),
                p(x1, 3.0),
                p(x0, 3.0),
                p(x0, -3.0) + Vec3::Y * 0.01,
                p(x1, -3.0) + Vec3::Y * 0.01,
                p(x1, 3.0) + Vec3::Y * 0.01,
                p(x0, 3.0) + Vec3::Y * 0.01,
            ],
            // A thin closed slab, outward-wound.
            vec![
                [0, 1, 2],
                [0, 2, 3],
                [4, 6, 5],
                [4, 7, 6],
                [0, 4, 5],
                [0, 5, 1],
                [1, 5, 6],
                [1, 6, 2],
                [2, 6, 7],
                [2, 7, 3],
                [3, 7, 4],
                [3, 4, 0],
            ],
        )
    };
    let mut scene = box_scene(Vec3::new(1.0, 0.01, 1.0), light(0.8));
    scene.objects.truncate(1);
    for (i, mesh) in [plate(-4.0, 0.0, 2.0), plate(-4.0, -0.2, 3.0)]
        .into_iter()
        .enumerate()
    {
        scene.objects.push(Object {
            name: format!("plate {i}"),
            mesh,
            casts_shadow: true,
        });
    }
    let disk = *scene.light.as_disk().unwrap();
    let twin = WedgeTwin::new(&PreparedCasters::new(&scene), &disk, OpenMeshes::TwoSided);
    let oracle = Oracle::from_scene(&scene, 4096);
    let (mut darker, mut brighter) = (0.0f64, 0.0f64);
    for i in 0..=60 {
        let x = Vec3::new(-2.0 + 4.0 * i as f32 / 60.0, 0.0, 0.3);
        let (v, exact) = (twin.visibility(x), f64::from(oracle.visibility(x)));
        darker = darker.max(exact - v);
        brighter = brighter.max(v - exact);
    }
    println!("two plates: up to {darker:.3} too dark, {brighter:.3} too bright");
    assert!(darker > 0.05, "summed coverage must darken: {darker}");
    assert!(
        brighter > 0.1,
        "a one-bit H under two umbrae must lighten: {brighter}"
    );
}
