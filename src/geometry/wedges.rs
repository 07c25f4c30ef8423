//! Penumbra wedges (Akenine-Möller & Assarsson 2002; Assarsson & Akenine-Möller 2003) for the
//! disk light, on the CPU: the exact part of the disk one silhouette edge covers as seen from a
//! receiver point, the wedge that bounds where it is not zero, and the twin of the whole method.
//! `shaders/passes/wedges.wgsl` is its GPU twin.
//!
//! **The method.** A hard shadow volume from the disk's centre (`geometry::hard_volume`, the
//! stencil count `H` of `shadow-volume`), then one wedge per silhouette edge of that volume;
//! for a receiver point `x` inside a wedge, the edge's coverage `c` of the disk as `x` sees it is
//! added up, and
//!
//! ```text
//! V(x) = clamp(1 − H(x) − Σ_edges c_i(x), 0, 1),   H = 1 where the centre's count is not 0
//! ```
//!
//! (and `H = 1` on a side of a caster turned away from the centre, which the centre cannot see:
//! [`WedgeTwin::surface_visibility`]).
//!
//! **The coverage.** Project the edge from `x` onto the light's plane (after clipping it to the
//! slab between the light's plane and `x`'s parallel plane: parts beyond `x` cannot occlude,
//! parts behind the one-sided light cannot either) and express it in disk units. With `p0`, `p1`
//! the part of the projected segment inside the unit disk,
//!
//! ```text
//! c(a, b) = (p0 × p1 − atan2(p0 × p1, p0 · p1)) / (2π)      (0 if the segment misses the disk)
//! ```
//!
//! is the signed area between the chord `p0 p1` and the arc, inside the angle the ends subtend
//! at the centre, over the disk's area. For a closed loop walked counter-clockwise, the signed
//! areas of `disk ∩ triangle(centre, A_i, B_i)` sum to `disk ∩ loop`; taking away each edge's
//! sector (which sums to the centre's winding number `H`) leaves terms that vanish for edges
//! whose projection misses the disk — the edges whose wedge does not hold `x`. So the covered
//! fraction is `H + Σ c_i`, and `c < 0` exactly when `x` is inside the edge's hard-shadow quad:
//! the 2003 paper's add-or-subtract rule falls out. A whole chord at signed distance `h` from the
//! centre covers `(acos h − h √(1 − h²))/π`, the disk–half-plane area of `V(t)`'s exact variant.
//! (Checked numerically against sampled disks by `a_whole_chord_covers_the_disk_half_plane_area`.)
//!
//! **The receiver's own plane.** A receiver `x` with normal `n` gets nothing from the part of the
//! disk behind its tangent plane (`n · (y − x) ≤ 0`): a fact of the light integral, not of the
//! casters. Wedges miss it where the receiver is on a caster and lit from the centre, its plane
//! cutting the disk (the band above a sphere's terminator): no silhouette edge of the centre's
//! volume is between it and the light, so no wedge holds it and the sum reads 1. So the plane is
//! taken as one more occluder, `V = min(V_wedges, F)` with `F` the exact part of the disk in front
//! of the plane ([`DiskFrame::horizon_fraction`]: the disk–half-plane area of V(t)'s exact
//! variant, `visibility::disk_segment_fraction`). `min`, not a product: on a face beside a
//! silhouette edge the edge lies in the face's plane, so its wedge already covers exactly what is
//! behind the plane (`V_wedges = F` there), and a product would count it twice; for a closed
//! opaque receiver the truth is never above `F`, and on the ground under a disk above it `F = 1`.
//! `--wedges-horizon 0` turns it off, to show the papers' raw method.
//!
//! **The errors the papers admit, kept:** silhouettes from the centre only (wrong for large
//! lights and thick casters: the side faces hide part of the light from points beside the
//! caster, which the centre's silhouette does not see), and overlapping edges and casters summed
//! instead of combined (two edges covering the same part of the light count it twice; the clamp
//! hides some of it).

