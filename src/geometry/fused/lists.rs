//! The light pass's bounded per-texel edge lists: what a texel stores, the caster crossings along
//! its ray (for `L(c)`), the proxy each edge is rasterised as, and the fragment test that decides
//! whether an edge enters a texel's list (see the module docs of [`super`]: "The light pass").

use glam::{Mat4, Vec2, Vec3};

use super::chord::FusedEdge;
use super::{CLIP, FACING_TOL};
use crate::scene::AreaLight;

/// What the light pass stores for one texel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TexelList {
    /// Edges that passed the test (all of them, as the GPU's counter counts them).
    pub count: usize,
    /// The stored edges (indices into [`FusedTwin::edges`]); empty on overflow.
    pub edges: Vec<u32>,
    /// `count > cap`: the camera pass falls back to `dbuffer`.
    pub overflow: bool,
}

/// The caster surfaces along a D-buffer texel's ray, for `L(c)`: what the light pass counts
/// along the texel's centre ray (additive blend), and the largest height of a crossing over the
/// 3×3 texels around it (max blend, then a 3×3 max).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CasterCrossings {
    pub count: u32,
    pub far_height: f32,
    /// Unit direction of the texel's centre ray.
    pub dir: Vec3,
}

impl CasterCrossings {
    /// `L(c)` for a receiver `x` beyond every crossing: the count along the texel's ray, plus
    /// the layers gained or lost where the ray, swept sideways to `x`'s, passes an edge that is a
    /// silhouette from `c` (an outline of the casters seen from `c`). Those edges are in `x`'s
    /// list: seen from `x` they project next to the disk centre. `None` for a receiver among the
    /// casters.
    pub fn layers_at<'a>(
        &self,
        x: Vec3,
        edges: impl IntoIterator<Item = &'a FusedEdge>,
        light: &AreaLight,
    ) -> Option<i32> {
        let h = light.height_of(x);
        if h.is_nan() || h <= self.far_height * (1.0 + 1e-4) {
            return None;
        }
        let c = light.center;
        let y = c + self.dir * (x - c).length();
        let mut layers = self.count as i32;
        for e in edges {
            if !e.is_silhouette_from(c) {
                continue;
            }
            let m = (e.a - c).cross(e.b - c);
            let fold = m.dot(e.fold);
            let (sx, sy) = (m.dot(x - c), m.dot(y - c));
            // The edge is crossed when the sweep from y to x passes its plane through c within
            // the edge: the segment a–b meets the triangle c, y, x.
            if fold == 0.0
                || (sx > 0.0) == (sy > 0.0)
                || !segment_meets_triangle(e.a, e.b, [c, y, x])
            {
                continue;
            }
            let gained = (sx > 0.0) == (fold > 0.0);
            layers += if gained {
                e.layers as i32
            } else {
                -(e.layers as i32)
            };
        }
        Some(layers)
    }
}

/// The light pass's proxy for one edge: a solid whose projection from the light centre holds every
/// texel direction [`edge_in_texel`] can accept, for receivers no higher than `h_max` (measured
/// from the light plane). Seen from `c`, the edge's wedge up to that height is the edge swept by
/// disks parallel to the light, of radius `(1 − H_p / h_max) r` at an edge point at height `H_p`
/// (the radius is linear along the edge, so the sweep is the convex hull of the two end disks).
/// Here each disk is an octagon around it (grown by `1/cos(π/8)`) plus `pad[k]` metres, the
/// margin for a texel's width at that end. Rasterise the two octagons and the eight quads between
/// their corresponding corners: together they cover the hull's projection.
pub fn wedge_proxy(
    edge: &FusedEdge,
    light: &AreaLight,
    h_max: f32,
    pad: [f32; 2],
) -> [[Vec3; 8]; 2] {
    let (e1, e2) = light.basis();
    let grow = 1.0 / (std::f32::consts::PI / 8.0).cos();
    [(edge.a, pad[0]), (edge.b, pad[1])].map(|(p, pad)| {
        let kappa = (1.0 - light.height_of(p) / h_max).clamp(0.0, 1.0);
        let radius = (kappa * light.radius + pad) * grow;
        std::array::from_fn(|k| {
            let a = k as f32 * std::f32::consts::FRAC_PI_4;
            p + radius * (a.cos() * e1 + a.sin() * e2)
        })
    })
}

