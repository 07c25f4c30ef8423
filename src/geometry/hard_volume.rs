//! Crow's shadow volume of a caster from a point light (the light's centre): the hard shadow the
//! stencil methods (`shadow-volume`, and the hard part of penumbra wedges) count on the GPU.
//!
//! The volume of one face lit by the point `p` is the region behind it as seen from `p`: the
//! face itself (the *front cap*), the face projected to infinity (the *back cap*) and one
//! semi-infinite quad per edge (the *sides*). A caster's volume is the sum of its faces'
//! volumes: a point's count is the number of faces between it and `p`. Where two lit faces share
//! an edge their side quads cancel, so only the silhouette edges keep a side: this is the
//! silhouette rule of [`super::silhouette::find_silhouettes`] with the point classes (radius 0),
//! and a test checks the two agree.
//!
//! Which faces make caps ([`Caps`]):
//! - **lit** (Crow 1977): only faces whose front faces `p`. Exact for closed, consistently
//!   wound meshes: a ray that crosses the solid crosses as many front faces toward `p` as faces
//!   turned away;
//! - **dark**: only the faces turned away from `p`, reversed. The same count as the lit caps for
//!   a closed mesh at every point outside the solid; its caps lie on the caster's unlit side, so
//!   the lit surfaces the camera sees are never on a volume's boundary (no depth fight between a
//!   cap and the surface it copies; Everitt and Kilgard 2002 note that either set closes the
//!   volume). What closed casters get;
//! - **both** (two-sided): every face, the faces turned away from `p` reversed. The count is
//!   then the number of faces between the point and the light, which is exact for any triangle
//!   soup, open sheets and inconsistently wound meshes included (an open mesh is a two-sided
//!   sheet everywhere in this house). Bergeron (1986) generalised Crow's volumes to open models
//!   in this way; it costs about twice the fill.
//!
//! Nothing here depends on the GPU: [`HardVolume::triangles`] gives the homogeneous vertices
//! (w = 0 at infinity) that `render::passes::stencil_volumes` draws with the z-fail stencil test,
//! and [`HardVolume::count`] is its CPU twin (how many volumes hold a point).

use glam::{Vec3, Vec4};

use super::adjacency::{CasterMesh, NO_FACE};
use super::classify::{classify, FaceClass};
use super::PreparedCasters;
use crate::scene::{AreaLight, Light, LineLight, Outline};

/// Which faces of a caster make shadow volumes (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Caps {
    /// Faces whose front faces the light (Crow's closed-mesh assumption).
    Lit,
    /// Faces turned away from the light, reversed (closed meshes: the same count, robust).
    Dark,
    /// Every face (exact for open and badly wound meshes, about twice the fill).
    Both,
}

/// What an open mesh gets: Crow's one-sided volumes or the two-sided count.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum OpenMeshes {
    OneSided,
    TwoSided,
}

impl Caps {
    /// What a caster gets: dark caps for a closed, consistently wound 2-manifold; for any other
    /// mesh, lit caps (one-sided) or both (two-sided) as `open` says.
    pub fn for_mesh(mesh: &CasterMesh, open: OpenMeshes) -> Caps {
        match (mesh.report.is_closed_manifold(), open) {
            (true, _) => Caps::Dark,
            (false, OpenMeshes::OneSided) => Caps::Lit,
            (false, OpenMeshes::TwoSided) => Caps::Both,
        }
    }
}

/// The closed shadow volume of one caster from a point light.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HardVolume {
    /// The light point every side and the back cap are extruded away from.
    pub light: Vec3,
    /// Cap triangles, each wound with its normal toward the light (front cap as it is; its
    /// reversed copy at infinity is the back cap).
    pub caps: Vec<[Vec3; 3]>,
    /// Side edges `e0 → e1` in the direction the caps walk them, repeated once per unit of
    /// multiplicity.
    pub sides: Vec<[Vec3; 2]>,
}

