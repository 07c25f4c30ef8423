//! The CPU twin of the D-buffer against ray-cast ground truth, over random convex casters
//! (hulls of random points), random disk lights and random receiver points.
//!
//! What must hold (design.md §2, issue #2):
//! - where the oracle says umbra even for a disk 10 % larger (a margin around the boundary), the
//!   twin says umbra; where it says lit even for the larger disk, the twin says lit;
//! - on the penumbra, V(t) with the exact variant is close to the oracle: mean |ΔV| ≤ 0.1 for every
//!   caster, and at least 80 % of all penumbra points within 0.1. (Not every point: eq. 3 is exact
//!   only for edges parallel to the disk, and random hulls have acute corners, where Assumption 1
//!   of seed 000 fails. The closing note of issue #2 gives the measured spread.)

use std::cell::Cell;

use dbuffer::geometry::hull::convex_hull;
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::{Branch, DBufferTwin, PreparedCasters, VolumeParams, VtVariant};
use dbuffer::scene::{Camera, DiskLight, Mesh, Object, Scene};
use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};

const MARGIN: f32 = 1.1;

fn ground() -> Mesh {
    Mesh::new(
        vec![
            Vec3::new(-20.0, 0.0, -20.0),
            Vec3::new(20.0, 0.0, -20.0),
            Vec3::new(20.0, 0.0, 20.0),
            Vec3::new(-20.0, 0.0, 20.0),
        ],
        vec![[0, 2, 1], [0, 3, 2]],
    )
}

fn scene_with(caster: Mesh, light: DiskLight) -> Scene {
    Scene {
        name: "random".into(),
        camera: Camera {
            eye: Vec3::new(0.0, 3.0, 6.0),
            target: Vec3::ZERO,
            fov_y_deg: 45.0,
        },
        light,
        objects: vec![
            Object {
                name: "hull".into(),
                mesh: caster,
                casts_shadow: true,
            },
            Object {
                name: "ground".into(),
                mesh: ground(),
                casts_shadow: false,
            },
        ],
    }
}

fn v3() -> impl Strategy<Value = Vec3> {
    (-1.0f32..1.0, -0.5f32..0.5, -1.0f32..1.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// A random case: caster centre and size, hull points, light offset, tilt and radius, receivers.
type Case = (
    (f32, f32, f32),
    f32,
    Vec<Vec3>,
    (f32, f32),
    (f32, f32),
    f32,
    Vec<(f32, f32, f32, bool)>,
);

fn cases() -> impl Strategy<Value = Case> {
    (
        (-0.5f32..0.5, 1.0f32..2.5, -0.5f32..0.5),
        0.3f32..1.2,
        prop::collection::vec(v3(), 6..24),
        (-0.5f32..0.5, -0.5f32..0.5),
        (-0.4f32..0.4, -0.4f32..0.4),
        0.1f32..1.2,
        prop::collection::vec((-3.0f32..3.0, 0.0f32..1.0, -3.0f32..3.0, any::<bool>()), 120),
    )
}

/// Checks one case; returns (penumbra points, of which within 0.1).
fn check(case: Case) -> Result<(usize, usize), TestCaseError> {
    let (centre, size, hull_points, light_offset, tilt, radius, receivers) = case;
    let centre = Vec3::new(centre.0, centre.1, centre.2);
    let points: Vec<Vec3> = hull_points.iter().map(|p| centre + size * *p).collect();
    let Some(hull) = convex_hull(&points) else {
        return Ok((0, 0));
    };
    let light = DiskLight {
        center: Vec3::new(light_offset.0, 4.0, light_offset.1),
        normal: Vec3::new(tilt.0, -1.0, tilt.1).normalize(),
        radius,
        intensity: 1.0,
    };
    let bottom = points.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
    let scene = scene_with(hull, light);
    let geometry = PreparedCasters::new(&scene).build(&light, &VolumeParams::for_scene(&scene));
    prop_assert!(geometry.warnings.is_empty(), "{:?}", geometry.warnings);
    let twin = DBufferTwin::new(&scene, &geometry.casters);
    let oracle = Oracle::from_scene(&scene, 1024);
    let wide = Oracle::new(
        scene.all_triangles(),
        DiskLight {
            radius: radius * MARGIN,
            ..light
        },
        1024,
    );

    let (mut sum, mut count, mut within) = (0.0f64, 0usize, 0usize);
    for (x, h, z, on_ground) in receivers {
        // On the ground, or in the air between the ground and the caster's lowest point.
        let y = if on_ground { 0.0 } else { h * bottom.max(0.0) };
        let x = Vec3::new(centre.x + x, y, centre.z + z);
        let sample = twin.sample(x);
        let v_wide = wide.visibility(x);
        if v_wide == 0.0 {
            prop_assert_eq!(sample.branch, Branch::Umbra, "deep umbra at {}: {:?}", x, sample);
        }
        if v_wide == 1.0 {
            prop_assert_eq!(sample.branch, Branch::Lit, "deep lit at {}: {:?}", x, sample);
        }
        let v = f64::from(oracle.visibility(x));
        if v > 0.0 && v < 1.0 {
            let err = (VtVariant::Exact.apply(sample.t) - v).abs();
            sum += err;
            count += 1;
            within += usize::from(err <= 0.1);
        }
    }
    if count > 0 {
        let mae = sum / count as f64;
        prop_assert!(mae <= 0.1, "penumbra MAE {mae:.3} over {count} points");
    }
    Ok((count, within))
}

#[test]
fn twin_agrees_with_the_oracle_on_random_convex_casters() {
    let mut runner = TestRunner::new(Config {
        cases: 48,
        ..Config::default()
    });
    let totals = Cell::new((0usize, 0usize));
    let result = runner.run(&cases(), |case| {
        let (n, ok) = check(case)?;
        let (tn, tok) = totals.get();
        totals.set((tn + n, tok + ok));
        Ok(())
    });
    if let Err(e) = result {
        panic!("{e}");
    }
    let (n, ok) = totals.get();
    assert!(n > 500, "too few penumbra points: {n}");
    let share = ok as f64 / n as f64;
    println!("penumbra points within 0.1 of the oracle: {ok}/{n} = {share:.3}");
    assert!(share >= 0.8, "only {share:.3} of penumbra points within 0.1");
}