use glam::{DVec2, DVec3, Vec3};

use super::hard_volume::{scene_volumes, HardVolume, OpenMeshes};
use super::hull::convex_hull;
use super::outline::{convex_cut_area, polygon_edge_coverage};
use super::visibility::{disk_cut2_area, disk_segment_fraction};
use super::PreparedCasters;
use crate::scene::{AreaLight, MAX_POLYGON_VERTICES};

/// Fraction of a receiver's height above the light plane kept off either end of the slab an
/// edge is clipped to (the GPU uses the same).
pub const SLAB_EPS: f64 = 1e-4;

/// The part of the unit disk between the directed segment `a → b` and the arc, inside the angle
/// its ends subtend at the centre, over π (see the module documentation); 0 where it misses.
pub fn edge_coverage_2d(a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let len = d.length();
    // Also false for NaN: a degenerate or broken segment covers nothing.
    if len.is_nan() || len <= 0.0 {
        return 0.0;
    }
    let dh = d / len;
    // Signed distance of the line from the centre, then ± the half chord around the foot:
    // stable for far, nearly grazing projections, where the quadratic's discriminant is not.
    let h = a.x * dh.y - a.y * dh.x;
    if h.abs() >= 1.0 {
        return 0.0;
    }
    let half = (1.0 - h * h).sqrt();
    let foot = -a.dot(dh);
    let t0 = (foot - half).clamp(0.0, len);
    let t1 = (foot + half).clamp(0.0, len);
    if t1 <= t0 {
        return 0.0;
    }
    let p0 = a + dh * t0;
    let p1 = a + dh * t1;
    let cross = p0.perp_dot(p1);
    (cross - cross.atan2(p0.dot(p1))) / (2.0 * std::f64::consts::PI)
}

/// The faces' angle (its sine) to the direction from a corner's apex to the shaded point over
/// which V exact fades in from the chord to the corner's wedge
/// ([`DiskFrame::corner_visibility`]): an edge whose face turns toward the point stops being its
/// silhouette there.
pub const SILHOUETTE_MARGIN: f64 = 0.1;

/// Light radii past the light's rim over which V exact fades in from the chord to the corner's
/// wedge as a corner's edges reach past the light seen from the shaded point
/// ([`DiskFrame::corner_visibility`]).
pub const REACH_MARGIN: f64 = 0.25;

/// The share of a closing fan's angle, from each of its two sides, over which V exact fades in
/// from the chord (what the quad beyond that side gives) to the corner's wedge
/// ([`DiskFrame::corner_visibility`]): the two meet there, so a fan's texels join the quads'
/// without a seam.
pub const SEAM_MARGIN: f64 = 0.15;

/// The light's frame for the coverage: centre, normal (toward the scene), radius (of the disk,
/// or of the disk a polygon fits in) and the basis `(u, w)` of its plane, with `u × w = −n` (the
/// orientation the sign rule is stated in); for a rectangle or polygon its corners in that basis
/// in units of the radius, counter-clockwise there, and their area.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiskFrame {
    pub center: DVec3,
    pub normal: DVec3,
    pub u: DVec3,
    pub w: DVec3,
    pub radius: f64,
    corners: [DVec2; MAX_POLYGON_VERTICES],
    corner_count: usize,
    corner_area: f64,
}

