//! The exact area of one edge's region of the disk, for V where the disk is one layer deep
//! (see the module docs of [`super`]: "Exact where one layer deep").

use glam::Vec2;

/// The area, as a fraction of the unit disk's, of the part of the disk beyond the segment `p q`
/// as seen from the centre: the disk within the angle `p 0 q`, less the triangle `0 p q`.
pub fn region_area(p: Vec2, q: Vec2) -> f64 {
    let (p, q) = (p.as_dvec2(), q.as_dvec2());
    let cross = p.perp_dot(q);
    if !cross.is_finite() || cross == 0.0 {
        return 0.0;
    }
    let sector = cross.atan2(p.dot(q)) / 2.0;
    ((sector - disk_triangle_area(p, q)) / std::f64::consts::PI).abs()
}

/// Whether the region of the segment `p q` (unit-disk coordinates) is a whole circular segment:
/// both ends outside the disk and the segment across it, so the region is all of the disk beyond
/// the chord. In `f32`, as `region_area` of `shaders/methods/dbuffer_fused.wgsl` decides its
/// common case, so the CPU twin and the GPU take the same path.
pub fn whole_segment(p: Vec2, q: Vec2) -> bool {
    let c = p.perp_dot(q);
    let d = q - p;
    let a = d.dot(d);
    let h2 = c * c / a;
    let t0 = -p.dot(d) / a;
    let half = ((1.0 - h2).max(0.0) / a).sqrt();
    p.dot(p) > 1.0 && q.dot(q) > 1.0 && h2 < 1.0 && t0 - half > 0.0 && t0 + half < 1.0
}

/// Signed area of the unit disk ∩ the triangle (0, p, q).
fn disk_triangle_area(p: glam::DVec2, q: glam::DVec2) -> f64 {
    let sector = |a: glam::DVec2, b: glam::DVec2| a.perp_dot(b).atan2(a.dot(b)) / 2.0;
    let triangle = |a: glam::DVec2, b: glam::DVec2| a.perp_dot(b) / 2.0;
    let (pin, qin) = (p.length_squared() <= 1.0, q.length_squared() <= 1.0);
    if pin && qin {
        return triangle(p, q);
    }
    // |p + t d|² = 1.
    let d = q - p;
    let (a, b, c) = (d.length_squared(), 2.0 * p.dot(d), p.length_squared() - 1.0);
    let disc = b * b - 4.0 * a * c;
    if a == 0.0 || disc <= 0.0 {
        return sector(p, q);
    }
    let root = disc.sqrt();
    let (t1, t2) = ((-b - root) / (2.0 * a), (-b + root) / (2.0 * a));
    let (s1, s2) = (p + d * t1.clamp(0.0, 1.0), p + d * t2.clamp(0.0, 1.0));
    match (pin, qin) {
        (true, false) => triangle(p, s2) + sector(s2, q),
        (false, true) => sector(p, s1) + triangle(s1, q),
        _ if t1 >= 1.0 || t2 <= 0.0 => sector(p, q),
        _ => sector(p, s1) + triangle(s1, s2) + sector(s2, q),
    }
}
