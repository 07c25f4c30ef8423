//! Umbra and penumbra volumes of a caster, as one indexed triangle mesh tagged by kind.
//!
//! - **Umbra volume**: a quad per umbra-silhouette edge, extruded away from its `p_u`, plus the
//!   silhouette faces (Jakobsen et al. 2004, §3.3; without them the D-buffer has holes). Umbra quads are
//!   oriented with their normal *away* from the light centre `c`: every umbra quad lies on a plane
//!   tangent to the disk with the disk (and `c`) on its inner side, so a ray from `c` can only
//!   *leave* the umbra through it. Adjacent quads cross at convex corners and beyond the apex of a
//!   closing umbra; they are not trimmed here. The D-buffer rule resolves that: per caster, the
//!   *nearest* umbra exit along the ray is the boundary (see [`super::twin`]).
//! - **Penumbra volume**: a quad per penumbra-silhouette edge, extruded away from its `p_p`,
//!   oriented with its normal *toward* `c` (a ray from `c` enters the penumbra through it).
//! - **Fans** close both surfaces: at every vertex shared by two quads of one volume, triangles
//!   from the vertex extruded away from rim points interpolated along the shorter disk arc between
//!   the two edges' extrusion points (see `Fans::close` for why every such vertex gets one).
//!
//! Each vertex carries the silhouette edge and the extrusion point it came from, so the light pass
//! (and [`VolumeVertex::edge_plane_distance`], its CPU twin) can evaluate eq. (2) per fragment.

use glam::Vec3;

use super::adjacency::CasterMesh;
use super::classify::{classify, FaceClass};
use super::silhouette::{count_silhouettes, extrusion_points, find_silhouettes, SilhouetteEdge};
pub use crate::budget::MAX_VOLUME_TRIANGLES;

mod fans;
use crate::scene::{AreaLight, Outline, Scene};
use fans::{extrude_away, EdgeEnd, Fans};

/// What a volume triangle is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VolumeKind {
    UmbraQuad,
    /// A silhouette face of category A, rendered as part of the umbra volume.
    SilhouetteFaceA,
    /// A silhouette face of category B, rendered as part of the umbra volume.
    SilhouetteFaceB,
    /// Closes the umbra surface between two umbra quads at a shared vertex.
    UmbraFan,
    PenumbraQuad,
    PenumbraFan,
}

impl VolumeKind {
    pub fn is_umbra(self) -> bool {
        matches!(
            self,
            VolumeKind::UmbraQuad
                | VolumeKind::UmbraFan
                | VolumeKind::SilhouetteFaceA
                | VolumeKind::SilhouetteFaceB
        )
    }

    pub fn is_silhouette_face(self) -> bool {
        matches!(
            self,
            VolumeKind::SilhouetteFaceA | VolumeKind::SilhouetteFaceB
        )
    }

    /// Small integer code, the same one the GPU uses.
    pub fn code(self) -> u32 {
        match self {
            VolumeKind::UmbraQuad => 0,
            VolumeKind::SilhouetteFaceA => 1,
            VolumeKind::SilhouetteFaceB => 2,
            VolumeKind::PenumbraQuad => 3,
            VolumeKind::PenumbraFan => 4,
            VolumeKind::UmbraFan => 5,
        }
    }
}

/// A volume vertex: its position and, constant over its triangle, where it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeVertex {
    pub position: Vec3,
    pub kind: VolumeKind,
    /// The silhouette edge the triangle was extruded from (both ends equal for a fan: its apex;
    /// for a silhouette face, its first vertex).
    pub edge: [Vec3; 2],
    /// The rim point it was extruded away from (`p_u`, `p_p` or a fan rim point).
    pub extrusion: Vec3,
}