impl DiskFrame {
    pub fn new(light: &AreaLight) -> DiskFrame {
        let (u, w) = light.basis();
        let (u, mut w) = (u.as_dvec3(), w.as_dvec3());
        let normal = light.normal.as_dvec3();
        if u.cross(w).dot(normal) > 0.0 {
            w = -w;
        }
        let radius = f64::from(light.radius);
        let mut corners = [DVec2::ZERO; MAX_POLYGON_VERTICES];
        let mut corner_count = 0;
        if let Some(p) = light.corners() {
            let c = light.center.as_dvec3();
            for (i, v) in p.vertices().iter().enumerate() {
                let g = v.as_dvec3() - c;
                corners[i] = DVec2::new(g.dot(u), g.dot(w)) / radius;
            }
            corner_count = p.len();
            let ring = &mut corners[..corner_count];
            let signed: f64 = (0..ring.len())
                .map(|i| ring[i].perp_dot(ring[(i + 1) % ring.len()]))
                .sum();
            if signed < 0.0 {
                ring.reverse();
            }
        }
        let ring = &corners[..corner_count];
        let corner_area = 0.5
            * (0..ring.len())
                .map(|i| ring[i].perp_dot(ring[(i + 1) % ring.len()]))
                .sum::<f64>();
        DiskFrame {
            center: light.center.as_dvec3(),
            normal,
            u,
            w,
            radius,
            corners,
            corner_count,
            corner_area,
        }
    }

    /// A rectangle's or polygon's corners (radius units, counter-clockwise in `(u, w)`); empty
    /// for a disk.
    pub fn corners(&self) -> &[DVec2] {
        &self.corners[..self.corner_count]
    }

    /// Their area (radius units²).
    pub fn corner_area(&self) -> f64 {
        self.corner_area
    }

    /// The light's share where `p · m ≥ h` (radius units): a disk's segment, a polygon's cut.
    fn share_beyond(&self, m: DVec2, h: f64) -> f64 {
        if self.corner_count == 0 {
            return disk_segment_fraction(h);
        }
        (convex_cut_area(self.corners(), &[(m, h)]) / self.corner_area).clamp(0.0, 1.0)
    }

    /// The part of the disk in front of the plane through `x` with normal `n` (`n · (y − x) > 0`),
    /// the receiver's horizon: with `k = n · (c − x)` and `m` the part of `n` in the disk's
    /// plane, a disk point `c + r p` is in front where `p · m̂ > −k / (r |m|)`, the far side of a
    /// chord. 1 or 0 where `n` is (nearly) the disk's normal, by the side the centre is on.
    pub fn horizon_fraction(&self, x: Vec3, n: Vec3) -> f64 {
        let n = n.as_dvec3();
        let k = n.dot(self.center - x.as_dvec3());
        let s = (n - n.dot(self.normal) * self.normal).length() * self.radius;
        // No chord to cut by (NaN included; the GPU's `!(s > |k|)`).
        if s.is_nan() || k.is_nan() || s <= k.abs() {
            return if k > 0.0 { 1.0 } else { 0.0 };
        }
        if self.corner_count == 0 {
            return disk_segment_fraction(-k / s);
        }
        // In front: n · (c + r p − x) > 0, i.e. p · m > −k / r with m = (n·u, n·w).
        let m = DVec2::new(n.dot(self.u), n.dot(self.w));
        self.share_beyond(m, -k / self.radius)
    }