/// The light pass's proxy as the GPU draws it: the convex hull, in the light view's normalised
/// device coordinates, of [`wedge_proxy`]'s two octagons projected by `view_proj` (at most 16
/// corners, counter-clockwise). Drawing the hull, not the octagons and quads, draws each texel
/// once per edge, so an edge enters a list at most once. Where a corner lies at or behind the
/// light view's eye plane the projection is not convex: the whole view (`[-1, 1]²`).
pub fn proxy_hull(
    edge: &FusedEdge,
    light: &AreaLight,
    h_max: f32,
    pad: [f32; 2],
    view_proj: &Mat4,
) -> Vec<Vec2> {
    let whole = vec![
        Vec2::new(-1.0, -1.0),
        Vec2::new(1.0, -1.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(-1.0, 1.0),
    ];
    let [o0, o1] = wedge_proxy(edge, light, h_max, pad);
    let mut points = Vec::with_capacity(16);
    for p in o0.iter().chain(&o1) {
        let clip = *view_proj * p.extend(1.0);
        if clip.w.is_nan() || clip.w <= 1e-6 {
            return whole;
        }
        let ndc = Vec2::new(clip.x, clip.y) / clip.w;
        if !ndc.is_finite() {
            return whole;
        }
        points.push(ndc);
    }
    hull_2d(points)
}

/// The convex hull of `points` (Andrew's monotone chain), counter-clockwise, without collinear
/// corners.
fn hull_2d(mut points: Vec<Vec2>) -> Vec<Vec2> {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let turn = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let chain = |ordered: &mut dyn Iterator<Item = Vec2>| {
        let mut out: Vec<Vec2> = Vec::new();
        for p in ordered {
            while out.len() >= 2 && turn(out[out.len() - 2], out[out.len() - 1], p) <= 0.0 {
                out.pop();
            }
            out.push(p);
        }
        out.pop();
        out
    };
    let mut hull = chain(&mut points.iter().copied());
    hull.extend(chain(&mut points.iter().rev().copied()));
    hull
}

/// Whether the segment `a b` meets the triangle.
fn segment_meets_triangle(a: Vec3, b: Vec3, tri: [Vec3; 3]) -> bool {
    crate::geometry::ray::intersect_triangle(a, b - a, &tri)
        .is_some_and(|t| (0.0..=1.0).contains(&t))
}

/// A patch of receiver surface around one texel: a point on it, its unit normal, how far the
/// same surface reaches within the 3×3 texels around (`radius`) and how far it strays from the
/// plane there (`bulge`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    pub point: Vec3,
    pub normal: Vec3,
    pub radius: f32,
    pub bulge: f32,
}

impl Patch {
    /// The range of the plane function `n·p − offset` over the patch.
    fn range(&self, n: Vec3, offset: f32) -> (f32, f32) {
        let f = n.dot(self.point) - offset;
        let spread = self.radius * n.cross(self.normal).length() + self.bulge;
        (f - spread, f + spread)
    }
}

/// The ray of one texel as the light pass's fragment shader sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct TexelRay {
    /// Unit direction from the light centre through the texel's centre.
    pub dir: Vec3,
    /// Where the texel's receivers can be. Receivers are surfaces facing the light centre (the
    /// camera pass shades the others black). `patches`: the first, second and last such surface
    /// along the ray, each with the same receivers of the 3×3 texels around when they lie on the
    /// same surface; `deeper`: a stretch of distances along `dir` for the rest (receivers across
    /// an outline, or between the second and the last of a ray with more than three), converted
    /// from heights.
    pub patches: Vec<Patch>,
    pub deeper: Option<(f32, f32)>,
    /// The largest of them all: where the wedge test is made.
    pub far: f32,
    /// The texel's half-diagonal as a slope (lateral distance per unit of distance from `c`).
    pub half_slope: f32,
}

