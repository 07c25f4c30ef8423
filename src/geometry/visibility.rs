//! The visibility parameter `t` (corrected eq. 3 of Jakobsen et al. 2004, docs/method/dbuffer.md#the-visibility-parameter-t) and the `V(t)` variants.
//!
//! Along the ray from the light centre `c` through a shaded point `x`: `D = |cx|`; `S = |cx_s|`,
//! the distance to the plane through the silhouette edge parallel to the disk; `U = |cx_uv|` and
//! `P = |cx_pv|`, the distances to the umbra and penumbra volumes. The printed eq. (3) swaps its
//! branch conditions and divides by `U − S` (zero on the line through `c` and the edge); the exact
//! 2D result, proved against a segment light in the tests below, is
//!
//! ```text
//! hidden from c:   t = S (D − U) / (2 U (D − S))       in (0, ½) for D > U ≥ S; D ≤ U is umbra
//! visible from c:  t = 1 − S (D − P) / (2 P (D − S))   in (½, 1) for D > P ≥ S; D ≤ P is lit
//! ```
//!
//! The guards `D ≤ U` and `D ≤ P` are part of the rule: the formulas hold only beyond the volume,
//! and a receiver nearer to the light than the edge (`D < S`) would otherwise flip sign.

use std::fmt;
use std::str::FromStr;

/// Which side of the method a pixel fell on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Branch {
    /// Hidden from the centre and inside the umbra volume: `t = 0`.
    Umbra,
    /// Hidden from the centre, beyond the umbra volume: `0 < t ≤ ½`.
    PenumbraHidden,
    /// Visible from the centre, inside the penumbra volume: `½ ≤ t < 1`.
    PenumbraVisible,
    /// Visible from the centre and outside every penumbra volume: `t = 1`.
    Lit,
}

impl Branch {
    /// Small integer code, the same one the GPU writes.
    pub fn code(self) -> u32 {
        match self {
            Branch::Umbra => 0,
            Branch::PenumbraHidden => 1,
            Branch::PenumbraVisible => 2,
            Branch::Lit => 3,
        }
    }
}

/// `t` for a point hidden from the centre. `u = None`: no umbra exit along the ray (the umbra never
/// ends), so the point is in the umbra.
pub fn t_hidden(d: f64, s: f64, u: Option<f64>) -> (f64, Branch) {
    match u {
        Some(u) if d > u && u > 0.0 => {
            // d > u >= s keeps the denominator positive; s == u gives exactly ½.
            let t = s * (d - u) / (2.0 * u * (d - s));
            (t.clamp(0.0, 0.5), Branch::PenumbraHidden)
        }
        _ => (0.0, Branch::Umbra),
    }
}

/// `t` for a point visible from the centre. `p = None`: no penumbra volume along the ray.
pub fn t_visible(d: f64, s: f64, p: Option<f64>) -> (f64, Branch) {
    match p {
        Some(p) if d > p && p > 0.0 => {
            let t = 1.0 - s * (d - p) / (2.0 * p * (d - s));
            (t.clamp(0.5, 1.0), Branch::PenumbraVisible)
        }
        _ => (1.0, Branch::Lit),
    }
}

/// The `V(t)` functions that turn the parameter into a visible fraction of the disk.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum VtVariant {
    /// `3t² − 2t³`, Jakobsen et al. 2004, eq. (4).
    #[default]
    Smoothstep,
    /// `√t`, Jakobsen et al. 2004, §6.2, for small occluders.
    Sqrt,
    /// The visible fraction of a disk cut by a chord at `1 − 2t` radii from its centre.
    Exact,
    /// `t`.
    Linear,
}

impl VtVariant {
    pub const ALL: [VtVariant; 4] = [
        VtVariant::Smoothstep,
        VtVariant::Sqrt,
        VtVariant::Exact,
        VtVariant::Linear,
    ];

    pub fn name(self) -> &'static str {
        match self {
            VtVariant::Smoothstep => "smoothstep",
            VtVariant::Sqrt => "sqrt",
            VtVariant::Exact => "exact",
            VtVariant::Linear => "linear",
        }
    }

    /// Small integer code, the same one the GPU reads (`VT_*` in `shaders/shared/camera.wgsl`).
    pub fn code(self) -> u32 {
        match self {
            VtVariant::Smoothstep => 0,
            VtVariant::Sqrt => 1,
            VtVariant::Exact => 2,
            VtVariant::Linear => 3,
        }
    }

    /// `V(t)`, with `t` clamped to `[0, 1]`.
    pub fn apply(self, t: f64) -> f64 {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        match self {
            VtVariant::Smoothstep => t * t * (3.0 - 2.0 * t),
            VtVariant::Sqrt => t.sqrt(),
            VtVariant::Exact => disk_segment_fraction(1.0 - 2.0 * t),
            VtVariant::Linear => t,
        }
    }

    /// `V(t)` for a light of `outline`, `side` the chord's lit side (the winning volume
    /// triangle's, [`super::volume_vertices::lit_side`]): [`VtVariant::apply`], except `exact`
    /// under a polygon, which is the polygon's share beyond the chord (the camera pass's
    /// `v_of_t_toward`).
    pub fn apply_toward(self, t: f64, side: [f32; 2], outline: &super::outline::Outline2d) -> f64 {
        let m = glam::Vec2::from(side);
        match outline {
            super::outline::Outline2d::Polygon { .. }
                if self == VtVariant::Exact && m.length_squared() > 1e-12 =>
            {
                let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
                f64::from(outline.fraction_beyond(m.normalize(), t as f32))
            }
            _ => self.apply(t),
        }
    }
}