impl VolumeVertex {
    /// `|cx_s|`: the distance along the ray from `c` (unit direction `dir`) to the plane through
    /// the silhouette edge parallel to the disk — eq. (2) as its definition in words has it (docs/method/dbuffer.md). The
    /// edge point used is the one the fragment was extruded from (on the line from the extrusion
    /// point through the fragment), so it is exact per fragment even for edges that are not
    /// parallel to the disk. On a silhouette face the face is its own edge: `|cx_s| = |cx|`.
    ///
    /// Note: the formula printed in Jakobsen et al. 2004,
    /// `(dir(c,x)·n)/(dir(c,e)·n)·dist(c,e)`, is this distance with the ratio inverted; the two
    /// agree only where `dir(c,x)·n = dir(c,e)·n`.
    pub fn edge_plane_distance(&self, hit: Vec3, dir: Vec3, light: &AreaLight) -> f32 {
        let along = dir.dot(light.normal);
        if self.kind.is_silhouette_face() {
            return (hit - light.center).length();
        }
        if along.is_nan() || along <= 0.0 {
            return f32::INFINITY;
        }
        let e = closest_point_on_line(self.edge[0], self.edge[1], self.extrusion, hit);
        (e - light.center).dot(light.normal) / along
    }
}

/// The point of the line `a b` closest to the line `p q` (`a` when the two are parallel or `a = b`).
pub fn closest_point_on_line(a: Vec3, b: Vec3, p: Vec3, q: Vec3) -> Vec3 {
    let (d1, d2, w0) = (b - a, q - p, a - p);
    let (aa, bb, cc) = (d1.dot(d1), d1.dot(d2), d2.dot(d2));
    let (dd, ee) = (d1.dot(w0), d2.dot(w0));
    let den = aa * cc - bb * bb;
    if den.is_nan() || den <= 1e-12 * aa * cc {
        return a;
    }
    a + d1 * ((bb * ee - cc * dd) / den)
}

/// An indexed triangle mesh of volume geometry.
#[derive(Clone, Debug, Default)]
pub struct VolumeMesh {
    pub vertices: Vec<VolumeVertex>,
    pub indices: Vec<u32>,
    /// The silhouette corner each closing fan was made at, in the order the fans were pushed
    /// (their triangles are consecutive): what V exact needs where a fan wins ([`FanCorner`]).
    pub corners: Vec<FanCorner>,
}

/// A closing fan's silhouette corner: the apex and the far ends of its two silhouette edges,
/// the normals of each edge's faces, and the fan's triangles `first .. first + count`. Seen from
/// a point behind the fan the caster's corner covers the light where it lies behind both planes
/// through the point and an edge (on each plane's side that holds the other edge): a wedge,
/// whose area grows with the square of the depth, where one chord's strip grows linearly.
///
/// `exact`: whether V exact may be taken from this corner at all (the camera pass still decides
/// per point, [`super::wedges::DiskFrame::corner_visibility`]). It is, where the corner seen
/// from behind its apex is convex and the whole caster lies inside its wedge (every vertex, for
/// a caster that does not bound a convex solid; at most [`CORNER_CHECK_VERTICES`] of them): the
/// wedge is then all of the caster that point sees near the light. A reflex corner, one whose
/// sides are unclear, a caster reaching past the corner's edges (an L's other leg) or one of more
/// vertices keeps the chord.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FanCorner {
    pub first: u32,
    pub count: u32,
    pub apex: Vec3,
    pub ends: [Vec3; 2],
    /// Each edge's two faces' unit normals; the second is zero on an open boundary edge.
    pub normals: [[Vec3; 2]; 2],
    /// The two edges' extrusion points on the light's boundary, between which the fan runs.
    pub supports: [Vec3; 2],
    pub exact: bool,
}

/// The most vertices of a caster that does not bound a convex solid whose corners are checked
/// for [`FanCorner::exact`] (every vertex against every corner's wedge); a larger one keeps the
/// chord at every corner.
pub const CORNER_CHECK_VERTICES: usize = 4096;

impl VolumeMesh {
    /// The corner of the fan triangle `i` belongs to, if it is a fan's.
    pub fn corner_of(&self, i: usize) -> Option<&FanCorner> {
        self.corner_index(i).map(|k| &self.corners[k])
    }

