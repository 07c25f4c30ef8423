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
}