/// The classes of a caster's faces against the point `p`: [`FaceClass::AllFront`] where the
/// face's front faces `p`, [`FaceClass::NoneFront`] elsewhere (a face whose plane holds `p`
/// included), never a silhouette class. `classify` with a zero-radius disk.
pub fn point_classes(mesh: &CasterMesh, p: Vec3) -> Vec<FaceClass> {
    classify(mesh, &point_light(p))
}

/// The zero-radius disk at `p`: a point light for the disk's geometry functions and the oracle.
pub fn point_light(p: Vec3) -> AreaLight {
    AreaLight {
        center: p,
        normal: Vec3::NEG_Y,
        radius: 0.0,
        intensity: 1.0,
        outline: Outline::Disk,
    }
}

/// The light's centre as a point light: a disk with radius 0, its plane kept (the oracle's
/// one-sided rule still holds), or a line's midpoint as a segment of length 0 (emitting all
/// around, as the line does). What `reference-hard` casts its rays to.
pub fn centre_light(light: &Light) -> Light {
    match *light {
        Light::Area(d) => Light::Area(AreaLight {
            radius: 0.0,
            outline: Outline::Disk,
            ..d
        }),
        Light::Line(l) => {
            let m = l.midpoint();
            Light::Line(LineLight { a: m, b: m, ..l })
        }
    }
}

/// Whether face `f` walks edge `a → b` in that direction (else `b → a`).
fn walks(mesh: &CasterMesh, f: u32, a: u32, b: u32) -> bool {
    let v = mesh.faces[f as usize].v;
    (0..3).any(|k| v[k] == a && v[(k + 1) % 3] == b)
}

/// The shadow volume of `mesh` from the point `light` its `classes` were taken against (see
/// [`point_classes`]), closed by `caps`.
pub fn hard_volume(
    mesh: &CasterMesh,
    classes: &[FaceClass],
    light: Vec3,
    caps: Caps,
) -> HardVolume {
    let lit = |f: u32| classes.get(f as usize) == Some(&FaceClass::AllFront);
    let (use_lit, use_dark) = match caps {
        Caps::Lit => (true, false),
        Caps::Dark => (false, true),
        Caps::Both => (true, true),
    };
    let mut out = HardVolume {
        light,
        ..HardVolume::default()
    };
    for (f, face) in mesh.faces.iter().enumerate() {
        let [a, b, c] = face.v.map(|k| mesh.position(k));
        if lit(f as u32) {
            if use_lit {
                out.caps.push([a, b, c]);
            }
        } else if use_dark {
            out.caps.push([a, c, b]);
        }
    }
    for edge in &mesh.edges {
        let mut m = 0i32;
        for f in edge.faces {
            if f == NO_FACE {
                continue;
            }
            let dir = if walks(mesh, f, edge.v[0], edge.v[1]) {
                1
            } else {
                -1
            };
            if lit(f) {
                m += if use_lit { dir } else { 0 };
            } else if use_dark {
                m -= dir;
            }
        }
        let (e0, e1) = (mesh.position(edge.v[0]), mesh.position(edge.v[1]));
        let side = if m > 0 { [e0, e1] } else { [e1, e0] };
        for _ in 0..m.unsigned_abs() {
            out.sides.push(side);
        }
    }
    out
}

/// The volumes of every caster of a scene from the point `light`: each caster's classes and
/// volume, closed as [`Caps::for_mesh`] says.
pub fn scene_volumes(
    casters: &PreparedCasters,
    light: Vec3,
    open: OpenMeshes,
) -> Vec<(Vec<FaceClass>, Caps, HardVolume)> {
    casters
        .meshes
        .iter()
        .map(|m| {
            let classes = point_classes(m, light);
            let caps = Caps::for_mesh(m, open);
            let volume = hard_volume(m, &classes, light, caps);
            (classes, caps, volume)
        })
        .collect()
}