/// The light pass's test for one edge and one texel (its fragment shader does exactly this):
/// 1. *the wedge*: the point `y` of the ray at `far` sees the edge's projection meet the disk,
///    with a margin for the texel's width: moving `y` sideways by `l` moves the projection of an
///    edge point at height `H_p` by `l · H_p / (H_y − H_p)`. Wedges only grow with depth along a
///    ray from `c`, so this covers every depth up to `far`;
/// 2. *the silhouette*: some receiver of the texel may see one face of the edge in front and
///    the other behind. On the first surface: within the patch's radius of its point (a face
///    function changes by at most the distance); deeper: somewhere on the `deeper` stretch of
///    the ray beyond the edge, where each face function is linear along the ray and moves by at
///    most the pyramid's half-width sideways.
pub fn edge_in_texel(edge: &FusedEdge, ray: &TexelRay, light: &AreaLight) -> bool {
    let c = light.center;
    let along = ray.dir.dot(light.normal);
    if along.is_nan() || along <= 0.0 || ray.far.is_nan() || ray.far <= 0.0 {
        return false;
    }
    let y = c + ray.dir * ray.far;
    let hy = ray.far * along;
    let limit = hy * (1.0 - CLIP);
    let (ha, hb) = (light.height_of(edge.a), light.height_of(edge.b));
    let (mut pa, mut pb) = (edge.a, edge.b);
    let (mut qa, mut qb) = (ha, hb);
    match (ha < limit, hb < limit) {
        (true, true) => {}
        (false, false) => return false,
        (true, false) => {
            pb = edge.a + (edge.b - edge.a) * ((limit - ha) / (hb - ha));
            qb = limit;
        }
        (false, true) => {
            pa = edge.a + (edge.b - edge.a) * ((limit - ha) / (hb - ha));
            qa = limit;
        }
    }
    let (e1, e2) = light.basis();
    // Projection from y onto the light plane, in disk coordinates (metres).
    let project = |p: Vec3, hp: f32| {
        let q = y + (p - y) * (hy / (hy - hp));
        Vec2::new((q - c).dot(e1), (q - c).dot(e2))
    };
    let (sa, sb) = (project(pa, qa), project(pb, qb));
    // The pyramid's half-width at y, measured parallel to the light plane.
    let lateral = ray.far * ray.half_slope / along;
    let amplification = |hp: f32| hp.max(0.0) / (hy - hp);
    let margin = lateral * amplification(qa).max(amplification(qb));
    if distance_to_segment(Vec2::ZERO, sa, sb) > light.radius + margin {
        return false;
    }
    if edge.layers == 1 {
        return true; // an open boundary is a silhouette from everywhere
    }
    // Points of the ray nearer the light than the edge cannot see it in front of the disk.
    let t_edge = ha.min(hb) / along;
    // f_i(t) = f_i(c) + t n_i·w, give or take t · half_slope sideways; "maybe in front":
    // f_i + s t > −tol, "maybe behind": f_i − s t < tol.
    let tol = FACING_TOL * (1.0 + y.abs().max_element() + edge.a.abs().max_element());
    let (f0, g0) = (edge.n0.dot(c) - edge.offset0, edge.n0.dot(ray.dir));
    let (f1, g1) = (edge.n1.dot(c) - edge.offset1, edge.n1.dot(ray.dir));
    let s = ray.half_slope;
    let front = |f: f32, g: f32| positive_on(f + tol, g + s);
    let back = |f: f32, g: f32| positive_on(tol - f, s - g);
    let silhouette = [
        intersect(front(f0, g0), back(f1, g1)),
        intersect(back(f0, g0), front(f1, g1)),
    ];
    let deeper = ray.deeper.is_some_and(|(lo, hi)| {
        let lo = lo.max(t_edge);
        silhouette.iter().any(|&(a, b)| a.max(lo) <= b.min(hi))
    });
    let first = ray.patches.iter().any(|patch| {
        let (lo0, hi0) = patch.range(edge.n0, edge.offset0);
        let (lo1, hi1) = patch.range(edge.n1, edge.offset1);
        let (front0, back0) = (hi0 > -tol, lo0 < tol);
        let (front1, back1) = (hi1 > -tol, lo1 < tol);
        light.height_of(patch.point) + patch.radius > ha.min(hb)
            && ((front0 && back1) || (back0 && front1))
    });
    first || deeper
}

/// Where `alpha + beta t > 0`, as an interval of `t`.
fn positive_on(alpha: f32, beta: f32) -> (f32, f32) {
    if beta > 0.0 {
        (-alpha / beta, f32::INFINITY)
    } else if beta < 0.0 {
        (f32::NEG_INFINITY, -alpha / beta)
    } else if alpha > 0.0 {
        (f32::NEG_INFINITY, f32::INFINITY)
    } else {
        (f32::INFINITY, f32::NEG_INFINITY)
    }
}

fn intersect(a: (f32, f32), b: (f32, f32)) -> (f32, f32) {
    (a.0.max(b.0), a.1.min(b.1))
}

fn distance_to_segment(p: Vec2, a: Vec2, b: Vec2) -> f32 {
    let d = b - a;
    let len2 = d.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * t - p).length()
}
