//! The candidate edges of the casters and the chord each one cuts from the disk as seen from a
//! receiver (see the module docs of [`super`]: "The chord of an edge", "Which edges").

use glam::{Vec2, Vec3};

use super::area::region_area;
use super::{CLIP, FACING_TOL};
use crate::geometry::adjacency::{CasterMesh, NO_FACE};
use crate::geometry::classify::FaceClass;
use crate::geometry::outline::polygon_edge_coverage;
use crate::scene::AreaLight;

/// A candidate silhouette edge: what the light pass rasterises and the camera pass reads, per edge
/// (the GPU's storage-buffer record, 7 × `vec4<f32>`: see `docs/method/dbuffer-fused.md`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FusedEdge {
    pub a: Vec3,
    pub b: Vec3,
    /// Face planes `n·p − offset` (positive in front). For an open boundary edge, face 1 is the
    /// back of face 0.
    pub n0: Vec3,
    pub offset0: f32,
    pub n1: Vec3,
    pub offset1: f32,
    /// The sum of the two faces' unit directions away from the edge, within each face: the side of
    /// the plane through `x` and the edge that the faces project onto when the edge is a silhouette
    /// from `x` (they fold onto one side).
    pub fold: Vec3,
    /// Layers a crossing of the projected edge adds: 2 between two faces, 1 on an open boundary.
    pub layers: u32,
    /// Index of the caster.
    pub caster: u32,
    /// Whether the caster bounds a convex solid (`CasterMesh::convex`): where its edges alone cut
    /// the disk, the disk is one layer deep.
    pub convex: bool,
}

impl FusedEdge {
    /// The edge as the GPU's storage-buffer record (`FusedEdge` of `shaders/shared/fused.wgsl`):
    /// `a.xyz, layers` · `b.xyz, max |aᵢ|` (the scale of the facing tolerance) ·
    /// `n0.xyz, offset0` · `n1.xyz, offset1` · `fold.xyz, 1 if a silhouette from the light
    /// centre c else 0` (an outline seen from `c`, which [`CasterCrossings::layers_at`] looks
    /// for) · `m_c.xyz, m_c·fold` with `m_c = (a − c) × (b − c)`, the normal of the plane through
    /// `c` and the edge · `caster, 1 if the caster is convex else 0, 0, 0`. The same `f32`s the
    /// CPU twin computes with.
    pub fn gpu_record(&self, c: Vec3) -> [[f32; 4]; 7] {
        let m = (self.a - c).cross(self.b - c);
        [
            self.a.extend(self.layers as f32).to_array(),
            self.b.extend(self.a.abs().max_element()).to_array(),
            self.n0.extend(self.offset0).to_array(),
            self.n1.extend(self.offset1).to_array(),
            self.fold
                .extend(f32::from(u8::from(self.is_silhouette_from(c))))
                .to_array(),
            m.extend(m.dot(self.fold)).to_array(),
            [
                self.caster as f32,
                f32::from(u8::from(self.convex)),
                0.0,
                0.0,
            ],
        ]
    }

    /// Whether `x` sees one face from the front and the other from the back. A point on a face's
    /// plane counts as in front of it.
    pub fn is_silhouette_from(&self, x: Vec3) -> bool {
        let tol = FACING_TOL * (1.0 + x.abs().max_element() + self.a.abs().max_element());
        let front0 = self.n0.dot(x) - self.offset0 > -tol;
        let front1 = self.n1.dot(x) - self.offset1 > -tol;
        front0 != front1
    }
}

/// The candidate edges of one caster: every edge whose two faces are not both all-frontfacing nor
/// both none-frontfacing (an open boundary edge always is one).
pub fn candidate_edges(mesh: &CasterMesh, classes: &[FaceClass], caster: u32) -> Vec<FusedEdge> {
    let mut out = Vec::new();
    for e in &mesh.edges {
        let f0 = e.faces[0] as usize;
        let (Some(_), Some(&c0)) = (mesh.faces.get(f0), classes.get(f0)) else {
            continue;
        };
        let boundary = e.faces[1] == NO_FACE;
        let c1 = if boundary {
            c0.mirrored()
        } else {
            match classes.get(e.faces[1] as usize) {
                Some(&c) => c,
                None => continue,
            }
        };
        if c0 == c1 && matches!(c0, FaceClass::AllFront | FaceClass::NoneFront) {
            continue;
        }
        let (a, b) = (mesh.position(e.v[0]), mesh.position(e.v[1]));
        let along = (b - a).normalize_or_zero();
        let inward = |o: Vec3| {
            let d = o - a;
            (d - d.dot(along) * along).normalize_or_zero()
        };
        let d0 = inward(mesh.opposite_vertex(e.faces[0], e));
        let plane0 = mesh.plane(e.faces[0]);
        let (n1, offset1, d1) = if boundary {
            (-plane0.0, -plane0.1, d0)
        } else {
            let (normal1, offset1) = mesh.plane(e.faces[1]);
            (
                normal1,
                offset1,
                inward(mesh.opposite_vertex(e.faces[1], e)),
            )
        };
        out.push(FusedEdge {
            a,
            b,
            n0: plane0.0,
            offset0: plane0.1,
            n1,
            offset1,
            fold: d0 + d1,
            layers: if boundary { 1 } else { 2 },
            caster,
            convex: mesh.convex,
        });
    }
    out
}

