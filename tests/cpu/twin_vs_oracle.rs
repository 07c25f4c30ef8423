//! The CPU twin of the D-buffer against ray-cast ground truth, over random convex casters
//! (hulls of random points), random disk lights and random receiver points.
//!
//! What must hold (docs/method/dbuffer.md, issue #2):
//! - where the whole of a disk 10 % larger is hidden (a margin around the boundary), the twin says
//!   umbra; where none of the larger disk is hidden, the twin says lit. For a convex caster above
//!   `x` this is decided exactly: the hidden part of the light plane is the convex hull of the
//!   caster's vertices projected from `x` (sampling the disk misses the thin slivers that a thin
//!   caster blocks near the rim);
//! - on the penumbra, V(t) with the exact variant is close to the oracle: mean |ΔV| ≤ 0.1 for every
//!   caster whose umbra reaches the ground (and with 20 or more penumbra points), and at least 80 % of their penumbra points within 0.1.
//!   Not every point: eq. 3 is exact only for edges parallel to the disk, and random hulls have
//!   acute corners, where Assumption 1 of Jakobsen et al. 2004 fails. Casters whose umbra closes before the
//!   ground (a light much larger than the caster) are the paper's "no umbra" case, where V comes
//!   out too low by construction (Jakobsen et al. 2004, §4): their classes are checked, their V is only
//!   measured and printed.

use std::cell::Cell;

use dbuffer::geometry::hull::convex_hull;
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::{Branch, DBufferTwin, PreparedCasters, VolumeParams, VtVariant};
use dbuffer::scene::{Camera, DiskLight, Mesh, Object, Scene};
use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRng, TestRunner};

const MARGIN: f32 = 1.1;

/// Exact classification with the margin, for a convex caster entirely between `x` and the light
/// plane: `Some(true)` when a disk of radius `MARGIN·r` is wholly hidden, `Some(false)` when none
/// of it is, `None` in between (or when a vertex is not between `x` and the light plane).
fn deep_class(x: Vec3, vertices: &[Vec3], light: &DiskLight) -> Option<bool> {
    let (u, w) = light.basis();
    let n = light.normal;
    let mut pts: Vec<(f64, f64)> = Vec::with_capacity(vertices.len());
    for &v in vertices {
        let den = (v - x).dot(n);
        let num = (light.center - x).dot(n);
        if !(den < 0.0 && num < den) {
            return None;
        }
        let p = x + (v - x) * (num / den) - light.center;
        pts.push((f64::from(p.dot(u)), f64::from(p.dot(w))));
    }
    // Convex hull (monotone chain), counter-clockwise.
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64)> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    if hull.len() < 3 {
        return Some(false);
    }
    // Signed distance from the disk centre (the origin) to the polygon: positive outside.
    let (mut inside, mut nearest) = (true, f64::INFINITY);
    for i in 0..hull.len() {
        let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
        inside &= cross(a, b, (0.0, 0.0)) > 0.0;
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let t = (-(a.0 * dx + a.1 * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        let (px, py) = (a.0 + t * dx, a.1 + t * dy);
        nearest = nearest.min((px * px + py * py).sqrt());
    }
    let r = f64::from(light.radius * MARGIN);
    if inside && nearest >= r {
        Some(true)
    } else if !inside && nearest >= r {
        Some(false)
    } else {
        None
    }
}

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
        light: light.into(),
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
        prop::collection::vec(
            (-3.0f32..3.0, 0.0f32..1.0, -3.0f32..3.0, any::<bool>()),
            120,
        ),
    )
}

/// Penumbra points, those within 0.1, and the sum of |ΔV|, for one group of cases.
#[derive(Clone, Copy, Default)]
struct Tally {
    points: usize,
    within: usize,
    sum: f64,
    deep_umbra: usize,
    deep_lit: usize,
}

impl Tally {
    fn add(self, o: Tally) -> Tally {
        Tally {
            points: self.points + o.points,
            within: self.within + o.within,
            sum: self.sum + o.sum,
            deep_umbra: self.deep_umbra + o.deep_umbra,
            deep_lit: self.deep_lit + o.deep_lit,
        }
    }
}