    /// V at `x` behind one convex silhouette corner of a caster, and how far it may be trusted
    /// there: `(v, weight)`, V exact at `x` being the chord's V moved `weight` of the way to `v`.
    ///
    /// `v` is the light less the corner's wedge as `x` sees it: the part behind both planes
    /// through `x` and an edge from `apex` to an end, each on the side that holds the other end.
    /// A polygon is clipped, a disk cut by `disk_cut2_area`. The corner is only the caster near
    /// the light where three things hold, each decided at `x`, not once per fan (a fine
    /// tessellation's silhouette zig-zags, so a corner convex from behind its apex is reflex
    /// from a point beside it):
    /// - both edges are silhouettes seen from `x` (their two faces on two sides of it; an open
    ///   edge always is): where a face of the edge turns toward `x` the caster's outline from
    ///   `x` runs past the edge. `weight` fades in over [`SILHOUETTE_MARGIN`] of the faces'
    ///   angle to the direction of `x`;
    /// - the corner is convex seen from `x` (the caster, against the edges' faces' normals, on
    ///   the side of each plane that holds the other end);
    /// - both edges reach past the light seen from `x` (their far ends, projected from `x` onto
    ///   the light's plane, outside the light): a corner whose edges end over the light (a
    ///   caster smaller than the light, a finely tessellated one) is not the caster there — its
    ///   other edges cut the light too — and the wedge, drawn fan by fan, would streak the
    ///   shadow. `weight` fades in over [`REACH_MARGIN`] light radii past the light's rim.
    ///
    /// And `weight` fades to 0 toward the fan's two sides ([`SEAM_MARGIN`]), where its texels
    /// meet the quads', which keep the chord: the wedge there differs from the strip by what the
    /// other edge hides, and a fan drawn over its neighbours' V would show its outline.
    ///
    /// `None` where one fails (the chord's V then). The twin of `corner_visibility` in
    /// `shaders/methods/dbuffer.wgsl`.
    pub fn corner_visibility(
        &self,
        x: Vec3,
        apex: Vec3,
        ends: [Vec3; 2],
        normals: [[Vec3; 2]; 2],
        supports: [Vec3; 2],
    ) -> Option<(f64, f64)> {
        if self.corner_count > 0 && (self.corner_area.is_nan() || self.corner_area <= 0.0) {
            return None;
        }
        let (x, a) = (x.as_dvec3(), apex.as_dvec3());
        let to_x = x - a;
        let dist = to_x.length();
        let edges = [ends[0].as_dvec3() - a, ends[1].as_dvec3() - a];
        let mut weight = 1.0f64;
        let mut cuts = [(DVec2::ZERO, 0.0); 2];
        for k in 0..2 {
            let [na, nb] = normals[k].map(|n| n.as_dvec3());
            // A silhouette from x: its faces on two sides of x (an open edge's virtual back
            // face is the other side of its one face).
            let da = na.dot(to_x);
            let db = if nb == DVec3::ZERO { -da } else { nb.dot(to_x) };
            let straddles = da * db < 0.0;
            if !straddles {
                return None;
            }
            weight = weight.min(da.abs().min(db.abs()) / (dist * SILHOUETTE_MARGIN));
            let (edge, other) = (edges[k], edges[1 - k]);
            let mut n = edge.cross(to_x);
            let side = n.dot(other);
            let floor = 1e-9 * n.length() * other.length();
            if side.is_nan() || floor.is_nan() || side.abs() <= floor {
                return None;
            }
            if side < 0.0 {
                n = -n;
            }
            // Convex from x: the caster (against its outward direction) on the other end's side.
            let caster_inside = n.dot(na + nb) < 0.0;
            if !caster_inside {
                return None;
            }
            // Behind: n · (c + r p − a) ≥ 0, p in radius units of the basis.
            let m = DVec2::new(n.dot(self.u), n.dot(self.w)) * self.radius;
            cuts[k] = (m, n.dot(a - self.center));
        }
        weight = weight.min(self.reach(x, ends) / REACH_MARGIN);
        weight = weight.min(self.fan_share(x, a, supports) / SEAM_MARGIN);
        let hidden = if self.corner_count > 0 {
            convex_cut_area(self.corners(), &cuts) / self.corner_area
        } else {
            // The unit disk: each cut with a unit normal (one parallel to the disk keeps all of
            // it or none).
            let unit = |(m, h): (DVec2, f64)| {
                let len = m.length();
                if len > 1e-12 * h.abs() {
                    (m / len, h / len)
                } else {
                    (DVec2::X, if h <= 0.0 { -2.0 } else { 2.0 })
                }
            };
            let ((m1, h1), (m2, h2)) = (unit(cuts[0]), unit(cuts[1]));
            disk_cut2_area(m1, h1, m2, h2) / std::f64::consts::PI
        };
        let v = (1.0 - hidden).clamp(0.0, 1.0);
        weight = weight.clamp(0.0, 1.0);
        (v.is_finite() && weight.is_finite()).then_some((v, weight))
    }