/// What one edge does to the disk as seen from `x`: the samples `q` with `chord(q) > 0` and
/// `(end_a(q) > 0) != (end_b(q) > 0)` get `delta` layers. Coefficients are in unit-disk
/// coordinates `(u, v)`; `chord` is oriented so that the disk centre is on its negative side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeChord {
    /// `[A, B, C]`: `A u + B v + C`, `C < 0`.
    pub chord: [f32; 3],
    /// `[A, B]` of the line from the centre through the projection of one end point.
    pub end_a: [f32; 2],
    pub end_b: [f32; 2],
    /// ± the edge's layers: + where the far side of the chord is the caster's side.
    pub delta: i32,
    /// The exact area of the region, as a fraction of the disk's.
    pub area: f64,
    /// The (clipped) edge's end points projected from the receiver onto the light's plane, in
    /// unit-disk coordinates (radii from the centre along `e₁`, `e₂`): what a picture of the disk
    /// draws.
    pub ends: [Vec2; 2],
}

impl EdgeChord {
    /// Whether the unit-disk point `p` is in the region.
    #[inline]
    pub fn contains(&self, p: Vec2) -> bool {
        let [a, b, c] = self.chord;
        let beyond = a * p.x + b * p.y + c > 0.0;
        let sa = self.end_a[0] * p.x + self.end_a[1] * p.y > 0.0;
        let sb = self.end_b[0] * p.x + self.end_b[1] * p.y > 0.0;
        beyond && sa != sb
    }
}

/// [`region_area`] of the disk, or for a rectangle or polygon light the same region of it (the
/// part beyond the segment inside the angle its ends subtend at the centre), as a fraction of
/// its area: `geometry::outline::polygon_edge_coverage`, unsigned. `p` and `q` are in unit-disk
/// coordinates (radii of the disk the polygon fits in).
pub fn region_area_of(light: &AreaLight, p: Vec2, q: Vec2) -> f64 {
    let Some(poly) = light.corners() else {
        return region_area(p, q);
    };
    let (e1, e2) = light.basis();
    let r = light.radius;
    let mut corners: Vec<glam::DVec2> = poly
        .vertices()
        .iter()
        .map(|v| {
            let g = *v - light.center;
            glam::DVec2::new(f64::from(g.dot(e1) / r), f64::from(g.dot(e2) / r))
        })
        .collect();
    let area = 0.5
        * (0..corners.len())
            .map(|i| corners[i].perp_dot(corners[(i + 1) % corners.len()]))
            .sum::<f64>();
    if area < 0.0 {
        corners.reverse();
    }
    polygon_edge_coverage(&corners, area.abs(), p.as_dvec2(), q.as_dvec2()).abs()
}

/// The chord `edge` cuts from the disk as seen from `x`, or `None` when it changes nothing there:
/// not a silhouette from `x`, entirely beyond `x`'s height, or degenerate (chord through `c`).
pub fn edge_chord(edge: &FusedEdge, x: Vec3, light: &AreaLight) -> Option<EdgeChord> {
    let (e1, e2) = light.basis();
    let c = light.center;
    let hx = light.height_of(x);
    if hx.is_nan() || hx <= 0.0 || !edge.is_silhouette_from(x) {
        return None;
    }
    // Clip the edge to the part nearer the light than x.
    let limit = hx * (1.0 - CLIP);
    let (ha, hb) = (light.height_of(edge.a), light.height_of(edge.b));
    let (mut pa, mut pb) = (edge.a, edge.b);
    match (ha < limit, hb < limit) {
        (true, true) => {}
        (false, false) => return None,
        (true, false) => pb = edge.a + (edge.b - edge.a) * ((limit - ha) / (hb - ha)),
        (false, true) => pa = edge.a + (edge.b - edge.a) * ((limit - ha) / (hb - ha)),
    }
    let r = light.radius;
    let m = (edge.a - x).cross(edge.b - x);
    let cc = m.dot(c - x);
    let fold = m.dot(edge.fold);
    if cc == 0.0 || fold == 0.0 || !cc.is_finite() {
        return None;
    }
    // The caster's side of the chord is the side of `fold`. Crossing from c to a sample beyond the
    // chord enters the caster's projection (+) unless c is already on the caster's side (−).
    let c_on_caster_side = (cc > 0.0) == (fold > 0.0);
    let layers = edge.layers as i32;
    let delta = if c_on_caster_side { -layers } else { layers };
    let s = -cc.signum();
    let chord = [s * r * m.dot(e1), s * r * m.dot(e2), s * cc];
    // Side of the projected end point p relative to the line from c through a sample:
    // ((c − x) × (q − x))·(p − x) = r (u ((c − x) × e1)·(p − x) + v ((c − x) × e2)·(p − x)).
    let (k1, k2) = ((c - x).cross(e1), (c - x).cross(e2));
    let end = |p: Vec3| [r * k1.dot(p - x), r * k2.dot(p - x)];
    // The projected end points, in radii, for the exact area of the region.
    let project = |p: Vec3| {
        let q = x + (p - x) * (hx / (hx - light.height_of(p)));
        Vec2::new((q - c).dot(e1), (q - c).dot(e2)) / r
    };
    let ends = [project(pa), project(pb)];
    Some(EdgeChord {
        chord,
        end_a: end(pa),
        end_b: end(pb),
        delta,
        area: region_area_of(light, ends[0], ends[1]),
        ends,
    })
}
