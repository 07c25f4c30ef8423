//! The ray-cast ground truth: `V(x)`, the fraction of the light visible from a point.
//!
//! `V(x)` is estimated with shadow rays from `x` to `K` stratified sample points on the light
//! (docs/method/metrics.md). On a disk, the samples are the cells of a jittered grid on the unit square,
//! mapped to the disk by Shirley and Chiu's area-preserving concentric map, so every sample
//! stands for the same area `πr²/K`. On a line light ([`line_samples`]), sample `i` is jittered
//! inside the `i`-th of `K` equal pieces of the segment, so it stands for the length `L/K`; the
//! occluded part of the segment seen through one straight edge is one interval, so `V_K` is
//! within `2/K` of the exact fraction. The jitter comes from a fixed-seed hash: the same `K`
//! always gives the same samples and the same `V`, on every run and thread.
//!
//! When `K` is not a perfect square the grid has `m = round(√K)` rows; the first `K mod m` rows
//! hold one cell more than the others, and each row's height is proportional to its cell count,
//! so every cell still has area `1/K` (for a square `K` this is the plain `√K × √K` grid).
//!
//! Conventions:
//! - a disk light is one-sided: a point on or behind its plane (`height_of(x) <= 0`) has
//!   `V = 0`; a line light emits all around its segment ([`Light::reaches`]);
//! - the light itself is not geometry;
//! - occlusion uses [`intersect_triangle_tolerant`](super::ray::intersect_triangle_tolerant):
//!   plain `f32` Möller–Trumbore lets about one shadow ray in 10⁵ slip through the shared edge
//!   of two triangles of a closed mesh, which would light umbra points;
//! - `x` is usually on a receiver surface. A hit counts only for `SELF_EPS <= t <= 1 − SELF_EPS`
//!   along the segment from `x` (t = 0) to the sample (t = 1), so neither the receiver under `x`
//!   nor anything touching the light's plane at the sample shadows it. Occluders closer to `x`
//!   than `SELF_EPS` times the distance to the light are not seen;
//! - a point with a NaN or infinite coordinate has `V = 0`, and so has every point when the
//!   light itself is not finite (NaN or infinite centre, normal or radius); `K = 0` is treated
//!   as `K = 1`;
//! - [`Oracle::rays_cast`] counts `K` shadow rays per point in front of the light, including
//!   those the shadow cache (the last occluder, tried before the BVH) answers.
//!
//! Speed: `benches/oracle.rs` (`cargo bench --bench oracle`) measures rays per second.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::bvh::Bvh;
use crate::scene::{Light, LineLight, Scene};

/// Default number of light samples per point (Jakobsen et al. 2004, Fig. 7b and 8d).
pub const DEFAULT_SAMPLES: usize = 1024;

/// Hits closer than this fraction of the segment to either end are ignored (self-intersection).
pub const SELF_EPS: f32 = 1e-4;

/// Seed of the jitter hash. Changing it changes every reference image.
const JITTER_SEED: u64 = 0x0d1b_5eed_0000_0000;

/// The ray-cast visibility oracle. See the module documentation.
#[derive(Debug)]
pub struct Oracle {
    /// Shared with every oracle relit from this one ([`Oracle::relit`]): it depends on the
    /// triangles alone.
    bvh: Arc<Bvh>,
    light: Light,
    /// Sample points on the light, world space.
    samples: Vec<Vec3>,
    /// Whether the light's coordinates are finite (otherwise `V = 0`).
    light_ok: bool,
    rays: AtomicU64,
}

impl Clone for Oracle {
    fn clone(&self) -> Self {
        Self {
            bvh: Arc::clone(&self.bvh),
            light: self.light,
            samples: self.samples.clone(),
            light_ok: self.light_ok,
            rays: AtomicU64::new(self.rays.load(Ordering::Relaxed)),
        }
    }
}

impl Oracle {
    /// An oracle where every triangle occludes, with `samples` rays per point (0 means 1), for
    /// a disk or a line light.
    pub fn new(triangles: Vec<[Vec3; 3]>, light: impl Into<Light>, samples: usize) -> Oracle {
        let light = light.into();
        Oracle::with_samples(triangles, light, light_samples(&light, samples))
    }