    /// Where `x` lies across the fan at `apex` between the extrusion points `supports`: the
    /// fan's texels are the rays from the light's centre through its triangles, between the
    /// planes through the centre, the apex and each support; the share is the distance to the
    /// nearer plane over the sum of both (0 on a side, ½ on the middle), 0 outside.
    fn fan_share(&self, x: DVec3, apex: DVec3, supports: [Vec3; 2]) -> f64 {
        let mut d = [0.0f64; 2];
        for k in 0..2 {
            let p = supports[k].as_dvec3() - self.center;
            let q = supports[1 - k].as_dvec3() - self.center;
            let n = (apex - self.center).cross(p);
            // The fan lies on the side away from the other support (its rays run from the apex
            // away from the rim points).
            let away = if n.dot(q) > 0.0 { -n } else { n };
            d[k] = away.dot(x - self.center).max(0.0) / away.length();
        }
        let sum = d[0] + d[1];
        if sum > 0.0 && sum.is_finite() {
            d[0].min(d[1]) / sum
        } else {
            0.0
        }
    }

    /// How far outside the light the nearer of `ends` lies, seen from `x` (projected from it onto
    /// the light's plane), in radii: negative inside. An end no nearer the light's plane than
    /// `x` is infinitely far (its edge runs away from the light).
    fn reach(&self, x: DVec3, ends: [Vec3; 2]) -> f64 {
        let hx = self.normal.dot(x - self.center);
        let mut least = f64::INFINITY;
        for end in ends {
            let e = end.as_dvec3();
            let he = self.normal.dot(e - self.center);
            let nearer = he < hx;
            if !nearer {
                continue;
            }
            let g = x + (e - x) * (hx / (hx - he)) - self.center;
            let q = DVec2::new(g.dot(self.u), g.dot(self.w)) / self.radius;
            let ring = self.corners();
            let out = if ring.is_empty() {
                q.length() - 1.0
            } else {
                (0..ring.len())
                    .map(|i| {
                        let d = ring[(i + 1) % ring.len()] - ring[i];
                        DVec2::new(d.y, -d.x).dot(q - ring[i]) / d.length()
                    })
                    .fold(f64::NEG_INFINITY, f64::max)
            };
            least = least.min(out);
        }
        least
    }

    /// The coverage of the disk by the edge `e0 → e1` as `x` sees it (`e0 → e1` in the
    /// direction the hard volume's sides walk it).
    pub fn edge_coverage(&self, x: Vec3, e0: Vec3, e1: Vec3) -> f64 {
        let (x, e0, e1) = (x.as_dvec3(), e0.as_dvec3(), e1.as_dvec3());
        let c = self.center;
        let tx = self.normal.dot(x - c);
        if tx.is_nan() || tx <= 0.0 || self.radius.is_nan() || self.radius <= 0.0 {
            return 0.0;
        }
        let (t0, t1) = (self.normal.dot(e0 - c), self.normal.dot(e1 - c));
        let (lo, hi) = (SLAB_EPS * tx, (1.0 - SLAB_EPS) * tx);
        let (mut s0, mut s1) = (0.0f64, 1.0f64);
        let dt = t1 - t0;
        if dt.abs() < 1e-12 * tx {
            if t0 < lo || t0 > hi {
                return 0.0;
            }
        } else {
            let (sa, sb) = ((lo - t0) / dt, (hi - t0) / dt);
            s0 = s0.max(sa.min(sb));
            s1 = s1.min(sa.max(sb));
            if s1 <= s0 {
                return 0.0;
            }
        }
        let to_disk = |q: DVec3| {
            let tq = self.normal.dot(q - c);
            let g = x + (q - x) * (tx / (tx - tq)) - c;
            DVec2::new(g.dot(self.u), g.dot(self.w)) / self.radius
        };
        let (a, b) = (to_disk(e0.lerp(e1, s0)), to_disk(e0.lerp(e1, s1)));
        if self.corner_count == 0 {
            edge_coverage_2d(a, b)
        } else {
            polygon_edge_coverage(self.corners(), self.corner_area, a, b)
        }
    }
}

