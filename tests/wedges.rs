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
    assert!(thick.1 > 0.025 && thick.1 > 5.0 * thin.1, "thick {thick:?} thin {thin:?}");
}

/// Every ground point an edge covers part of the light for lies inside that edge's wedge.
#[test]
fn wedges_hold_every_point_their_edge_covers() {
    let scene = box_scene(Vec3::new(1.0, 0.5, 1.0), light(0.6));
    let disk = *scene.light.as_disk().unwrap();
    let twin = WedgeTwin::new(&PreparedCasters::new(&scene), &disk, OpenMeshes::TwoSided);
    let reach = wedge_reach(&scene);
    let mut checked = 0;
    for v in &twin.volumes {
        for &[e0, e1] in &v.sides {
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
                        assert!(inside(x), "{x} covered by {e0} → {e1} but outside its wedge");
                    }
                }
            }
        }
    }
    assert!(checked > 1000, "{checked}");
}