    /// The same occluders under another light with `samples` rays per point (0 means 1): the
    /// BVH is shared, not built again, so moving the light costs only its samples.
    pub fn relit(&self, light: impl Into<Light>, samples: usize) -> Oracle {
        let light = light.into();
        Oracle::on_bvh(Arc::clone(&self.bvh), light, light_samples(&light, samples))
    }

    /// An oracle with the sample points `samples` on `light` given (0 samples: none visible):
    /// `compare --orbit` moves one set of samples with the light, so the reference's pattern
    /// on the light is the same in every frame.
    pub fn with_samples(
        triangles: Vec<[Vec3; 3]>,
        light: impl Into<Light>,
        samples: Vec<Vec3>,
    ) -> Oracle {
        Oracle::on_bvh(Arc::new(Bvh::build(triangles)), light.into(), samples)
    }

    fn on_bvh(bvh: Arc<Bvh>, light: Light, samples: Vec<Vec3>) -> Oracle {
        let light_ok =
            light.is_finite() && samples.iter().all(|s| s.is_finite()) && !samples.is_empty();
        Oracle {
            bvh,
            light,
            samples,
            light_ok,
            rays: AtomicU64::new(0),
        }
    }

    /// The oracle for a scene: every object occludes, casters or not.
    pub fn from_scene(scene: &Scene, samples: usize) -> Oracle {
        Oracle::new(scene.all_triangles(), scene.light, samples)
    }

    /// The light.
    pub fn light(&self) -> &Light {
        &self.light
    }

    /// The BVH of the occluders.
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Whether `self` and `other` cast against one BVH (one was [`Oracle::relit`] from the
    /// other, or both from a third).
    pub fn shares_bvh(&self, other: &Oracle) -> bool {
        Arc::ptr_eq(&self.bvh, &other.bvh)
    }

    /// Number of light samples (rays per point in front of the light).
    pub fn sample_count(&self) -> usize {
        self.samples.len()
    }

    /// The light sample points, world space.
    pub fn sample_points(&self) -> &[Vec3] {
        &self.samples
    }

    /// Shadow rays cast so far by this oracle (all threads).
    pub fn rays_cast(&self) -> u64 {
        self.rays.load(Ordering::Relaxed)
    }

    /// Sets the ray counter back to zero.
    pub fn reset_ray_count(&self) {
        self.rays.store(0, Ordering::Relaxed);
    }

    /// `V(x)` in `[0, 1]`: the fraction of the light's samples visible from `x`.
    pub fn visibility(&self, x: Vec3) -> f32 {
        self.count_visible(x, &self.samples) as f32 / self.samples.len().max(1) as f32
    }

    /// Whether `x` gets shadow rays at all: a finite point in front of a finite light (every
    /// other point has `V = 0`). The GPU's reference asks it to trace the same points.
    pub fn casts_from(&self, x: Vec3) -> bool {
        self.light_ok && x.is_finite() && self.light.reaches(x)
    }

    /// How many of `samples` (points on the light) `x` sees; 0 for a point behind the light, a
    /// non-finite point or a non-finite light. The progressive reference calls it with slices of
    /// the sample set.
    pub fn count_visible(&self, x: Vec3, samples: &[Vec3]) -> u32 {
        if !self.casts_from(x) {
            return 0;
        }
        let (t0, t1) = (SELF_EPS, 1.0 - SELF_EPS);
        let mut visible = 0u32;
        // Shadow cache: neighbouring samples are mostly blocked by the same triangle, so the
        // last occluder is tried before the BVH. Only genuine hits count: V does not change.
        let mut last: Option<u32> = None;
        for &s in samples {
            let d = s - x;
            if last.is_some_and(|i| self.bvh.hits_triangle_tolerant(i, x, d, t0, t1)) {
                continue;
            }
            match self.bvh.find_any_hit_tolerant(x, d, t0, t1) {
                Some(h) => last = Some(h.triangle),
                None => visible += 1,
            }
        }
        self.rays.fetch_add(samples.len() as u64, Ordering::Relaxed);
        visible
    }

    /// [`Oracle::visibility`] for many points, in parallel on all cores; same order as `xs`.
    pub fn visibility_many(&self, xs: &[Vec3]) -> Vec<f32> {
        xs.par_iter().map(|&x| self.visibility(x)).collect()
    }
}

/// `k` samples (0 means 1) on `light`: stratified over a disk, rectangle or polygon, jittered
/// along a segment.
fn light_samples(light: &Light, k: usize) -> Vec<Vec3> {
    let k = k.max(1);
    match light {
        Light::Area(d) => super::outline::area_samples(d, k),
        Light::Line(l) => line_samples(l, k),
    }
}

/// `k` stratified points on the unit disk (see the module documentation), deterministic.
pub fn disk_samples(k: usize) -> Vec<Vec2> {
    square_strata(k)
        .into_iter()
        .map(|(u, v)| concentric(u, v))
        .collect()
}

/// `k` jittered points of the unit square, one per stratum of `round(√k)` rows of about equal
/// columns (see the module documentation), deterministic: mapped onto a light by an
/// area-preserving map they are its stratified samples.
pub fn square_strata(k: usize) -> Vec<(f32, f32)> {
    if k == 0 {
        return Vec::new();
    }
    let rows = ((k as f64).sqrt().round() as usize).clamp(1, k);
    let base = k / rows;
    let extra = k % rows;
    let mut out = Vec::with_capacity(k);
    let mut y0 = 0.0f64;
    for row in 0..rows {
        let cols = base + usize::from(row < extra);
        let h = cols as f64 / k as f64;
        for col in 0..cols {
            let i = out.len() as u64;
            let jx = unit_hash(i, 0);
            let jy = unit_hash(i, 1);
            let u = (col as f64 + jx) / cols as f64;
            let v = y0 + h * jy;
            out.push((u as f32, v as f32));
        }
        y0 += h;
    }
    out
}

/// `k` stratified points on the segment of `light`, deterministic: point `i` at
/// `a + (i + ξ_i)/k · (b − a)` with `ξ_i` the jitter hash (one point per equal piece).
pub fn line_samples(light: &LineLight, k: usize) -> Vec<Vec3> {
    (0..k)
        .map(|i| {
            let s = (i as f64 + unit_hash(i as u64, 0)) / k as f64;
            light.at(s as f32)
        })
        .collect()
}

/// Shirley and Chiu's concentric map from the unit square to the unit disk (area-preserving).
pub fn concentric(u: f32, v: f32) -> Vec2 {
    let a = 2.0 * u - 1.0;
    let b = 2.0 * v - 1.0;
    if a == 0.0 && b == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, std::f32::consts::FRAC_PI_4 * (b / a))
    } else {
        (
            b,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a / b),
        )
    };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// A hash of `(i, lane)` to `[0, 1)` (SplitMix64 finaliser).
