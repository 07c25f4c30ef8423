//! Ray against triangle: the one intersection routine of the CPU side.

use glam::Vec3;

/// Möller–Trumbore, two-sided. Returns the ray parameter `t` (in units of `dir`) of the hit,
/// or `None` when the ray misses or runs parallel to the triangle.
#[inline]
pub fn intersect_triangle(origin: Vec3, dir: Vec3, tri: &[Vec3; 3]) -> Option<f32> {
    intersect_precomputed(origin, dir, tri[0], tri[1] - tri[0], tri[2] - tri[0])
}

/// [`intersect_triangle`] for a triangle given as its first corner `v0` and the edges
/// `e1 = tri[1] − v0`, `e2 = tri[2] − v0` (what the BVH stores), with bit-identical results.
#[inline(always)]
pub fn intersect_precomputed(origin: Vec3, dir: Vec3, v0: Vec3, e1: Vec3, e2: Vec3) -> Option<f32> {
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
