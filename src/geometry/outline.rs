//! What the methods need of a planar light's shape, for a disk and a convex polygon alike
//! (a rectangle is its four corners):
//! - the range of a plane's function over it ([`plane_range`]: face classes, exact for a
//!   polygon since a linear function takes its extremes at the vertices);
//! - the two planes through a line that touch it ([`tangent_points`]: the extrusion points —
//!   for a polygon the vertices those planes pass through);
//! - its boundary between two such points ([`boundary_between`]: the closing fans — rim points
//!   along the shorter arc of a disk, the polygon's own vertices in between);
//! - uniform, stratified samples of its area ([`area_samples`]: the reference, `sampled`, the
//!   fused mask);
//! - the exact fraction of it beyond a chord ([`Outline2d::fraction_beyond`]: V exact).

use glam::{DVec2, Vec2, Vec3};

use crate::scene::{AreaLight, Polygon};

/// The range `[min f, max f]` over the light of `f(p) = normal·p − offset`, and `f(c)`.
pub fn plane_range(normal: Vec3, offset: f32, light: &AreaLight) -> (f32, f32, f32) {
    let fc = normal.dot(light.center) - offset;
    match light.corners() {
        None => {
            let n_perp = normal - normal.dot(light.normal) * light.normal;
            let reach = light.radius * n_perp.length();
            (fc - reach, fc + reach, fc)
        }
        Some(p) => {
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for v in p.vertices() {
                // Relative to the centre, so a vertex on a plane through c reads exactly f(c).
                let f = fc + normal.dot(*v - light.center);
                lo = lo.min(f);
                hi = hi.max(f);
            }
            (lo, hi, fc)
        }
    }
}

/// Relative tolerance for "the edge is parallel to the light's plane".
const PARALLEL_EPS: f32 = 1e-6;

/// The two points where planes through the line `v1 v2` touch the light with all of it on one
/// side, or `None` when no such plane exists: the line meets the light's plane inside the light
/// (it pierces the light's cone of tangency; only casters that reach the light's plane have
/// such edges). For a disk the two rim points; for a polygon the two vertices the planes pass
/// through (of vertices on one such plane, the first).
pub fn tangent_points(v1: Vec3, v2: Vec3, light: &AreaLight) -> Option<[Vec3; 2]> {
    match light.corners() {
        None => disk_tangent_points(v1, v2, light),
        Some(p) => polygon_tangent_points(v1, v2, light, &p),
    }
}

fn disk_tangent_points(v1: Vec3, v2: Vec3, light: &AreaLight) -> Option<[Vec3; 2]> {
    let (c, n, r) = (light.center, light.normal, light.radius);
    let dir = v2 - v1;
    let len = dir.length();
    if len.is_nan() || len <= 0.0 || r.is_nan() || r <= 0.0 {
        return None;
    }
    let denom = dir.dot(n);
    if denom.abs() <= PARALLEL_EPS * len {
        // Parallel to the disk plane: the tangent planes touch at c ± r·normalize(dir × n_c).
        let side = dir.cross(n).try_normalize()?;
        return Some([c + r * side, c - r * side]);
    }
    // Where the line meets the disk plane.
    let a = v1 + dir * (-(v1 - c).dot(n) / denom);
    let mut ac = a - c;
    ac -= ac.dot(n) * n;
    let d = ac.length();
    if !d.is_finite() || d <= r * (1.0 + 1e-5) {
        return None;
    }
    let u = ac / d;
    let w = n.cross(u);
    let cos = r / d;
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    Some([c + r * (cos * u + sin * w), c + r * (cos * u - sin * w)])
}