fn unit_hash(i: u64, lane: u64) -> f64 {
    let mut z = JITTER_SEED ^ i.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (lane << 62);
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::scene::AreaLight;

    fn light() -> AreaLight {
        AreaLight {
            center: Vec3::new(0.0, 4.0, 0.0),
            normal: Vec3::NEG_Y,
            radius: 0.5,
            intensity: 1.0,
            outline: crate::scene::Outline::Disk,
        }
    }

    #[test]
    fn samples_are_stratified_inside_the_disk_for_any_k() {
        for k in [1usize, 2, 3, 5, 10, 64, 100, 1000, 1024, 1025] {
            let s = disk_samples(k);
            assert_eq!(s.len(), k);
            assert!(s.iter().all(|p| p.length() <= 1.0 + 1e-6));
            // Equal-area cells: the fraction inside radius 1/√2 is about one half.
            if k >= 64 {
                let inner = s.iter().filter(|p| p.length() < 0.5f32.sqrt()).count();
                let f = inner as f32 / k as f32;
                // Only the cells the circle crosses (about √k of them) add error.
                let tol = 2.0 / (k as f32).powf(0.75);
                assert!((f - 0.5).abs() < tol, "k={k}: {f}");
            }
            assert_eq!(s, disk_samples(k), "deterministic");
        }
    }

    #[test]
    fn empty_scene_is_lit_in_front_and_dark_behind() {
        let o = Oracle::new(Vec::new(), light(), 64);
        assert_eq!(o.visibility(Vec3::ZERO), 1.0);
        assert_eq!(o.visibility(Vec3::new(3.0, -2.0, 1.0)), 1.0);
        assert_eq!(
            o.visibility(Vec3::new(0.0, 4.0, 0.0)),
            0.0,
            "on the light plane"
        );
        assert_eq!(
            o.visibility(Vec3::new(0.0, 5.0, 0.0)),
            0.0,
            "behind the light"
        );
        assert_eq!(o.visibility(Vec3::new(f32::NAN, 0.0, 0.0)), 0.0);
        assert_eq!(o.visibility(Vec3::new(f32::INFINITY, 0.0, 0.0)), 0.0);
        assert_eq!(o.rays_cast(), 128);
        o.reset_ray_count();
        assert_eq!(o.rays_cast(), 0);
        let v = o.visibility_many(&[Vec3::ZERO, Vec3::Y * 10.0, Vec3::X]);
        assert_eq!(v, vec![1.0, 0.0, 1.0]);
        assert_eq!(
            Oracle::new(Vec::new(), light(), 0).visibility(Vec3::ZERO),
            1.0
        );
    }

    #[test]
    fn a_relit_oracle_casts_as_a_new_one_on_the_same_bvh() {
        // A square occluder half over the receivers: moving the light moves the shadow.
        let q = [
            Vec3::new(-1.0, 2.0, -1.0),
            Vec3::new(1.0, 2.0, -1.0),
            Vec3::new(1.0, 2.0, 1.0),
            Vec3::new(-1.0, 2.0, 1.0),
        ];
        let tris = vec![[q[0], q[1], q[2]], [q[0], q[2], q[3]]];
        let first = Oracle::new(tris.clone(), light(), 64);
        let moved = AreaLight {
            center: Vec3::new(2.5, 4.0, 0.3),
            radius: 0.8,
            ..light()
        };
        let relit = first.relit(moved, 100);
        let fresh = Oracle::new(tris, moved, 100);
        assert!(relit.shares_bvh(&first) && !fresh.shares_bvh(&first));
        assert_eq!(relit.sample_points(), fresh.sample_points());
        assert_eq!(relit.light(), fresh.light());
        let xs: Vec<Vec3> = (0..40)
            .map(|i| Vec3::new(-3.0 + 0.17 * i as f32, 0.0, 0.05 * i as f32 - 1.0))
            .collect();
        let (a, b) = (relit.visibility_many(&xs), fresh.visibility_many(&xs));
        assert_eq!(a, b);
        assert_ne!(a, first.visibility_many(&xs), "the light moved the shadow");
        assert!(a.contains(&0.0) && a.contains(&1.0));
    }

    #[test]
    fn a_broken_light_gives_zero_not_a_panic() {
        for l in [
            AreaLight {
                radius: f32::NAN,
                ..light()
            },
            AreaLight {
                normal: Vec3::NAN,
                ..light()
            },
            AreaLight {
                center: Vec3::splat(f32::INFINITY),
                ..light()
            },
        ] {
            let o = Oracle::new(vec![[Vec3::ZERO, Vec3::X, Vec3::Z]], l, 16);
            assert_eq!(o.visibility(Vec3::new(0.0, 1.0, 0.0)), 0.0);
        }
        // A zero radius is a point light: valid.
        let point = Oracle::new(
            Vec::new(),
            AreaLight {
                radius: 0.0,
                ..light()
            },
            16,
        );
        assert_eq!(point.visibility(Vec3::ZERO), 1.0);
    }

    #[test]
    fn receiver_does_not_shadow_itself() {
        // A ground quad under the light; points on it (and on a tilted one) are fully lit.
        let g = [
            [
                Vec3::new(-5.0, 0.0, -5.0),
                Vec3::new(5.0, 0.0, -5.0),
                Vec3::new(5.0, 0.0, 5.0),
            ],
            [
                Vec3::new(-5.0, 0.0, -5.0),
                Vec3::new(5.0, 0.0, 5.0),
                Vec3::new(-5.0, 0.0, 5.0),
            ],
        ];
        let o = Oracle::new(g.to_vec(), light(), 256);
        for i in 0..50 {
            let p = Vec3::new(-4.9 + 0.19 * i as f32, 0.0, 0.37 * (i % 7) as f32 - 1.0);
            assert_eq!(o.visibility(p), 1.0, "{p}");
        }
    }

    #[test]
    fn from_scene_every_object_occludes_casters_or_not() {
        use crate::scene::{Camera, Mesh, Object};
        let quad = |y: f32| {
            Mesh::new(
                vec![
                    Vec3::new(-1.0, y, -1.0),
                    Vec3::new(1.0, y, -1.0),
                    Vec3::new(1.0, y, 1.0),
                    Vec3::new(-1.0, y, 1.0),
                ],
                vec![[0, 2, 1], [0, 3, 2]],
            )
        };
        let scene = Scene {
            name: "t".into(),
            camera: Camera {
                eye: Vec3::ONE,
                target: Vec3::ZERO,
                fov_y_deg: 45.0,
            },
            light: light().into(),
            objects: vec![
                Object {
                    name: "ground".into(),
                    mesh: quad(0.0),
                    casts_shadow: false,
                },
                Object {
                    name: "lid".into(),
                    mesh: quad(2.0),
                    casts_shadow: false,
                },
            ],
        };
        let o = Oracle::from_scene(&scene, 64);
        assert_eq!(o.bvh().len(), 4);
        assert_eq!(o.sample_count(), 64);
        assert_eq!(
            o.visibility(Vec3::ZERO),
            0.0,
            "under the lid, on the ground"
        );
        assert_eq!(o.visibility(Vec3::new(0.0, 2.0, 0.0)), 1.0, "on the lid");
    }

    #[test]
    fn points_on_a_convex_caster_do_not_shadow_themselves() {
        // A UV sphere (convex polyhedron): from a point on a facet, the caster lies behind the
        // facet's plane, so V is 1 when the whole disk is in front of that plane and 0 when it
        // is all behind (the face classes of docs/method/dbuffer.md), whatever the rounding of the point.
        let l = AreaLight {
            center: Vec3::new(0.3, 3.0, -0.2),
            normal: Vec3::new(-0.1, -1.0, 0.05).normalize(),
            radius: 0.6,
            intensity: 1.0,
            outline: crate::scene::Outline::Disk,
        };
        let (nu, nv) = (64, 32);
        let p = |i: usize, j: usize| {
            let (u, v) = (
                std::f32::consts::TAU * i as f32 / nu as f32,
                std::f32::consts::PI * j as f32 / nv as f32,
            );
            Vec3::new(u.cos() * v.sin(), v.cos(), u.sin() * v.sin()) * 0.7 + Vec3::Y
        };
        let mut tris = Vec::new();
        for i in 0..nu {
            for j in 0..nv {
                let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            }
        }
        let o = Oracle::new(tris.clone(), l, 256);
        let (mut lit, mut dark) = (0, 0);
        for t in &tris {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            if n.length() < 1e-6 {
                continue; // the poles' zero-area triangles
            }
            let centroid = (t[0] + t[1] + t[2]) / 3.0;
            let n = n.normalize() * n.dot(centroid - Vec3::Y).signum();
            let n_perp = n - n.dot(l.normal) * l.normal;
            let f_c = n.dot(l.center - t[0]);
            let spread = l.radius * n_perp.length();
            let v = o.visibility(centroid);
            if f_c - spread > 1e-3 {
                assert_eq!(v, 1.0, "all-frontfacing facet at {centroid}");
                lit += 1;
            } else if f_c + spread < -1e-3 {
                assert_eq!(v, 0.0, "none-frontfacing facet at {centroid}");
                dark += 1;
            }
        }
        assert!(lit > 500 && dark > 500, "{lit} lit, {dark} dark");
    }

    #[test]
    fn blocker_between_gives_zero() {
        let big = 50.0;
        let tris = vec![
            [
                Vec3::new(-big, 2.0, -big),
                Vec3::new(big, 2.0, -big),
                Vec3::new(big, 2.0, big),
            ],
            [
                Vec3::new(-big, 2.0, -big),
                Vec3::new(big, 2.0, big),
                Vec3::new(-big, 2.0, big),
            ],
        ];
        let o = Oracle::new(tris, light(), DEFAULT_SAMPLES);
        assert_eq!(o.visibility(Vec3::ZERO), 0.0);
        assert_eq!(o.visibility(Vec3::new(0.0, 3.0, 0.0)), 1.0);
    }
}
