//! Ray against triangle: the one intersection routine of the CPU side.

use glam::{Vec3, Vec3A};

/// Möller–Trumbore, two-sided. Returns the ray parameter `t` (in units of `dir`) of the hit,
/// or `None` when the ray misses or runs parallel to the triangle.
#[inline]
pub fn intersect_triangle(origin: Vec3, dir: Vec3, tri: &[Vec3; 3]) -> Option<f32> {
    let v0 = Vec3A::from(tri[0]);
    intersect_edges(
        origin.into(),
        dir.into(),
        v0,
        Vec3A::from(tri[1]) - v0,
        Vec3A::from(tri[2]) - v0,
    )
}

/// [`intersect_triangle`] for a triangle given as its first corner `v0` and the edges
/// `e1 = tri[1] − v0`, `e2 = tri[2] − v0` (what the BVH stores). It is the same code, so the
/// results are bit-identical; SIMD vectors because this is the oracle's inner loop.
#[inline(always)]
pub fn intersect_edges(origin: Vec3A, dir: Vec3A, v0: Vec3A, e1: Vec3A, e2: Vec3A) -> Option<f32> {
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < f32::MIN_POSITIVE * 16.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv)
}

/// Rounding allowance of [`intersect_edges_tolerant`], in units of the summed magnitudes of
/// each dot product's terms (a few dozen ulps).
const TOLERANCE: f32 = 32.0 * f32::EPSILON;

/// [`intersect_triangle`] with each triangle grown by the rounding error of the test itself.
///
/// Möller–Trumbore in `f32` is not watertight: a ray through (or within rounding of) the edge
/// two triangles share can be rejected by both, and a shadow ray slips through a closed mesh.
/// Here each barycentric condition is relaxed by a bound on its own rounding error
/// (`TOLERANCE` × the sum of the absolute products in its dot products), so such rays hit at
/// least one of the triangles. The growth is a few ulps of the coordinates in size, not a
/// fraction of the triangle: a 100 m quad does not move its edge visibly.
#[inline]
pub fn intersect_triangle_tolerant(origin: Vec3, dir: Vec3, tri: &[Vec3; 3]) -> Option<f32> {
    let v0 = Vec3A::from(tri[0]);
    intersect_edges_tolerant(
        origin.into(),
        dir.into(),
        v0,
        Vec3A::from(tri[1]) - v0,
        Vec3A::from(tri[2]) - v0,
    )
}

/// [`intersect_triangle_tolerant`] on a corner and two edges, like [`intersect_edges`].
#[inline(always)]
pub fn intersect_edges_tolerant(
    origin: Vec3A,
    dir: Vec3A,
    v0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
) -> Option<f32> {
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < f32::MIN_POSITIVE * 16.0 {
        return None;
    }
    // Work with det-scaled barycentrics a = u·det, b = v·det, signs folded in.
    let sign = det.signum();
    let big_d = det.abs();
    let s = origin - v0;
    let a = s.dot(p) * sign;
    let err_a = TOLERANCE * s.abs().dot(p.abs());
    if a < -err_a {
        return None;
    }
    let q = s.cross(e1);
    let b = dir.dot(q) * sign;
    let err_b = TOLERANCE * dir.abs().dot(q.abs());
    let err_d = TOLERANCE * e1.abs().dot(p.abs());
    if b < -err_b || a + b > big_d + err_a + err_b + err_d {
        return None;
    }
    Some(e2.dot(q) / det)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The original scalar version, kept as the reference for the SIMD one.
    fn scalar(origin: Vec3, dir: Vec3, tri: &[Vec3; 3]) -> Option<f32> {
        let e1 = tri[1] - tri[0];
        let e2 = tri[2] - tri[0];
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < f32::MIN_POSITIVE * 16.0 {
            return None;
        }
        let inv = 1.0 / det;
        let s = origin - tri[0];
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = dir.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        Some(e2.dot(q) * inv)
    }

    #[test]
    fn simd_version_is_bit_identical_to_scalar() {
        let mut state = 12345u64;
        let mut f = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32 * 4.0 - 2.0
        };
        let mut hits = 0;
        for _ in 0..200_000 {
            let mut v = || Vec3::new(f(), f(), f());
            let tri = [v(), v(), v()];
            let (o, d) = (v() * 2.0, v());
            let a = intersect_triangle(o, d, &tri);
            assert_eq!(a.map(f32::to_bits), scalar(o, d, &tri).map(f32::to_bits));
            hits += usize::from(a.is_some());
        }
        assert!(hits > 1000);
    }

    #[test]
    fn tolerant_version_agrees_away_from_edges_and_closes_cracks() {
        let mut state = 99u64;
        let mut f = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32 * 4.0 - 2.0
        };
        for _ in 0..100_000 {
            let mut v = || Vec3::new(f(), f(), f());
            let tri = [v(), v(), v()];
            let (o, d) = (v() * 2.0, v());
            let exact = intersect_triangle(o, d, &tri);
            let tol = intersect_triangle_tolerant(o, d, &tri);
            if let Some(t) = exact {
                // Everything the exact test hits, the tolerant one hits, at about the same t.
                let t2 = tol.unwrap();
                assert!((t - t2).abs() <= 1e-5 * t.abs().max(1.0), "{t} vs {t2}");
            }
        }
        // Rays through the shared edge of two triangles hit at least one of them.
        let quad = [
            Vec3::new(-0.3, 1.1, 0.6),
            Vec3::new(-0.33, 1.13, 0.61),
            Vec3::new(-0.31, 1.07, 0.63),
            Vec3::new(-0.35, 1.09, 0.62),
        ];
        let (t1, t2) = ([quad[0], quad[1], quad[2]], [quad[1], quad[3], quad[2]]);
        let o = Vec3::new(0.3, -2.0, 5.0);
        let mut exact_cracks = 0;
        for k in 0..=10_000 {
            let p = quad[1].lerp(quad[2], k as f32 / 10_000.0);
            let d = p - o;
            if intersect_triangle(o, d, &t1).is_none() && intersect_triangle(o, d, &t2).is_none() {
                exact_cracks += 1;
            }
            assert!(
                intersect_triangle_tolerant(o, d, &t1).is_some()
                    || intersect_triangle_tolerant(o, d, &t2).is_some(),
                "crack at {p}"
            );
        }
        eprintln!("the exact test misses {exact_cracks} of 10001 rays through the edge");
    }
}
