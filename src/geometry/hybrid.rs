//! Shadow volumes reconstructed from a depth map (McCool 2000, "Shadow volume reconstruction from
//! depth maps"): the CPU twin of the `hybrid` method's compute pass
//! (`shaders/passes/hybrid.wgsl`), the specification it is tested against.
//!
//! The shadowed region of a distance map from the light point `p` is every point farther from
//! `p` than the map in its texel's direction. Its boundary is the map's surface and the *walls*
//! between neighbouring texels of different distance: in the plane through `p` and the texel
//! border, from the near texel's distance to the far one's. A camera ray never crosses a real
//! surface before the point it shows, so in front of that point it can only cross walls: the
//! parity of the walls it crosses (and whether the ray starts in shadow) is the point's shadow
//! state — one stencil bit. Walls between texels of almost equal distance lie on a continuous
//! surface and are dropped (the edge detection), so the threshold moves the shadow map's acne to
//! where the surface is steep.
//!
//! Reconstruction, per cell of 2×2 texel centres (a marching-squares template, McCool's
//! "template-based reconstruction"): each of the cell's four edges joins a texel pair; a pair is
//! discontinuous when exactly one of them saw nothing, or when `|d_a − d_b| > τ·min(d_a, d_b)` —
//! and, with the slope test on (the default), neither side's plane predicts the other: the
//! reciprocal of the light-view depth `w` (the clip w of the texel's surface point), which is
//! affine over the image for a plane, extrapolated from `a` and its neighbour beyond it misses
//! `w_b` by more than `τ·min(w)`, and from `b`'s side misses `w_a` (a second difference: a plane
//! seen at a grazing angle changes fast from texel to texel but makes no wall; a curved surface
//! at a grazing angle still can). With two
//! discontinuous edges the wall follows one straight segment between their midpoints (a straight
//! border, or a 45° cut across a corner); with one, three or four, a star of segments from each
//! discontinuous edge's midpoint to the cell's centre (the staircase along texel borders). Each
//! segment end carries its edge's near and far distances; neighbouring cells share every segment
//! end, so the network of walls has no cracks.

use glam::{Mat4, Vec2, Vec3};

/// A distance at or above this is "no surface" (the shadow map's clear value is 3e38).
pub const NO_SURFACE_AT: f32 = 1.5e38;

/// One segment of the reconstructed silhouette, in the map's image (texel units: texel `(i, j)`
/// spans `[i, i + 1] × [j, j + 1]`, its centre at `(i + ½, j + ½)`), with the distances from the
/// light of the wall's top (on the near texel's plane) and bottom (the far texel's distance, or
/// `far` where nothing was seen) at each end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallSegment {
    pub a: Vec2,
    pub b: Vec2,
    pub near: [f32; 2],
    pub far: [f32; 2],
}

/// The reconstruction's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallParams {
    /// τ, the relative distance jump that makes a texel pair discontinuous.
    pub threshold: f32,
    /// Templates (straight segments for two discontinuous edges) or the star everywhere.
    pub templates: bool,
    /// The distance of a wall's bottom where the far texel saw nothing.
    pub far: f32,
    /// A jump that either side's slope predicts is no edge (the second-difference test).
    pub slope_test: bool,
}

/// Whether a plane through `out` and `x` (light-view depths `w`) predicts `y` within `limit`:
/// `1/w` is affine over the image for a plane. `out` must be a surface.
pub fn plane_predicts(out: f32, x: f32, y: f32, limit: f32) -> bool {
    let g = 2.0 / x - 1.0 / out;
    out.is_finite() && out > 0.0 && g > 0.0 && (y - 1.0 / g).abs() <= limit
}

/// Where a wall's top belongs on the ray through its segment end `mid`: the near texel's own
/// plane (`1/w` extrapolated from the texel beyond it, `near_w_out`, and itself, `near_w`) half
/// a texel toward the far side, within `[near, far]`. Near a silhouette the occluder's surface
/// recedes fast from texel to texel; a top at the near texel's own distance would stand in front
/// of that surface and cut its lit side.
fn wall_top(
    near_w_out: f32,
    near_w: f32,
    mid: Vec2,
    (near, far): (f32, f32),
    depth: &dyn Fn(Vec2, f32) -> f32,
) -> f32 {
    let g = 1.5 / near_w - 0.5 / near_w_out;
    let (k0, k1) = (depth(mid, 0.0), depth(mid, 1.0) - depth(mid, 0.0));
    if !(near_w_out > 0.0 && g > 0.0 && k1 > 0.0) {
        return near;
    }
    let d = (1.0 / g - k0) / k1;
    if d.is_nan() {
        near
    } else {
        d.clamp(near, far)
    }
}