/// The planes through the line are a pencil about it: each vertex lies at an angle about the
/// line. The polygon spans an interval of those angles (under π unless the line pierces it);
/// its ends are the touching planes.
fn polygon_tangent_points(v1: Vec3, v2: Vec3, light: &AreaLight, p: &Polygon) -> Option<[Vec3; 2]> {
    let dir = (v2 - v1).try_normalize()?;
    // Angles measured from the direction toward the centre, so the interval does not wrap.
    let toward = light.center - v1;
    let e1 = (toward - dir * toward.dot(dir)).try_normalize()?;
    let e2 = dir.cross(e1);
    let (mut lo, mut hi) = ((f32::INFINITY, 0usize), (f32::NEG_INFINITY, 0usize));
    for (i, v) in p.vertices().iter().enumerate() {
        let q = *v - v1;
        let a = q.dot(e2).atan2(q.dot(e1));
        if !a.is_finite() {
            return None;
        }
        if a < lo.0 {
            lo = (a, i);
        }
        if a > hi.0 {
            hi = (a, i);
        }
    }
    // An interval of π or more: the line passes through the polygon (or its plane holds it).
    if hi.0 - lo.0 >= std::f32::consts::PI * (1.0 - 1e-5) {
        return None;
    }
    let v = p.vertices();
    Some([v[hi.1], v[lo.1]])
}

/// The points of the light's boundary strictly between `p1` and `p2` (two points on it): for a
/// disk, rim points every `step` radians along the shorter arc; for a polygon, its vertices in
/// between going round the way `turn` says (> 0: counter-clockwise in [`AreaLight::basis`],
/// < 0: clockwise, 0: the shorter way by angle about the centre). A polygon needs the turn: its
/// vertices' angles about the centre do not follow the directions they touch (the corners of a
/// long strip are a few degrees from its axis), so the shorter way can be the wrong one.
pub fn boundary_between(light: &AreaLight, p1: Vec3, p2: Vec3, turn: f32, step: f32) -> Vec<Vec3> {
    let (u, w) = light.basis();
    let c = light.center;
    let angle = |p: Vec3| (p - c).dot(w).atan2((p - c).dot(u));
    let a1 = angle(p1);
    let mut delta = angle(p2) - a1;
    if delta > std::f32::consts::PI {
        delta -= std::f32::consts::TAU;
    } else if delta < -std::f32::consts::PI {
        delta += std::f32::consts::TAU;
    }
    match light.corners() {
        None => {
            // An arc within ARC_SLACK of a whole number of steps takes that number: where two
            // supports lie a whole step apart (a regular caster under a disk), the count does
            // not flip with the last bit of an angle (the GPU stage's `atan2` is not libm's).
            let n =
                ((delta.abs() / step.max(1e-3) - ARC_SLACK).ceil() as usize).min(MAX_ARC_POINTS);
            (1..n)
                .map(|k| {
                    let a = a1 + delta * k as f32 / n as f32;
                    c + light.radius * (a.cos() * u + a.sin() * w)
                })
                .collect()
        }
        Some(poly) => {
            if turn > 0.0 && delta < 0.0 {
                delta += std::f32::consts::TAU;
            } else if turn < 0.0 && delta > 0.0 {
                delta -= std::f32::consts::TAU;
            }
            // Vertices whose angle from p1, the way `delta` turns, lies strictly inside it.
            let mut inside: Vec<(f32, Vec3)> = poly
                .vertices()
                .iter()
                .filter_map(|&v| {
                    let mut d = angle(v) - a1;
                    if delta < 0.0 {
                        d = -d;
                    }
                    let d = d.rem_euclid(std::f32::consts::TAU);
                    let eps = 1e-5;
                    (d > eps && d < delta.abs() - eps).then_some((d, v))
                })
                .collect();
            inside.sort_by(|a, b| a.0.total_cmp(&b.0));
            inside.into_iter().map(|(_, v)| v).collect()
        }
    }
}

/// How far past a whole number of steps a disk fan's arc may reach and still take that number
/// of triangles (a share of a step): [`boundary_between`].
pub const ARC_SLACK: f32 = 1e-3;

/// The most rim points a disk fan takes between two extrusion points.
pub const MAX_ARC_POINTS: usize = 64;