impl HardVolume {
    /// Triangles of the closed volume as homogeneous points (w = 1 finite, w = 0 a direction
    /// from the light), three per triangle, every normal pointing out of the volume (so a
    /// counter-clockwise triangle on screen is seen from outside). Every finite vertex is pushed
    /// `push` times its distance from the light further away from it: the front cap then lies
    /// just behind the lit faces, so their own pixels are never counted as inside.
    pub fn triangles(&self, push: f32) -> Vec<Vec4> {
        let p = self.light;
        let finite = |v: Vec3| (v + (v - p) * push).extend(1.0);
        let infinite = |v: Vec3| (v - p).extend(0.0);
        let mut out = Vec::with_capacity(6 * (self.caps.len() + self.sides.len()));
        for &[a, b, c] in &self.caps {
            out.extend([finite(a), finite(b), finite(c)]);
            out.extend([infinite(a), infinite(c), infinite(b)]);
        }
        for &[e0, e1] in &self.sides {
            out.extend([finite(e1), finite(e0), infinite(e0)]);
            out.extend([finite(e1), infinite(e0), infinite(e1)]);
        }
        out
    }

    /// Triangles of the volume: caps and sides.
    pub fn triangle_count(&self) -> usize {
        2 * (self.caps.len() + self.sides.len())
    }

    /// How many of the faces' volumes hold `x` (the stencil count the GPU makes; 0: lit), the
    /// CPU twin of the z-fail count for tests: the light point itself is outside every volume
    /// (each starts at its face), so the count at `x` is the signed number of volume faces the
    /// segment from `x` to the light leaves through (+1) or enters through (−1).
    pub fn count(&self, x: Vec3) -> i32 {
        let p = self.light;
        let mut n = 0;
        for &[a, b, c] in &self.caps {
            let normal = (b - a).cross(c - a);
            n += crossing(x, p, a, normal, |q| {
                [(a, b), (b, c), (c, a)]
                    .iter()
                    .all(|&(u, v)| (v - u).cross(q - u).dot(normal) >= 0.0)
            });
        }
        for &[e0, e1] in &self.sides {
            // The quad's outward normal as `triangles` winds it, (e1, e0, e0 + (e0 − p)).
            let normal = (e0 - e1).cross(e0 - p);
            n += crossing(x, p, e0, normal, |q| beyond_edge(p, e0, e1, q));
        }
        n
    }
}

/// +1 when the segment from `x` to `p` leaves through the plane through `on` with outward
/// `normal` at a point `inside` accepts, −1 when it enters there, else 0.
fn crossing(x: Vec3, p: Vec3, on: Vec3, normal: Vec3, inside: impl Fn(Vec3) -> bool) -> i32 {
    let dir = p - x;
    let den = normal.dot(dir);
    if den == 0.0 || !den.is_finite() {
        return 0;
    }
    let t = normal.dot(on - x) / den;
    if !(t > 0.0 && t < 1.0 && inside(x + dir * t)) {
        return 0;
    }
    if den > 0.0 {
        1
    } else {
        -1
    }
}