    /// The index in [`Self::corners`] of the fan triangle `i` belongs to, if it is a fan's.
    pub fn corner_index(&self, i: usize) -> Option<usize> {
        let i = i as u32;
        let k = self
            .corners
            .partition_point(|c| c.first <= i)
            .checked_sub(1)?;
        let c = &self.corners[k];
        (i < c.first + c.count).then_some(k)
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Triangle `i`: its corners and its first vertex (which carries the triangle's attributes).
    pub fn triangle(&self, i: usize) -> ([Vec3; 3], &VolumeVertex) {
        let k = &self.indices[3 * i..3 * i + 3];
        let v = |j: usize| self.vertices[k[j] as usize].position;
        ([v(0), v(1), v(2)], &self.vertices[k[0] as usize])
    }

    pub fn count(&self, pred: impl Fn(VolumeKind) -> bool) -> usize {
        (0..self.triangle_count())
            .filter(|&i| pred(self.triangle(i).1.kind))
            .count()
    }

    /// Append a polygon given as a fan around its first corner, wound so that its normal points
    /// toward `c` (`toward_c`) or away from it.
    fn push_polygon(&mut self, corners: &[Vec3], template: VolumeVertex, c: Vec3, toward_c: bool) {
        if corners.len() < 3 {
            return;
        }
        let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        let flip = (normal.dot(c - corners[0]) > 0.0) != toward_c;
        // Past what was reserved (the fans), grow by an eighth, not by doubling: a volume of
        // millions of triangles must not hold twice its size for a few fan triangles more.
        let spare = self.vertices.capacity() - self.vertices.len();
        if spare < corners.len() {
            let more = corners.len().max(self.vertices.len() / 8);
            self.vertices.reserve_exact(more);
            self.indices.reserve_exact(3 * more);
        }
        let base = self.vertices.len() as u32;
        self.vertices
            .extend(corners.iter().map(|&position| VolumeVertex {
                position,
                ..template
            }));
        for k in 1..corners.len() as u32 - 1 {
            if flip {
                self.indices.extend([base, base + k + 1, base + k]);
            } else {
                self.indices.extend([base, base + k, base + k + 1]);
            }
        }
    }
}

/// How far volumes are extruded, and how finely fans follow the disk rim.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeParams {
    /// Distance the far end of every extruded vertex lies beyond it.
    pub far: f32,
    /// Largest angle of the disk arc one fan triangle covers, in degrees.
    pub fan_step_deg: f32,
    /// Classify faces against the light centre alone (a point light), then extrude those
    /// silhouettes over the whole disk: the penumbra-wedge approximation Jakobsen et al. 2004, Fig. 1
    /// criticises (method `dbuffer-center`). Off, faces are classified against the disk.
    pub center_silhouettes: bool,
}

impl Default for VolumeParams {
    fn default() -> Self {
        Self {
            far: 1000.0,
            fan_step_deg: 11.25,
            center_silhouettes: false,
        }
    }
}

impl VolumeParams {
    /// Extrude well beyond everything in the scene.
    pub fn for_scene(scene: &Scene) -> Self {
        let mut lo = scene.light.center() - Vec3::splat(scene.light.half_extent());
        let mut hi = scene.light.center() + Vec3::splat(scene.light.half_extent());
        for o in &scene.objects {
            if let Some((a, b)) = o.mesh.bounds() {
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
        let size = (hi - lo).length();
        Self {
            far: if size.is_finite() {
                (size * 20.0).max(10.0)
            } else {
                1000.0
            },
            ..Self::default()
        }
    }
}

/// Counts for the stats panel and `meta.json`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GeometryStats {
    pub triangles: usize,
    pub all_front: usize,
    pub none_front: usize,
    pub silhouette_a: usize,
    pub silhouette_b: usize,
    pub umbra_edges: usize,
    pub penumbra_edges: usize,
    /// Penumbra fans.
    pub fans: usize,
    /// Umbra fans.
    pub umbra_fans: usize,
    pub umbra_triangles: usize,
    pub penumbra_triangles: usize,
    /// Silhouette edges whose line meets the disk: no tangent plane, no volume.
    pub unextruded_edges: usize,
}

impl std::ops::AddAssign for GeometryStats {
    fn add_assign(&mut self, o: Self) {
        self.triangles += o.triangles;
        self.all_front += o.all_front;
        self.none_front += o.none_front;
        self.silhouette_a += o.silhouette_a;
        self.silhouette_b += o.silhouette_b;
        self.umbra_edges += o.umbra_edges;
        self.penumbra_edges += o.penumbra_edges;
        self.fans += o.fans;
        self.umbra_fans += o.umbra_fans;
        self.umbra_triangles += o.umbra_triangles;
        self.penumbra_triangles += o.penumbra_triangles;
        self.unextruded_edges += o.unextruded_edges;
    }
}

/// Everything the geometry stage computes for one caster and one light.
#[derive(Clone, Debug, Default)]
pub struct CasterGeometry {
    pub name: String,
    /// One class per face of the [`CasterMesh`].
    pub classes: Vec<FaceClass>,
    pub silhouettes: Vec<SilhouetteEdge>,
    pub volumes: VolumeMesh,
    pub stats: GeometryStats,
    pub warnings: Vec<String>,
}

/// Classify, find silhouettes and build both volumes of one caster, within the whole scene's
/// budget of volume triangles ([`MAX_VOLUME_TRIANGLES`]).
pub fn build_caster(mesh: &CasterMesh, light: &AreaLight, params: &VolumeParams) -> CasterGeometry {
    build_caster_within(mesh, light, params, MAX_VOLUME_TRIANGLES as usize)
}

/// Like [`build_caster`] with at most `max_triangles` volume triangles. Their number is known
/// after classification but before any is made (silhouette faces, and two per silhouette edge,
/// plus the fans, counted as they are made): a caster whose volumes would pass the limit gets
/// none (it casts no shadow) and a warning naming the budget.
pub fn build_caster_within(
    mesh: &CasterMesh,
    light: &AreaLight,
    params: &VolumeParams,
    max_triangles: usize,
) -> CasterGeometry {
    let classes = if params.center_silhouettes {
        classify(
            mesh,
            &AreaLight {
                radius: 0.0,
                outline: Outline::Disk,
                ..*light
            },
        )
    } else {
        classify(mesh, light)
    };
    let c = light.center;
    let mut volumes = VolumeMesh::default();
    let mut stats = GeometryStats {
        triangles: mesh.faces.len(),
        ..GeometryStats::default()
    };
    for class in &classes {
        match class {
            FaceClass::AllFront => stats.all_front += 1,
            FaceClass::NoneFront => stats.none_front += 1,
            FaceClass::SilhouetteA => stats.silhouette_a += 1,
            FaceClass::SilhouetteB => stats.silhouette_b += 1,
        }
    }
    let mut warnings: Vec<String> = mesh.report.warning(&mesh.name).into_iter().collect();
    // What the volumes cost before they are made: every silhouette face, two triangles per
    // extruded silhouette edge, then the fans.
    let (umbra_edges, penumbra_edges) = count_silhouettes(mesh, &classes);
    let at_least = stats.silhouette_a + stats.silhouette_b + 2 * (umbra_edges + penumbra_edges);
    if at_least > max_triangles {
        stats.umbra_edges = umbra_edges;
        stats.penumbra_edges = penumbra_edges;
        warnings.push(over_volume_budget(&mesh.name, at_least, max_triangles));
        return CasterGeometry {
            name: mesh.name.clone(),
            classes,
            silhouettes: Vec::new(),
            volumes,
            stats,
            warnings,
        };
    }
    let silhouettes = find_silhouettes(mesh, &classes);
    // Room for what is known to come (the fans add a little): growing by doubling would hold
    // up to twice the volumes at the peak (1.4M triangles: 436 MB instead of 218).
    volumes.vertices.reserve(3 * at_least);
    volumes.indices.reserve(3 * at_least);

    let extrude = |v: Vec3, p: Vec3| extrude_away(v, p, params.far);
    // Both ends of every extruded edge, for the fans.
    let mut umbra_ends: Vec<EdgeEnd> = Vec::new();
    let mut penumbra_ends: Vec<EdgeEnd> = Vec::new();
    for s in &silhouettes {
        stats.umbra_edges += usize::from(s.umbra);
        stats.penumbra_edges += usize::from(s.penumbra);
        let Some(points) = extrusion_points(s.v[0], s.v[1], s.caster_side, light) else {
            stats.unextruded_edges += 1;
            continue;
        };
        let [a, b] = s.v;
        let volumes_of_edge = [
            (
                s.umbra,
                VolumeKind::UmbraQuad,
                points.umbra,
                &mut umbra_ends,
            ),
            (
                s.penumbra,
                VolumeKind::PenumbraQuad,
                points.penumbra,
                &mut penumbra_ends,
            ),
        ];
        for (on, kind, p, ends) in volumes_of_edge {
            if !on {
                continue;
            }
            let template = VolumeVertex {
                position: a,
                kind,
                edge: s.v,
                extrusion: p,
            };
            let umbra = kind.is_umbra();
            volumes.push_polygon(&[a, b, extrude(b, p), extrude(a, p)], template, c, !umbra);
            let inside = if umbra {
                FaceClass::NoneFront
            } else {
                FaceClass::AllFront
            };
            ends.extend(EdgeEnd::both(mesh, &classes, s.edge, inside, p));
        }
    }

    // Close both surfaces at the vertices where two quads of one volume meet.
    let fans = Fans {
        mesh,
        light,
        params,
    };
    // The silhouette faces come last; the fans may use what they leave of the budget.
    let fan_limit = max_triangles - (stats.silhouette_a + stats.silhouette_b);
    let penumbra_fans = fans.close(
        &mut volumes,
        &mut penumbra_ends,
        VolumeKind::PenumbraFan,
        fan_limit,
    );
    let umbra_fans = fans.close(
        &mut volumes,
        &mut umbra_ends,
        VolumeKind::UmbraFan,
        fan_limit,
    );
    let (Some(penumbra_fans), Some(umbra_fans)) = (penumbra_fans, umbra_fans) else {
        let wanted = volumes.triangle_count() + stats.silhouette_a + stats.silhouette_b;
        stats.umbra_edges = umbra_edges;
        stats.penumbra_edges = penumbra_edges;
        warnings.push(over_volume_budget(&mesh.name, wanted, max_triangles));
        return CasterGeometry {
            name: mesh.name.clone(),
            classes,
            silhouettes,
            volumes: VolumeMesh::default(),
            stats,
            warnings,
        };
    };
    stats.fans = penumbra_fans;
    stats.umbra_fans = umbra_fans;

    for (face, class) in mesh.faces.iter().zip(&classes) {
        let kind = match class {
            FaceClass::SilhouetteA => VolumeKind::SilhouetteFaceA,
            FaceClass::SilhouetteB => VolumeKind::SilhouetteFaceB,
            _ => continue,
        };
        let corners = face.v.map(|k| mesh.position(k));
        let base = volumes.vertices.len() as u32;
        volumes
            .vertices
            .extend(corners.iter().map(|&position| VolumeVertex {
                position,
                kind,
                edge: [corners[0], corners[0]],
                extrusion: c,
            }));
        volumes.indices.extend([base, base + 1, base + 2]);
    }

    stats.umbra_triangles = volumes.count(VolumeKind::is_umbra);
    stats.penumbra_triangles = volumes.triangle_count() - stats.umbra_triangles;

    let behind = mesh
        .positions
        .iter()
        .filter(|&&p| {
            let h = light.height_of(p);
            h.is_nan() || h <= 0.0
        })
        .count();
    if behind > 0 {
        warnings.push(format!(
            "caster '{}' reaches the light plane ({behind} vertices on or behind it): its shadow \
             volumes are incomplete",
            mesh.name
        ));
    }
    if stats.unextruded_edges > 0 {
        warnings.push(format!(
            "caster '{}': {} silhouette edges point into the light disk and get no volume",
            mesh.name, stats.unextruded_edges
        ));
    }

    CasterGeometry {
        name: mesh.name.clone(),
        classes,
        silhouettes,
        volumes,
        stats,
        warnings,
    }
}

/// The warning for a caster whose volumes would have more than `max` triangles.
fn over_volume_budget(name: &str, at_least: usize, max: usize) -> String {
    format!(
        "caster '{name}': its shadow volumes would have {at_least} or more triangles, over the \
         {max} the scene's budget leaves it ({MAX_VOLUME_TRIANGLES} volume triangles per scene, \
         MAX_VOLUME_TRIANGLES): it casts no shadow"
    )
}

#[cfg(test)]
mod tests;