/// The wedge of edge `e0 → e1`: a convex solid holding every point whose view of the disk the
/// edge can cut, up to `reach` from the edge. The exact region is swept by the rays from the
/// disk's points through the edge's points; it is held by the hull of the edge and of its ends
/// pushed `reach` away from the 8 corners of the octagon around the disk (circumradius
/// `r / cos(π/8)`): every point of the region is a convex combination of those 18 points.
/// Triangles outward-wound; a box around the 18 points where they span no volume.
pub fn wedge_hull(light: &AreaLight, e0: Vec3, e1: Vec3, reach: f32) -> Vec<[Vec3; 3]> {
    let (u, w) = light.basis();
    let rim = light.radius / (std::f32::consts::PI / 8.0).cos();
    let mut points = vec![e0, e1];
    for k in 0..8 {
        let a = k as f32 * std::f32::consts::TAU / 8.0;
        let q = light.center + rim * (a.cos() * u + a.sin() * w);
        for e in [e0, e1] {
            points.push(e + (e - q).normalize_or_zero() * reach);
        }
    }
    match convex_hull(&points) {
        Some(mesh) => mesh.triangle_corners().collect(),
        None => box_triangles(&points),
    }
}

/// The 12 outward-wound triangles of the bounding box of `points`.
fn box_triangles(points: &[Vec3]) -> Vec<[Vec3; 3]> {
    let lo = points.iter().fold(Vec3::splat(f32::MAX), |m, p| m.min(*p));
    let hi = points.iter().fold(Vec3::splat(f32::MIN), |m, p| m.max(*p));
    let pad = (hi - lo).max_element().max(1e-3) * 1e-3;
    let (lo, hi) = (lo - pad, hi + pad);
    let corner = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    // Quads as corner indices, counter-clockwise seen from outside.
    const QUADS: [[usize; 4]; 6] = [
        [0, 2, 3, 1], // −z
        [4, 5, 7, 6], // +z
        [0, 1, 5, 4], // −y
        [2, 6, 7, 3], // +y
        [0, 4, 6, 2], // −x
        [1, 3, 7, 5], // +x
    ];
    QUADS
        .iter()
        .flat_map(|q| {
            [
                [corner(q[0]), corner(q[1]), corner(q[2])],
                [corner(q[0]), corner(q[2]), corner(q[3])],
            ]
        })
        .collect()
}