/// Checks one case; returns its penumbra tally and whether its umbra reaches the ground.
fn check(case: Case) -> Result<(Tally, bool), TestCaseError> {
    let (centre, size, hull_points, light_offset, tilt, radius, receivers) = case;
    let centre = Vec3::new(centre.0, centre.1, centre.2);
    let points: Vec<Vec3> = hull_points.iter().map(|p| centre + size * *p).collect();
    let Some(hull) = convex_hull(&points) else {
        return Ok((Tally::default(), true));
    };
    let centroid = points.iter().copied().sum::<Vec3>() / points.len() as f32;
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

    // Does the umbra reach the ground? Look where the ray from c through the caster lands.
    let down = (centroid - light.center).normalize();
    let below = light.center + down * (light.center.y / -down.y);
    let umbra_reaches_ground = oracle.visibility(below) == 0.0;

    let (mut sum, mut count, mut within) = (0.0f64, 0usize, 0usize);
    let (mut deep_umbra, mut deep_lit) = (0usize, 0usize);
    for (x, h, z, on_ground) in receivers {
        // On the ground, or in the air between the ground and the caster's lowest point.
        let y = if on_ground { 0.0 } else { h * bottom.max(0.0) };
        let x = Vec3::new(centre.x + x, y, centre.z + z);
        let sample = twin.sample(x);
        match deep_class(x, &points, &light) {
            Some(true) => {
                deep_umbra += 1;
                prop_assert_eq!(
                    sample.branch,
                    Branch::Umbra,
                    "deep umbra at {}: {:?}",
                    x,
                    sample
                )
            }
            Some(false) => {
                deep_lit += 1;
                prop_assert_eq!(
                    sample.branch,
                    Branch::Lit,
                    "deep lit at {}: {:?}",
                    x,
                    sample
                )
            }
            None => {}
        }
        let v = f64::from(oracle.visibility(x));
        if v > 0.0 && v < 1.0 {
            let err = (VtVariant::Exact.apply(sample.t) - v).abs();
            sum += err;
            count += 1;
            within += usize::from(err <= 0.1);
        }
    }
    // A per-caster mean needs points to be a mean; the share below covers every case.
    if count >= 20 && umbra_reaches_ground {
        let mae = sum / count as f64;
        prop_assert!(mae <= 0.1, "penumbra MAE {mae:.3} over {count} points");
    }
    let tally = Tally {
        points: count,
        within,
        sum,
        deep_umbra,
        deep_lit,
    };
    Ok((tally, umbra_reaches_ground))
}

#[test]
fn twin_agrees_with_the_oracle_on_random_convex_casters() {
    // Deterministic in CI (the same 48 cases every run); `PROPTEST_CASES=2000` explores more.
    let cases_wanted = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(48);
    let config = Config {
        cases: cases_wanted,
        failure_persistence: None,
        ..Config::default()
    };
    let rng = TestRng::deterministic_rng(config.rng_algorithm);
    let mut runner = TestRunner::new_with_rng(config, rng);
    // [cases whose umbra reaches the ground, "no umbra" cases]
    let totals = Cell::new([Tally::default(); 2]);
    let result = runner.run(&cases(), |case| {
        let (tally, umbra) = check(case)?;
        let mut t = totals.get();
        let k = usize::from(!umbra);
        t[k] = t[k].add(tally);
        totals.set(t);
        Ok(())
    });
    if let Err(e) = result {
        panic!("{e:?}");
    }
    let [with_umbra, no_umbra] = totals.get();
    for (name, t) in [
        ("umbra reaches the ground", with_umbra),
        ("no umbra", no_umbra),
    ] {
        println!(
            "{name}: {} deep-umbra and {} deep-lit points checked; {} penumbra points, {:.3} within 0.1, MAE {:.3}",
            t.deep_umbra,
            t.deep_lit,
            t.points,
            t.within as f64 / t.points.max(1) as f64,
            t.sum / t.points.max(1) as f64
        );
    }
    assert!(
        with_umbra.points > 500,
        "too few penumbra points: {}",
        with_umbra.points
    );
    let all = with_umbra.add(no_umbra);
    assert!(
        all.deep_umbra > 100 && all.deep_lit > 1000,
        "too few points checked: {} umbra, {} lit",
        all.deep_umbra,
        all.deep_lit
    );
    let share = with_umbra.within as f64 / with_umbra.points as f64;
    assert!(
        share >= 0.8,
        "only {share:.3} of penumbra points within 0.1"
    );
}