/// `n` points around the light's boundary (a disk's rim) or its corners: what overlays draw.
pub fn boundary(light: &AreaLight, n: usize) -> Vec<Vec3> {
    match light.corners() {
        Some(p) => p.vertices().to_vec(),
        None => {
            let (u, w) = light.basis();
            (0..n.max(3))
                .map(|k| {
                    let a = k as f32 / n.max(3) as f32 * std::f32::consts::TAU;
                    light.center + light.radius * (a.cos() * u + a.sin() * w)
                })
                .collect()
        }
    }
}

/// The point of the light at `(s, t)` of the unit square, by an area-preserving map: Shirley and
/// Chiu's concentric map onto the unit disk, then, for a polygon, the unit disk onto the polygon
/// along rays from its centroid — the angle `φ` of the disk point goes to the direction whose fan
/// of the polygon from angle 0 holds the share `φ / 2π` of its area, the radius `ρ` to `ρ` times
/// the polygon's reach that way ([`RadialMap`]). Both steps keep areas, so stratified squares give
/// stratified light samples of uniform density; and a polygon close to the disk (the 16-gon
/// inscribed in it) gets samples close to the disk's.
pub fn area_point(light: &AreaLight, s: f32, t: f32) -> Vec3 {
    RadialMap::of(light).point(light, s, t)
}

/// The disk-to-polygon map of [`area_point`], made once for many samples.
pub struct RadialMap {
    /// The polygon's corners about its centre in the light's basis, counter-clockwise there;
    /// empty for a disk.
    corners: Vec<Vec2>,
    area: f32,
}

impl RadialMap {
    pub fn of(light: &AreaLight) -> RadialMap {
        match Outline2d::of(light) {
            Outline2d::Disk { .. } => RadialMap {
                corners: Vec::new(),
                area: 0.0,
            },
            Outline2d::Polygon { corners, area } => RadialMap { corners, area },
        }
    }

    pub fn point(&self, light: &AreaLight, s: f32, t: f32) -> Vec3 {
        let (e1, e2) = light.basis();
        let p = super::oracle::concentric(s, t);
        if self.corners.len() < 3 || self.area.is_nan() || self.area <= 0.0 {
            return light.center + light.radius * (p.x * e1 + p.y * e2);
        }
        let rho = p.length();
        let phi = p.y.atan2(p.x).rem_euclid(std::f32::consts::TAU);
        let q = self.boundary_at_share(phi / std::f32::consts::TAU);
        light.center + rho * (q.x * e1 + q.y * e2)
    }