/// An edge of a cell between texels `a` and `b`, given as the line of four texels `a_out, a,
/// b, b_out` (the outer two beyond `a` and `b`), each `(distance, light-view depth)`, NaN outside
/// the map: its midpoint, the distance of the wall's top ([`wall_top`]) and of its bottom (the
/// far texel's), or `None` when continuous.
fn edge(
    line: [(f32, f32); 4],
    mid: Vec2,
    params: &WallParams,
    depth: &dyn Fn(Vec2, f32) -> f32,
) -> Option<(Vec2, f32, f32)> {
    let [(_, wa_out), (da, wa), (db, wb), (_, wb_out)] = line;
    let (na, nb) = (da >= NO_SURFACE_AT, db >= NO_SURFACE_AT);
    let top = |a_near: bool, near: f32, far: f32| {
        let (out, w) = if a_near { (wa_out, wa) } else { (wb_out, wb) };
        wall_top(out, w, mid, (near, far), depth)
    };
    match (na, nb) {
        (true, true) => None,
        (true, false) => Some((mid, top(false, db, params.far), params.far)),
        (false, true) => Some((mid, top(true, da, params.far), params.far)),
        (false, false) => {
            let (lo, hi) = (da.min(db), da.max(db));
            if hi - lo <= params.threshold * lo {
                return None;
            }
            let limit = params.threshold * wa.min(wb);
            if params.slope_test
                && (plane_predicts(wa_out, wa, wb, limit) || plane_predicts(wb_out, wb, wa, limit))
            {
                return None;
            }
            Some((mid, top(da <= db, lo, hi), hi))
        }
    }
}

/// Every wall segment of the `size`×`size` distance map `d` (row-major, row 0 at the top), cell
/// by cell in row-major order. `depth(q, d)` is the light-view depth (clip w) of the point at
/// distance `d` through image point `q` ([`WallSpace::depth`]).
pub fn wall_segments(
    d: &[f32],
    size: u32,
    params: &WallParams,
    depth: impl Fn(Vec2, f32) -> f32,
) -> Vec<WallSegment> {
    let n = size as usize;
    let mut out = Vec::new();
    if n < 2 || d.len() < n * n {
        return out;
    }
    // NaN outside the map and where nothing was seen: no prediction from there.
    let at = |x: i64, y: i64| {
        if x < 0 || y < 0 || x >= n as i64 || y >= n as i64 {
            return (f32::NAN, f32::NAN);
        }
        let v = d[y as usize * n + x as usize];
        let w = if v < NO_SURFACE_AT {
            depth(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), v)
        } else {
            f32::NAN
        };
        (v, w)
    };
    for j in 0..n as i64 - 1 {
        for i in 0..n as i64 - 1 {
            let (fi, fj) = (i as f32, j as f32);
            let row = |y: i64| [at(i - 1, y), at(i, y), at(i + 1, y), at(i + 2, y)];
            let column = |x: i64| [at(x, j - 1), at(x, j), at(x, j + 1), at(x, j + 2)];
            let edges = [
                edge(row(j), Vec2::new(fi + 1.0, fj + 0.5), params, &depth),
                edge(column(i + 1), Vec2::new(fi + 1.5, fj + 1.0), params, &depth),
                edge(row(j + 1), Vec2::new(fi + 1.0, fj + 1.5), params, &depth),
                edge(column(i), Vec2::new(fi + 0.5, fj + 1.0), params, &depth),
            ];
            let flagged: Vec<(Vec2, f32, f32)> = edges.iter().flatten().copied().collect();
            if flagged.len() == 2 && params.templates {
                let (a, b) = (flagged[0], flagged[1]);
                out.push(WallSegment {
                    a: a.0,
                    b: b.0,
                    near: [a.1, b.1],
                    far: [a.2, b.2],
                });
            } else {
                let centre = Vec2::new(fi + 1.0, fj + 1.0);
                for (m, near, far) in flagged {
                    out.push(WallSegment {
                        a: m,
                        b: centre,
                        near: [near, near],
                        far: [far, far],
                    });
                }
            }
        }
    }
    out
}