/// How far wedges reach: the diagonal of everything the scene holds (no receiver is farther from
/// a caster), and a little more.
pub fn wedge_reach(scene: &crate::scene::Scene) -> f32 {
    let mut lo = scene.light.center();
    let mut hi = lo;
    for o in &scene.objects {
        if let Some((a, b)) = o.mesh.bounds() {
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    let d = (hi - lo).length() * 1.05 + 1e-3;
    if d.is_finite() {
        d
    } else {
        1e4
    }
}

/// The edges whose wedges a scene's casters get: the sides of the casters' hard volumes from
/// the centre closed by their lit faces (Crow's one-sided volumes: each silhouette once, so the
/// loops wind once around what they hide). For a closed mesh these are the sides of any closing;
/// for an open one the two-sided count (`H`) counts both faces at a silhouette, but its wedges
/// must be summed once.
pub fn wedge_edges(casters: &PreparedCasters, center: Vec3) -> Vec<[Vec3; 2]> {
    scene_volumes(casters, center, OpenMeshes::OneSided)
        .into_iter()
        .flat_map(|(_, _, v)| v.sides)
        .collect()
}

/// The whole method on the CPU: the hard volumes from the centre (for `H`, closed as the
/// method's `open` says) and the wedges' edges.
pub struct WedgeTwin {
    pub frame: DiskFrame,
    pub volumes: Vec<HardVolume>,
    pub edges: Vec<[Vec3; 2]>,
    /// Clip the disk by the receiver's own plane in [`WedgeTwin::surface_visibility`]
    /// (`--wedges-horizon`, on unless set off).
    pub horizon: bool,
}

impl WedgeTwin {
    pub fn new(casters: &PreparedCasters, light: &AreaLight, open: OpenMeshes) -> WedgeTwin {
        WedgeTwin {
            frame: DiskFrame::new(light),
            volumes: scene_volumes(casters, light.center, open)
                .into_iter()
                .map(|(_, _, v)| v)
                .collect(),
            edges: wedge_edges(casters, light.center),
            horizon: true,
        }
    }

    /// `H(x)`: whether the centre's hard volumes hold `x` (the stencil count is not 0). For a
    /// point on a caster, its own face's volume starts at the point itself: it is counted from
    /// a hair (1e-4 of the way) toward the centre, as the GPU's volumes are pushed that much
    /// away from it.
    pub fn hard(&self, x: Vec3) -> bool {
        let c = self.frame.center.as_vec3();
        let x = x + (c - x) * 1e-4;
        self.volumes.iter().map(|v| v.count(x)).sum::<i32>() != 0
    }

    /// `Σ c_i(x)` over every wedge's edge.
    pub fn coverage_sum(&self, x: Vec3) -> f64 {
        self.edges
            .iter()
            .map(|&[e0, e1]| self.frame.edge_coverage(x, e0, e1))
            .sum()
    }

    /// V at `x`, as the method computes it.
    pub fn visibility(&self, x: Vec3) -> f64 {
        let h = if self.hard(x) { 1.0 } else { 0.0 };
        (1.0 - h - self.coverage_sum(x)).clamp(0.0, 1.0)
    }

    /// V at a surface point `x` with normal `n` (toward the viewer): on a side turned away from
    /// the centre, the centre is hidden by that surface itself (`H = 1`, as Crow's volume from
    /// the centre has it), so `V = clamp(−Σc)`; elsewhere [`WedgeTwin::visibility`]. Then, with
    /// [`WedgeTwin::horizon`], at most the part of the disk in front of the surface's plane
    /// (see the module documentation).
    pub fn surface_visibility(&self, x: Vec3, n: Vec3) -> f64 {
        let c = self.frame.center;
        let v = if n.as_dvec3().dot(c - x.as_dvec3()) <= 0.0 {
            (-self.coverage_sum(x)).clamp(0.0, 1.0)
        } else {
            self.visibility(x)
        };
        if self.horizon {
            v.min(self.frame.horizon_fraction(x, n))
        } else {
            v
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_whole_chord_covers_the_disk_half_plane_area() {
        for i in 0..=40 {
            let h = -1.0 + 2.0 * i as f64 / 40.0;
            // A long segment along +x at height y = h: the centre is on its right.
            let c = edge_coverage_2d(DVec2::new(-5.0, h), DVec2::new(5.0, h));
            assert!(
                (c.abs() - disk_segment_fraction(h.abs())).abs() < 1e-9,
                "h = {h}: {c}"
            );
            // Reversing the segment flips the sign.
            let r = edge_coverage_2d(DVec2::new(5.0, h), DVec2::new(-5.0, h));
            assert!((c + r).abs() < 1e-12, "h = {h}");
        }
        // The bottom edge of a counter-clockwise region above y = 0.5 (the centre outside it)
        // covers the segment beyond that chord: the design note's 0.1955 (its sign there is
        // for the edge walked the other way).
        let c = edge_coverage_2d(DVec2::new(-3.0, 0.5), DVec2::new(3.0, 0.5));
        assert!((c - 0.195_501_109_477_885).abs() < 1e-9, "{c}");
    }

    #[test]
    fn the_horizon_fraction_is_the_part_of_the_disk_in_front_of_the_plane() {
        // A tilted disk and random planes through random points: the fraction against the
        // disk's points on a fine polar grid counted in front of the plane.
        let light = AreaLight {
            center: Vec3::new(0.3, 4.0, -0.2),
            normal: Vec3::new(-0.2, -1.0, 0.1).normalize(),
            radius: 0.7,
            intensity: 1.0,
            outline: crate::scene::Outline::Disk,
        };
        let frame = DiskFrame::new(&light);
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (rings, spokes) = (300, 600);
        let mut cut = 0;
        for _ in 0..40 {
            let x = DVec3::new(rnd() * 2.0 - 1.0, 3.0 + rnd() * 2.0, rnd() * 2.0 - 1.0);
            let n = DVec3::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0).normalize();
            let f = frame.horizon_fraction(x.as_vec3(), n.as_vec3());
            // Equal-area rings: ring i at radius √((i + ½)/rings).
            let mut front = 0usize;
            for i in 0..rings {
                let rho = ((i as f64 + 0.5) / rings as f64).sqrt() * frame.radius;
                for j in 0..spokes {
                    let a = (j as f64 + 0.5) / spokes as f64 * std::f64::consts::TAU;
                    let y = frame.center + rho * (a.cos() * frame.u + a.sin() * frame.w);
                    front += usize::from(n.dot(y - x) > 0.0);
                }
            }
            let grid = front as f64 / (rings * spokes) as f64;
            assert!((f - grid).abs() < 2e-3, "x {x} n {n}: {f} against {grid}");
            cut += usize::from(grid > 0.02 && grid < 0.98);
        }
        assert!(cut >= 10, "only {cut} planes cut the disk");
        // A plane parallel to the disk: all or nothing by the side the centre is on.
        let below = Vec3::new(0.0, 1.0, 0.0);
        let nc = light.normal;
        assert_eq!(frame.horizon_fraction(below, -nc), 1.0);
        assert_eq!(frame.horizon_fraction(below, nc), 0.0);
    }

    #[test]
    fn polygons_cover_their_area_in_the_disk() {
        // Random convex polygons (counter-clockwise): winding of the centre + Σ c = the area of
        // polygon ∩ disk over π, against a fine grid of the disk.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..30 {
            let centre = DVec2::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0);
            let n = 3 + (rnd() * 5.0) as usize;
            let mut angles: Vec<f64> = (0..n).map(|_| rnd() * std::f64::consts::TAU).collect();
            angles.sort_by(f64::total_cmp);
            let size = 0.3 + rnd() * 1.5;
            let poly: Vec<DVec2> = angles
                .iter()
                .map(|a| centre + DVec2::new(a.cos(), a.sin()) * size)
                .collect();
            let inside = |p: DVec2| {
                (0..n).all(|i| (poly[(i + 1) % n] - poly[i]).perp_dot(p - poly[i]) >= 0.0)
            };
            let winding = if inside(DVec2::ZERO) { 1.0 } else { 0.0 };
            let sum: f64 = (0..n)
                .map(|i| edge_coverage_2d(poly[i], poly[(i + 1) % n]))
                .sum();
            let grid = 400;
            let mut hit = 0usize;
            let mut total = 0usize;
            for i in 0..grid {
                for j in 0..grid {
                    let p = DVec2::new(
                        -1.0 + 2.0 * (i as f64 + 0.5) / grid as f64,
                        -1.0 + 2.0 * (j as f64 + 0.5) / grid as f64,
                    );
                    if p.length_squared() <= 1.0 {
                        total += 1;
                        hit += usize::from(inside(p));
                    }
                }
            }
            let area = hit as f64 / total as f64;
            assert!(
                (winding + sum - area).abs() < 2e-3,
                "winding {winding} + Σc {sum} vs area {area}"
            );
        }
    }
}