/// Whether `q`, in the plane through `p`, `e0`, `e1`, lies on the side quad of the edge: between
/// the rays from `p` through `e0` and `e1`, beyond the edge.
fn beyond_edge(p: Vec3, e0: Vec3, e1: Vec3, q: Vec3) -> bool {
    // q = p + α (e0 − p) + β (e1 − p) with α, β ≥ 0 and α + β ≥ 1.
    let (u0, u1, w) = (e0 - p, e1 - p, q - p);
    let g = [u0.dot(u0), u0.dot(u1), u1.dot(u1)];
    let det = g[0] * g[2] - g[1] * g[1];
    if det <= 0.0 || !det.is_finite() {
        return false;
    }
    let (r0, r1) = (w.dot(u0), w.dot(u1));
    let alpha = (r0 * g[2] - r1 * g[1]) / det;
    let beta = (r1 * g[0] - r0 * g[1]) / det;
    alpha >= 0.0 && beta >= 0.0 && alpha + beta >= 1.0
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;
    use crate::geometry::silhouette::find_silhouettes;
    use crate::scene::{shapes, Mesh};

    fn cube() -> Mesh {
        shapes::cube()
    }

    /// Directed edges of the triangles, with points at infinity as (direction, 0), counted.
    fn directed_edges(tris: &[Vec4]) -> HashMap<[[u32; 4]; 2], i32> {
        let key = |v: Vec4| v.to_array().map(|c| (c + 0.0).to_bits());
        let mut m = HashMap::new();
        for t in tris.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *m.entry([key(a), key(b)]).or_insert(0) += 1;
            }
        }
        m
    }

    fn assert_closed(tris: &[Vec4]) {
        let m = directed_edges(tris);
        for (&[a, b], &n) in &m {
            assert_eq!(
                m.get(&[b, a]).copied().unwrap_or(0),
                n,
                "edge walked {n}× one way"
            );
        }
    }

    /// Signed volume of the volume cut at `far` along each direction: positive when every
    /// normal points outward.
    fn signed_volume(tris: &[Vec4], p: Vec3, far: f32) -> f32 {
        let pt = |v: Vec4| {
            if v.w == 0.0 {
                p + v.truncate() * far
            } else {
                v.truncate()
            }
        };
        tris.chunks_exact(3)
            .map(|t| pt(t[0]).dot(pt(t[1]).cross(pt(t[2]))) / 6.0)
            .sum()
    }

    #[test]
    fn closed_caster_volume_is_closed_outward_and_its_sides_are_the_silhouette() {
        let p = Vec3::new(0.3, 4.0, 0.2);
        for mesh in [cube(), shapes::sphere(16, 8)] {
            let m = CasterMesh::new("c", &mesh);
            assert!(m.report.is_closed_manifold());
            let classes = point_classes(&m, p);
            let v = hard_volume(&m, &classes, p, Caps::for_mesh(&m, OpenMeshes::TwoSided));
            assert_eq!(Caps::for_mesh(&m, OpenMeshes::OneSided), Caps::Dark);
            let lit = hard_volume(&m, &classes, p, Caps::Lit);
            assert_closed(&lit.triangles(0.0));
            assert!(signed_volume(&lit.triangles(0.0), p, 50.0) > 0.0);
            let mut lit_sides = lit.sides.clone();
            let mut dark_sides = v.sides.clone();
            let bits = |e: &[Vec3; 2]| e.map(|q| q.to_array().map(f32::to_bits));
            lit_sides.sort_by_key(bits);
            dark_sides.sort_by_key(bits);
            assert_eq!(
                lit_sides, dark_sides,
                "lit and dark caps share the silhouette"
            );
            let tris = v.triangles(0.0);
            assert_closed(&tris);
            assert!(signed_volume(&tris, p, 50.0) > 0.0);
            // The sides are exactly the silhouette edges of the point classes.
            let sil = find_silhouettes(&m, &classes);
            assert!(sil.iter().all(|s| s.umbra && s.penumbra));
            let mut a: Vec<_> = sil
                .iter()
                .map(|s| {
                    let lit =
                        classes[m.edges[s.edge as usize].faces[0] as usize] == FaceClass::AllFront;
                    let e = if lit { s.v } else { [s.v[1], s.v[0]] };
                    e.map(|q| q.to_array().map(f32::to_bits))
                })
                .collect();
            let mut b: Vec<_> = v
                .sides
                .iter()
                .map(|e| e.map(|q| q.to_array().map(f32::to_bits)))
                .collect();
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b);
            assert!(!b.is_empty());
        }
    }

    #[test]
    fn counts_match_the_point_light_oracle_for_a_closed_caster() {
        let p = Vec3::new(0.2, 3.0, -0.1);
        let m = CasterMesh::new("sphere", &shapes::sphere(12, 6));
        let v = hard_volume(&m, &point_classes(&m, p), p, Caps::Dark);
        let lit = hard_volume(&m, &point_classes(&m, p), p, Caps::Lit);
        let tris: Vec<[Vec3; 3]> = (0..m.faces.len())
            .map(|f| m.faces[f].v.map(|k| m.position(k)))
            .collect();
        let oracle = crate::geometry::oracle::Oracle::new(tris, point_light(p), 1);
        let mut shadowed = 0;
        for i in 0..400 {
            let x = Vec3::new(
                -2.0 + (i % 20) as f32 * 0.21,
                -1.5,
                -2.0 + (i / 20) as f32 * 0.21,
            );
            let hidden = oracle.visibility(x) < 0.5;
            assert_eq!(v.count(x), i32::from(hidden), "dark caps at {x}");
            assert_eq!(lit.count(x), i32::from(hidden), "lit caps at {x}");
            shadowed += usize::from(hidden);
        }
        assert!(shadowed > 10, "the test sees the shadow: {shadowed}");
    }

    #[test]
    fn open_sheet_two_sided_casts_and_one_sided_does_not() {
        // A square at y = 1 whose front faces down (away from a light above).
        let sheet = Mesh::new(
            vec![
                Vec3::new(-1.0, 1.0, -1.0),
                Vec3::new(1.0, 1.0, -1.0),
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(-1.0, 1.0, 1.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        let m = CasterMesh::new("sheet", &sheet);
        assert!(!m.report.is_closed_manifold());
        let p = Vec3::new(0.0, 4.0, 0.0);
        let classes = point_classes(&m, p);
        assert!(classes.iter().all(|c| *c == FaceClass::NoneFront));
        let two = hard_volume(&m, &classes, p, Caps::for_mesh(&m, OpenMeshes::TwoSided));
        let one = hard_volume(&m, &classes, p, Caps::for_mesh(&m, OpenMeshes::OneSided));
        assert_eq!(Caps::for_mesh(&m, OpenMeshes::OneSided), Caps::Lit);
        // Two-sided: the four rim edges once each (the diagonal cancels), the caps reversed.
        assert_eq!(two.sides.len(), 4);
        assert_eq!(two.caps.len(), 2);
        assert_closed(&two.triangles(0.0));
        assert!(signed_volume(&two.triangles(0.0), p, 50.0) > 0.0);
        assert_eq!(two.count(Vec3::new(0.1, 0.0, 0.3)), 1);
        assert_eq!(two.count(Vec3::new(3.0, 0.0, 0.0)), 0);
        // One-sided: the sheet's back faces the light, so Crow's volume is empty.
        assert!(one.sides.is_empty() && one.caps.is_empty());
        assert_eq!(one.count(Vec3::new(0.1, 0.0, 0.3)), 0);
    }

    #[test]
    fn two_sided_counts_every_face_between_point_and_light() {
        // Two stacked closed cubes counted two-sided: a point below both is behind 4 faces.
        let p = Vec3::new(0.0, 6.0, 0.0);
        let mut mesh = cube();
        let n = mesh.positions.len() as u32;
        let upper = cube().transformed(&glam::Affine3A::from_translation(Vec3::new(0.0, 2.0, 0.0)));
        mesh.positions.extend(upper.positions);
        mesh.triangles
            .extend(upper.triangles.iter().map(|t| t.map(|k| k + n)));
        let m = CasterMesh::new("two cubes", &mesh);
        let classes = point_classes(&m, p);
        let one = hard_volume(&m, &classes, p, Caps::Lit);
        let dark = hard_volume(&m, &classes, p, Caps::Dark);
        let two = hard_volume(&m, &classes, p, Caps::Both);
        let below = Vec3::new(0.1, -3.0, 0.23);
        assert_eq!(one.count(below), 2);
        assert_eq!(dark.count(below), 2);
        assert_eq!(two.count(below), 4);
        assert_closed(&two.triangles(0.0));
    }
}