/// How wall segments become world quads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallSpace {
    /// The light point.
    pub light: Vec3,
    /// The light view's clip → world transform (the inverse of its view-projection).
    pub inv_view_proj: Mat4,
    /// The map's side in texels.
    pub size: u32,
    /// The top sits this share of its distance beyond the near texel (the hard test's bias: the
    /// occluder's own lit surface beside its silhouette is not cut by its wall).
    pub top_bias: f32,
    /// The bottom reaches this share of its distance beyond the far texel (under the receiver:
    /// no gap where the receiver is tilted between texel centres).
    pub bottom_margin: f32,
}

impl WallSpace {
    /// The light-view depth (clip w) of the point at distance `d` from the light through image
    /// point `q`: affine in `1/w` over the image for a plane (the slope test's predictor).
    pub fn depth(&self, q: Vec2, d: f32) -> f32 {
        let p = self.light + self.direction(q) * d;
        (self.inv_view_proj.inverse() * p.extend(1.0)).w
    }

    /// The unit direction from the light through image point `q` (texel units).
    pub fn direction(&self, q: Vec2) -> Vec3 {
        let s = self.size.max(1) as f32;
        let ndc = glam::Vec4::new(2.0 * q.x / s - 1.0, 1.0 - 2.0 * q.y / s, 0.5, 1.0);
        let w = self.inv_view_proj * ndc;
        (w.truncate() / w.w - self.light).normalize_or_zero()
    }