impl fmt::Display for VtVariant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for VtVariant {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        VtVariant::ALL
            .into_iter()
            .find(|v| v.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown V(t) variant '{s}': expected one of smoothstep, sqrt, exact, linear"
                )
            })
    }
}

/// Area fraction of the unit disk beyond a chord at signed distance `h` (in radii) from the
/// centre: 0 for `h = 1`, ½ for `h = 0`, 1 for `h = −1`.
pub fn disk_segment_fraction(h: f64) -> f64 {
    let h = h.clamp(-1.0, 1.0);
    (h.acos() - h * (1.0 - h * h).max(0.0).sqrt()) / std::f64::consts::PI
}

/// The area of the unit disk within both half-planes `m1·p ≥ h1` and `m2·p ≥ h2` (`m1`, `m2`
/// unit), by Green's theorem over its boundary: the arcs of the circle inside both (half their
/// angle each) and the two chords' parts inside the other half-plane (`½ P × Q` each, walked
/// counter-clockwise). The disk's twin of a polygon's two cuts; `shaders/shared/camera.wgsl`
/// has it as `disk_cut2_area`.
pub fn disk_cut2_area(m1: glam::DVec2, h1: f64, m2: glam::DVec2, h2: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if h1 >= 1.0 || h2 >= 1.0 {
        return 0.0;
    }
    // The arc of the circle in each half-plane: [φ − α, φ + α].
    let arc = |m: glam::DVec2, h: f64| (m.y.atan2(m.x), h.max(-1.0).acos());
    let ((f1, a1), (f2, a2)) = (arc(m1, h1), arc(m2, h2));
    let mut area = 0.0;
    for k in [-1.0, 0.0, 1.0] {
        let (lo, hi) = (
            (f1 - a1).max(f2 - a2 + k * TAU),
            (f1 + a1).min(f2 + a2 + k * TAU),
        );
        area += 0.5 * (hi - lo).max(0.0);
    }
    if a1 >= PI && a2 >= PI {
        return PI;
    }
    // Each chord, walked with its half-plane on the left, clipped by the other half-plane.
    for (m, h, mo, ho) in [(m1, h1, m2, h2), (m2, h2, m1, h1)] {
        if h <= -1.0 {
            continue;
        }
        let d = glam::DVec2::new(m.y, -m.x);
        let half = (1.0 - h * h).max(0.0).sqrt();
        let (mut s0, mut s1) = (-half, half);
        // mo · (h m + s d) ≥ ho.
        let (slope, rest) = (mo.dot(d), ho - h * mo.dot(m));
        if slope.abs() < 1e-15 {
            if rest > 0.0 {
                continue;
            }
        } else if slope > 0.0 {
            s0 = s0.max(rest / slope);
        } else {
            s1 = s1.min(rest / slope);
        }
        if s1 > s0 {
            let (p, q) = (h * m + s0 * d, h * m + s1 * d);
            area += 0.5 * p.perp_dot(q);
        }
    }
    area.clamp(0.0, PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two cuts of the unit disk against the same cuts of a fine inscribed polygon.
    #[test]
    fn disk_cut2_area_is_the_polygon_limit() {
        use glam::DVec2;
        let n = 4096;
        let ring: Vec<DVec2> = (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                DVec2::new(a.cos(), a.sin())
            })
            .collect();
        let mut seed = 7u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..500 {
            let (t1, t2) = (next() * 6.3, next() * 6.3);
            let (h1, h2) = (next() * 2.4 - 1.2, next() * 2.4 - 1.2);
            let (m1, m2) = (
                DVec2::new(t1.cos(), t1.sin()),
                DVec2::new(t2.cos(), t2.sin()),
            );
            let want = super::super::outline::convex_cut_area(&ring, &[(m1, h1), (m2, h2)]);
            let got = disk_cut2_area(m1, h1, m2, h2);
            assert!(
                (got - want).abs() < 2e-3,
                "{m1} {h1} {m2} {h2}: {got} against {want}"
            );
        }
    }

    /// 2D set-up: a segment light from (−r, 0) to (r, 0) centred at c = 0, emitting toward −y; an
    /// occluder that is the half-line from `e` toward −x. Returns the exact visible fraction from
    /// `x` and the eq. (3) parameter computed from distances along the ray from c.
    struct Segment2d {
        r: f64,
        e: [f64; 2],
    }

    fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
        a[0] * b[1] - a[1] * b[0]
    }

    /// Distance along the unit ray `w` from the origin to the line through `p` and `q`, if ahead.
    fn ray_line(w: [f64; 2], p: [f64; 2], q: [f64; 2]) -> Option<f64> {
        let d = [q[0] - p[0], q[1] - p[1]];
        let den = cross(w, d);
        if den.abs() < 1e-300 {
            return None;
        }
        let s = cross(p, d) / den;
        (s > 0.0).then_some(s)
    }

    impl Segment2d {
        fn exact(&self, x: [f64; 2]) -> f64 {
            let [ex, ey] = self.e;
            if x[1] >= ey {
                return 1.0;
            }
            // The light point l is blocked iff the segment x→l crosses height ey left of ex.
            let k = (ey - x[1]) / (-x[1]);
            let px = x[0] + (ex - x[0]) / k;
            ((self.r - px) / (2.0 * self.r)).clamp(0.0, 1.0)
        }

        fn method(&self, x: [f64; 2]) -> (f64, Branch) {
            let [ex, ey] = self.e;
            let d = (x[0] * x[0] + x[1] * x[1]).sqrt();
            let w = [x[0] / d, x[1] / d];
            let s = ey / w[1];
            // Hidden from c: the ray crosses the occluder's height left of the edge, before x.
            let hidden = s < d && w[0] * s < ex;
            // Tangent points: the one whose line has the light and the occluder on the same side
            // is p_u, the other p_p (the same rule as the 3D extrusion).
            let occluder = [ex - 1.0, ey];
            let same_side = |t: [f64; 2]| {
                let dir = [t[0] - ex, t[1] - ey];
                let side_c = cross(dir, [-ex, -ey]);
                let side_o = cross(dir, [occluder[0] - ex, occluder[1] - ey]);
                side_c * side_o > 0.0
            };
            let (pu, pp) = if same_side([self.r, 0.0]) {
                ([self.r, 0.0], [-self.r, 0.0])
            } else {
                ([-self.r, 0.0], [self.r, 0.0])
            };
            if hidden {
                t_hidden(d, s, ray_line(w, self.e, pu))
            } else {
                t_visible(d, s, ray_line(w, self.e, pp))
            }
        }
    }

    #[test]
    fn corrected_eq3_is_exact_for_a_segment_light() {
        let mut worst: f64 = 0.0;
        let mut penumbra_points = 0;
        for (r, e) in [
            (0.5, [0.3, -1.0]),
            (1.0, [-0.2, -0.5]),
            (0.25, [1.5, -2.0]),
            (2.0, [0.0, -1.0]),
        ] {
            let setup = Segment2d { r, e };
            for i in 0..200 {
                for j in 1..60 {
                    let x = [-8.0 + 16.0 * i as f64 / 199.0, e[1] - 0.05 * j as f64 * 4.0];
                    let exact = setup.exact(x);
                    let (t, branch) = setup.method(x);
                    match branch {
                        Branch::Umbra => assert!(exact < 1e-9, "{x:?}: umbra, exact {exact}"),
                        Branch::Lit => assert!(exact > 1.0 - 1e-9, "{x:?}: lit, exact {exact}"),
                        _ => {
                            penumbra_points += 1;
                            worst = worst.max((t - exact).abs());
                        }
                    }
                }
            }
        }
        assert!(
            penumbra_points > 1000,
            "too few penumbra points: {penumbra_points}"
        );
        assert!(worst < 1e-9, "max |t − V_exact| = {worst:e}");
    }

    #[test]
    fn printed_eq3_is_wrong() {
        // The printed branches divide by U − S: on the ray through the edge itself S = U, and the
        // printed hidden branch is undefined there, while the corrected one gives exactly ½.
        let (t, _) = t_hidden(3.0, 2.0, Some(2.0));
        assert!((t - 0.5).abs() < 1e-12);
    }

    #[test]
    fn variants_hit_their_end_points() {
        for v in VtVariant::ALL {
            assert!(v.apply(0.0).abs() < 1e-12, "{v}");
            assert!((v.apply(1.0) - 1.0).abs() < 1e-12, "{v}");
            assert!(v.apply(-1.0).abs() < 1e-12 && (v.apply(2.0) - 1.0).abs() < 1e-12);
            assert_eq!(v.name().parse::<VtVariant>(), Ok(v));
        }
        assert!((VtVariant::Exact.apply(0.5) - 0.5).abs() < 1e-12);
        assert!((VtVariant::Smoothstep.apply(0.5) - 0.5).abs() < 1e-12);
        assert!("cubic"
            .parse::<VtVariant>()
            .unwrap_err()
            .contains("smoothstep"));
    }

    #[test]
    fn exact_variant_is_the_disk_segment_area() {
        // Numerically integrate the disk area beyond a chord and compare.
        for t in [0.05, 0.2, 0.37, 0.5, 0.81, 0.99] {
            let h = 1.0 - 2.0 * t;
            let n = 200_000;
            let area: f64 = (0..n)
                .map(|i| {
                    let x = h + (1.0 - h) * (i as f64 + 0.5) / n as f64;
                    2.0 * (1.0 - x * x).sqrt() * (1.0 - h) / n as f64
                })
                .sum();
            let fraction = area / std::f64::consts::PI;
            assert!(
                (VtVariant::Exact.apply(t) - fraction).abs() < 1e-6,
                "t = {t}"
            );
        }
    }
}