    /// The boundary point whose fan from the centre, swept counter-clockwise from angle 0, holds
    /// the share `f` of the area (the fan to a point along an edge grows linearly along it).
    fn boundary_at_share(&self, f: f32) -> Vec2 {
        let v = &self.corners;
        let n = v.len();
        // Where the ray at angle 0 (+x) leaves the polygon: the edge it crosses.
        let mut start = 0;
        let mut b0 = v[0];
        for i in 0..n {
            let (a, b) = (v[i], v[(i + 1) % n]);
            if (a.y <= 0.0) != (b.y <= 0.0) || (a.y == 0.0 && a.x > 0.0) {
                let x = if b.y != a.y {
                    a.x + (b.x - a.x) * (-a.y / (b.y - a.y))
                } else {
                    a.x
                };
                if x > 0.0 {
                    start = i;
                    b0 = Vec2::new(x, 0.0);
                    break;
                }
            }
        }
        let mut left = f.clamp(0.0, 1.0) * self.area;
        let mut from = b0;
        for k in 1..=n + 1 {
            let to = if k == n + 1 { b0 } else { v[(start + k) % n] };
            let tri = 0.5 * from.perp_dot(to);
            if left <= tri || k == n + 1 {
                let share = if tri > 0.0 {
                    (left / tri).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                return from + (to - from) * share;
            }
            left -= tri;
            from = to;
        }
        b0
    }
}

/// `k` stratified points of uniform area density on the light, deterministic: the strata of
/// [`super::oracle::square_strata`] through [`area_point`].
pub fn area_samples(light: &AreaLight, k: usize) -> Vec<Vec3> {
    let map = RadialMap::of(light);
    super::oracle::square_strata(k)
        .into_iter()
        .map(|(s, t)| map.point(light, s, t))
        .collect()
}

/// The light in its own plane: the corners in the basis of [`AreaLight::basis`] about its
/// centre (or, for a disk, its radius). What the exact V of a chord needs, on the CPU as the GPU
/// has it in its uniforms.
#[derive(Clone, Debug, PartialEq)]
pub enum Outline2d {
    Disk { radius: f32 },
    Polygon { corners: Vec<Vec2>, area: f32 },
}

impl Outline2d {
    pub fn of(light: &AreaLight) -> Outline2d {
        match light.corners() {
            None => Outline2d::Disk {
                radius: light.radius,
            },
            Some(p) => {
                let (u, w) = light.basis();
                let corners: Vec<Vec2> = p
                    .vertices()
                    .iter()
                    .map(|v| Vec2::new((*v - light.center).dot(u), (*v - light.center).dot(w)))
                    .collect();
                let mut corners = corners;
                // Counter-clockwise in this basis (it may be left-handed about the normal).
                if shoelace(&corners) < 0.0 {
                    corners.reverse();
                }
                let area = shoelace(&corners);
                Outline2d::Polygon { corners, area }
            }
        }
    }

    /// The extent `[lo, hi]` of `m·p` over the outline, `m` a unit vector of its plane.
    pub fn extent(&self, m: Vec2) -> (f32, f32) {
        match self {
            Outline2d::Disk { radius } => (-radius, *radius),
            Outline2d::Polygon { corners, .. } => {
                corners.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| {
                    (lo.min(m.dot(*p)), hi.max(m.dot(*p)))
                })
            }
        }
    }

    /// The fraction of the light's area where `m·p ≥ h`.
    pub fn area_fraction_above(&self, m: Vec2, h: f32) -> f32 {
        match self {
            Outline2d::Disk { radius } => disk_segment_fraction(if *radius > 0.0 {
                h / radius
            } else {
                h.signum()
            }),
            Outline2d::Polygon { corners, area } => {
                if *area <= 0.0 {
                    return if h <= 0.0 { 1.0 } else { 0.0 };
                }
                (clipped_area(corners, m, h) / area).clamp(0.0, 1.0)
            }
        }
    }

    /// V exact for the D-buffer's `t`: the fraction of the light beyond the chord a share `t` of
    /// the way across it, from its hidden side to its lit side `m` (the chord at
    /// `hi − t (hi − lo)` of the extent along `m`). For a disk, `disk_segment_fraction(1 − 2t)`
    /// whatever `m`.
    pub fn fraction_beyond(&self, m: Vec2, t: f32) -> f32 {
        let t = t.clamp(0.0, 1.0);
        let (lo, hi) = self.extent(m);
        self.area_fraction_above(m, hi - t * (hi - lo))
    }
}

/// The visible fraction of the unit disk beyond a chord at signed distance `h` from its centre.
pub fn disk_segment_fraction(h: f32) -> f32 {
    let h = h.clamp(-1.0, 1.0);
    // A difference of two nearly equal terms near h = 1: held at 0, as the camera pass holds it.
    ((h.acos() - h * (1.0 - h * h).max(0.0).sqrt()) / std::f32::consts::PI).max(0.0)
}

/// The signed area of a polygon (counter-clockwise positive).
pub fn shoelace(p: &[Vec2]) -> f32 {
    0.5 * (0..p.len())
        .map(|i| p[i].perp_dot(p[(i + 1) % p.len()]))
        .sum::<f32>()
}