    /// The wall of `s` as two triangles: top a, top b, bottom b; top a, bottom b, bottom a.
    pub fn quad(&self, s: &WallSegment) -> [Vec3; 6] {
        let (da, db) = (self.direction(s.a), self.direction(s.b));
        let p = self.light;
        let top_a = p + da * s.near[0] * (1.0 + self.top_bias);
        let top_b = p + db * s.near[1] * (1.0 + self.top_bias);
        let bottom_a = p + da * s.far[0] * (1.0 + self.bottom_margin);
        let bottom_b = p + db * s.far[1] * (1.0 + self.bottom_margin);
        [top_a, top_b, bottom_b, top_a, bottom_b, bottom_a]
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

    const FAR: f32 = 100.0;

    fn params(templates: bool) -> WallParams {
        WallParams {
            threshold: 0.02,
            templates,
            far: FAR,
            slope_test: true,
        }
    }

    /// A light-view depth equal to the distance (an orthographic-like test image).
    fn flat(_: Vec2, d: f32) -> f32 {
        d
    }

    fn image(n: u32, f: impl Fn(f32, f32) -> f32) -> Vec<f32> {
        (0..n * n)
            .map(|i| f((i % n) as f32 + 0.5, (i / n) as f32 + 0.5))
            .collect()
    }

    /// Segment ends and how many segments meet at each (image points are multiples of ½).
    fn degrees(s: &[WallSegment]) -> HashMap<(i32, i32), usize> {
        let key = |p: Vec2| ((p.x * 2.0).round() as i32, (p.y * 2.0).round() as i32);
        let mut m = HashMap::new();
        for seg in s {
            *m.entry(key(seg.a)).or_insert(0) += 1;
            *m.entry(key(seg.b)).or_insert(0) += 1;
        }
        m
    }

    #[test]
    fn a_disk_on_a_far_plane_gives_one_closed_loop() {
        let n = 32;
        let d = image(n, |x, y| {
            if (Vec2::new(x, y) - Vec2::splat(16.0)).length() < 7.0 {
                2.0
            } else {
                4.0
            }
        });
        for templates in [true, false] {
            let s = wall_segments(&d, n, &params(templates), flat);
            assert!(!s.is_empty());
            // A closed curve: every segment end is shared by exactly two segments.
            for (p, k) in degrees(&s) {
                assert_eq!(k, 2, "{templates}: end {p:?} has degree {k}");
            }
            for g in &s {
                assert_eq!(g.near, [2.0, 2.0]);
                assert_eq!(g.far, [4.0, 4.0]);
            }
        }
        // The star follows texel borders (two segments per cell the boundary crosses), the
        // templates cut across (one).
        let t = wall_segments(&d, n, &params(true), flat).len();
        let star = wall_segments(&d, n, &params(false), flat).len();
        assert_eq!(star, 2 * t);
    }

    #[test]
    fn a_step_gives_one_straight_polyline_across_the_map() {
        let n = 16;
        let d = image(n, |x, _| if x < 6.0 { 1.0 } else { 3.0 });
        let s = wall_segments(&d, n, &params(true), flat);
        // One segment per cell row, along x = 6 (the border between texels 5 and 6).
        assert_eq!(s.len(), (n - 1) as usize);
        for g in &s {
            assert_eq!((g.a.x, g.b.x), (6.0, 6.0));
            assert_eq!((g.near, g.far), ([1.0, 1.0], [3.0, 3.0]));
        }
        let ends = degrees(&s);
        let open: Vec<_> = ends.iter().filter(|(_, k)| **k == 1).collect();
        assert_eq!(open.len(), 2, "ends on the map's border");
        // Nothing seen on one side: the bottom goes to `far`.
        let sky = image(n, |x, _| if x < 6.0 { 1.0 } else { 3e38 });
        assert!(wall_segments(&sky, n, &params(true), flat)
            .iter()
            .all(|g| g.near == [1.0, 1.0] && g.far == [FAR, FAR]));
    }

    #[test]
    fn a_ramp_below_the_threshold_has_no_walls_and_the_star_has_more_pieces() {
        let n = 16;
        // 1 % per texel: continuous for τ = 2 %.
        let ramp = image(n, |x, _| 2.0 * 1.01f32.powf(x));
        assert!(wall_segments(&ramp, n, &params(true), flat).is_empty());
        // A plane at a grazing angle: 1/w affine, over 5 % per texel: walls without the slope
        // test, none with it; a real step on it is found either way.
        let steep = image(n, |x, _| 1.0 / (0.5 - 0.02 * x));
        let plain = WallParams {
            slope_test: false,
            ..params(true)
        };
        assert_eq!(
            wall_segments(&steep, n, &plain, flat).len(),
            ((n - 1) * (n - 1)) as usize
        );
        assert!(wall_segments(&steep, n, &params(true), flat).is_empty());
        let stepped = image(n, |x, _| {
            1.0 / (0.5 - 0.02 * x) + if x > 8.0 { 2.0 } else { 0.0 }
        });
        let found = wall_segments(&stepped, n, &params(true), flat);
        assert_eq!(found.len(), (n - 1) as usize);
        assert!(found.iter().all(|g| g.a.x == 8.0 && g.b.x == 8.0));
        let d = image(n, |x, y| if x + y < 12.0 { 1.0 } else { 3.0 });
        let t = wall_segments(&d, n, &params(true), flat);
        let star = wall_segments(&d, n, &params(false), flat);
        assert!(star.len() > t.len(), "{} vs {}", star.len(), t.len());
    }

    #[test]
    fn quads_stand_on_the_light_rays() {
        let view = Mat4::perspective_rh(1.2, 1.0, 0.1, 50.0)
            * Mat4::look_at_rh(Vec3::new(0.0, 4.0, 0.0), Vec3::ZERO, Vec3::Z);
        let space = WallSpace {
            light: Vec3::new(0.0, 4.0, 0.0),
            inv_view_proj: view.inverse(),
            size: 64,
            top_bias: 0.0,
            bottom_margin: 0.0,
        };
        let s = WallSegment {
            a: Vec2::new(20.0, 30.5),
            b: Vec2::new(21.0, 31.0),
            near: [2.0, 2.5],
            far: [4.0, 4.5],
        };
        let q = space.quad(&s);
        assert!(((q[0] - space.light).length() - 2.0).abs() < 1e-4);
        assert!(((q[5] - space.light).length() - 4.0).abs() < 1e-4);
        // The top and bottom of each end are on one ray from the light.
        let along = (q[0] - space.light)
            .normalize()
            .dot((q[5] - space.light).normalize());
        assert!((along - 1.0).abs() < 1e-6);
        // The ray through a texel centre projects back onto that texel.
        let c = view * (space.light + space.direction(Vec2::new(20.5, 30.5)) * 3.0).extend(1.0);
        let uv = Vec2::new(c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5) * 64.0;
        assert!((uv - Vec2::new(20.5, 30.5)).length() < 1e-3, "{uv}");
    }
}