/// The area of the part of the convex polygon `p` (counter-clockwise) where `m·x ≥ h`: one
/// Sutherland–Hodgman step and the shoelace formula, as `shaders/shared/area_light.wgsl` does it.
pub fn clipped_area(p: &[Vec2], m: Vec2, h: f32) -> f32 {
    let n = p.len();
    let mut sum = 0.0;
    let mut first: Option<Vec2> = None;
    let mut prev: Option<Vec2> = None;
    let mut push = |q: Vec2| {
        if let Some(r) = prev {
            sum += r.perp_dot(q);
        } else {
            first = Some(q);
        }
        prev = Some(q);
    };
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        let (da, db) = (m.dot(a) - h, m.dot(b) - h);
        if da >= 0.0 {
            push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            push(a + (b - a) * (da / (da - db)));
        }
    }
    if let (Some(f), Some(l)) = (first, prev) {
        sum += l.perp_dot(f);
    }
    (0.5 * sum).max(0.0)
}

/// The area of the convex polygon `p` (counter-clockwise) cut down to the half-planes
/// `m·x ≥ h` of `cuts` (Sutherland–Hodgman, one cut at a time), in `f64`.
pub fn convex_cut_area(p: &[DVec2], cuts: &[(DVec2, f64)]) -> f64 {
    let mut poly: Vec<DVec2> = p.to_vec();
    let mut next = Vec::with_capacity(p.len() + cuts.len());
    for &(m, h) in cuts {
        next.clear();
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let (da, db) = (m.dot(a) - h, m.dot(b) - h);
            if da >= 0.0 {
                next.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                next.push(a + (b - a) * (da / (da - db)));
            }
        }
        std::mem::swap(&mut poly, &mut next);
        if poly.len() < 3 {
            return 0.0;
        }
    }
    0.5 * (0..poly.len())
        .map(|i| poly[i].perp_dot(poly[(i + 1) % poly.len()]))
        .sum::<f64>()
        .max(0.0)
}

/// What the segment `a → b` (both in the light's plane, about its centre) covers of the convex
/// polygon `p` (counter-clockwise, of area `area`) in the penumbra-wedge sense: minus the part of
/// the polygon beyond the segment's line inside the angle its ends subtend at the centre, over
/// the polygon's area, for a segment that turns counter-clockwise about the centre (plus it, for
/// one that turns clockwise). The polygon twin of `wedges::edge_coverage_2d`, whose disk has the
/// same rule; `shaders/passes/wedges.wgsl` computes it the same way.
pub fn polygon_edge_coverage(p: &[DVec2], area: f64, a: DVec2, b: DVec2) -> f64 {
    let turn = a.perp_dot(b);
    if turn.is_nan() || turn == 0.0 || area.is_nan() || area <= 0.0 {
        return 0.0;
    }
    let (a, b, sign) = if turn > 0.0 {
        (a, b, -1.0)
    } else {
        (b, a, 1.0)
    };
    // Inside the angle: left of the ray to a, right of the ray to b; beyond the line: right of
    // a → b (the centre is on its left). Each as m·x ≥ 0 (or ≥ m·a).
    let left_of_a = (a.perp(), 0.0);
    let right_of_b = (-b.perp(), 0.0);
    let d = b - a;
    let beyond = (-d.perp(), -d.perp().dot(a));
    sign * convex_cut_area(p, &[left_of_a, right_of_b, beyond]) / area
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> AreaLight {
        AreaLight::rect(
            Vec3::new(0.0, 4.0, 0.0),
            Vec3::NEG_Y,
            [2.0, 1.0],
            Some(Vec3::X),
        )
    }

    #[test]
    fn clipped_area_of_a_square_is_linear_in_the_cut() {
        let o = Outline2d::of(&square());
        for k in 0..=10 {
            let t = k as f32 / 10.0;
            let v = o.fraction_beyond(Vec2::X, t);
            assert!((v - t).abs() < 1e-5, "t {t}: {v}");
            let v = o.fraction_beyond(Vec2::NEG_Y, t);
            assert!((v - t).abs() < 1e-5, "t {t}: {v}");
        }
    }

    #[test]
    fn a_triangle_clipped_near_its_corner_keeps_a_quadratic_share() {
        // Corner at +x: the first 10 % of the width from that corner holds 1 % of the area.
        let light = AreaLight::polygon(&[
            Vec3::new(-1.0, 4.0, 1.0),
            Vec3::new(1.0, 4.0, 0.0),
            Vec3::new(-1.0, 4.0, -1.0),
        ]);
        let o = Outline2d::of(&light);
        let (u, w) = light.basis();
        let m = Vec2::new(Vec3::X.dot(u), Vec3::X.dot(w)).normalize();
        let v = o.fraction_beyond(m, 0.1);
        assert!((v - 0.01).abs() < 1e-4, "{v}");
        let v = o.fraction_beyond(-m, 0.1);
        assert!((v - 0.19).abs() < 1e-4, "{v}");
    }

    #[test]
    fn polygon_samples_are_uniform_over_the_area() {
        // Every quarter of a 2 × 1 rectangle gets a quarter of the samples.
        let light = square();
        let s = area_samples(&light, 1024);
        assert_eq!(s.len(), 1024);
        let mut counts = [0usize; 4];
        for p in &s {
            assert!(p.x.abs() <= 1.0 + 1e-5 && p.z.abs() <= 0.5 + 1e-5, "{p}");
            assert!((p.y - 4.0).abs() < 1e-5);
            counts[usize::from(p.x > 0.0) * 2 + usize::from(p.z > 0.0)] += 1;
        }
        for c in counts {
            assert!((c as i32 - 256).abs() <= 12, "{counts:?}");
        }
    }

    #[test]
    fn the_16_gon_in_a_disk_gets_nearly_the_disk_samples() {
        let disk = AreaLight::disk(Vec3::new(0.0, 4.0, 0.0), Vec3::NEG_Y, 0.5);
        let polygon = disk.inscribed_polygon(16);
        let (a, b) = (area_samples(&disk, 256), area_samples(&polygon, 256));
        for (p, q) in a.iter().zip(&b) {
            // The 16-gon's reach is within cos(π/16) of the radius, so its points within 2 %.
            assert!(p.distance(*q) <= 0.02 * 0.5 + 1e-4, "{p} vs {q}");
            assert!(q.distance(polygon.center) <= 0.5 + 1e-5);
        }
    }

    #[test]
    fn samples_of_a_thin_triangle_are_uniform() {
        // A 20:1 triangle; each of its four quarters by area (cut across the long axis at the
        // quartiles of the area) holds a quarter of the samples.
        let light = AreaLight::polygon(&[
            Vec3::new(-2.0, 4.0, -0.1),
            Vec3::new(2.0, 4.0, 0.0),
            Vec3::new(-2.0, 4.0, 0.1),
        ]);
        let s = area_samples(&light, 4096);
        // Area to the right of x from the tip at x = 2: ((2 − x)/4)² of the whole.
        let quartiles: Vec<f32> = [0.25f32, 0.5, 0.75]
            .iter()
            .map(|q| 2.0 - 4.0 * q.sqrt())
            .collect();
        let mut counts = [0usize; 4];
        for p in &s {
            let k = quartiles.iter().filter(|&&x| p.x < x).count();
            counts[k] += 1;
        }
        for c in counts {
            assert!((c as i32 - 1024).abs() <= 40, "{counts:?}");
        }
    }

    #[test]
    fn plane_range_over_a_polygon_is_its_vertices_range() {
        let light = square();
        let n = Vec3::new(1.0, 1.0, 0.0).normalize();
        let (lo, hi, fc) = plane_range(n, 0.0, &light);
        let f = |p: Vec3| n.dot(p);
        assert!((fc - f(light.center)).abs() < 1e-6);
        assert!((lo - f(Vec3::new(-1.0, 4.0, 0.0))).abs() < 1e-5);
        assert!((hi - f(Vec3::new(1.0, 4.0, 0.0))).abs() < 1e-5);
    }

    #[test]
    fn polygon_tangent_planes_hold_the_polygon_on_one_side() {
        let light = AreaLight::polygon(&[
            Vec3::new(-1.0, 4.0, 1.0),
            Vec3::new(1.0, 4.0, 0.3),
            Vec3::new(0.5, 4.0, -1.0),
            Vec3::new(-0.8, 4.0, -0.6),
        ]);
        let mut state = 7u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        };
        for _ in 0..500 {
            let v1 = Vec3::new(3.0 * next(), 2.0 + next(), 3.0 * next());
            let v2 = v1 + Vec3::new(next(), 0.5 * next(), next());
            let Some(tp) = tangent_points(v1, v2, &light) else {
                continue;
            };
            for t in tp {
                let n = (v2 - v1).cross(t - v1);
                let sides: Vec<f32> = light
                    .corners()
                    .unwrap()
                    .vertices()
                    .iter()
                    .map(|v| n.dot(*v - v1) / n.length())
                    .collect();
                let all_one_side =
                    sides.iter().all(|s| *s >= -1e-4) || sides.iter().all(|s| *s <= 1e-4);
                assert!(all_one_side, "{sides:?}");
            }
        }
    }

    #[test]
    fn polygon_edge_coverage_meets_the_disk_rule_on_a_fine_polygon() {
        // A 4096-gon is the unit disk to 1e-6: the polygon rule must give the disk's coverage.
        let n = 4096;
        let p: Vec<DVec2> = (0..n)
            .map(|k| {
                let a = k as f64 / n as f64 * std::f64::consts::TAU;
                DVec2::new(a.cos(), a.sin())
            })
            .collect();
        let area = p.len() as f64 * 0.5 * (std::f64::consts::TAU / n as f64).sin();
        let mut state = 3u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 3.0 - 1.5
        };
        for _ in 0..200 {
            let (a, b) = (DVec2::new(next(), next()), DVec2::new(next(), next()));
            let disk = crate::geometry::wedges::edge_coverage_2d(a, b);
            let poly = polygon_edge_coverage(&p, area, a, b);
            assert!(
                (disk - poly).abs() < 1e-4,
                "{a} {b}: disk {disk}, polygon {poly}"
            );
        }
    }

    #[test]
    fn boundary_between_walks_the_polygon_the_short_way() {
        let light = square();
        let v = light.corners().unwrap();
        let v = v.vertices();
        assert_eq!(boundary_between(&light, v[0], v[2], 0.0, 0.1).len(), 1);
        assert_eq!(boundary_between(&light, v[0], v[1], 0.0, 0.1).len(), 0);
        let mid = (v[0] + v[1]) * 0.5;
        assert_eq!(boundary_between(&light, mid, v[2], 0.0, 0.1), vec![v[1]]);
    }

    /// The turn picks the way round: from one vertex to its neighbour the long way passes every
    /// other vertex, in order.
    #[test]
    fn boundary_between_goes_the_way_it_is_turned() {
        let light = square();
        let v = light.corners().unwrap();
        let v = v.vertices();
        let angle = |p: Vec3| {
            let (u, w) = light.basis();
            (p - light.center).dot(w).atan2((p - light.center).dot(u))
        };
        // Which way v[0] -> v[1] turns in the light's basis.
        let mut d = angle(v[1]) - angle(v[0]);
        if d > std::f32::consts::PI {
            d -= std::f32::consts::TAU;
        } else if d < -std::f32::consts::PI {
            d += std::f32::consts::TAU;
        }
        let short = d.signum();
        assert!(boundary_between(&light, v[0], v[1], short, 0.1).is_empty());
        assert_eq!(
            boundary_between(&light, v[0], v[1], -short, 0.1),
            vec![v[3], v[2]]
        );
    }
}
