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
use crate::scene::{AreaLight, Outline, Scene};

/// Largest group of silhouette edge ends at one vertex whose pairs are all compared (see
/// `Fans::pairs`).
const EXACT_PAIRING: usize = 64;
/// Neighbours around the rim each end of a larger group is compared with, on each side.
const PAIRING_WINDOW: usize = 16;

/// Most triangles of one fan: a half turn (a silhouette turns by less at a vertex) at the
/// finest step [`VolumeParams::fan_step_deg`] is meant to take (11.25° gives 16).
const MAX_FAN_TRIANGLES: usize = super::outline::MAX_ARC_POINTS;

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

/// `v` moved `far` further along the ray from the rim point `p` through it. Quads and fans both
/// extrude with this one function, so the end rays they share are bit-identical and the volume
/// surfaces stay closed (`tests/cpu/twin_builtins.rs` welds them by position).
fn extrude_away(v: Vec3, p: Vec3, far: f32) -> Vec3 {
    v + (v - p).normalize_or_zero() * far
}

/// One end of an extruded silhouette edge.
#[derive(Clone, Copy, Debug)]
struct EdgeEnd {
    /// Welded vertex.
    vertex: u32,
    edge: u32,
    /// The edge leaves this vertex when walked with the volume's inside face (none-front for the
    /// umbra, all-front for the penumbra) on its left.
    outgoing: bool,
    extrusion: Vec3,
}

impl EdgeEnd {
    fn both(
        mesh: &CasterMesh,
        classes: &[FaceClass],
        edge: u32,
        inside: FaceClass,
        extrusion: Vec3,
    ) -> [EdgeEnd; 2] {
        let e = &mesh.edges[edge as usize];
        // `e.v` is the direction the first face walks the edge (counter-clockwise).
        let forward = super::silhouette::edge_classes(e, classes).0 == inside;
        let (from, to) = if forward {
            (e.v[0], e.v[1])
        } else {
            (e.v[1], e.v[0])
        };
        [
            EdgeEnd {
                vertex: from,
                edge,
                outgoing: true,
                extrusion,
            },
            EdgeEnd {
                vertex: to,
                edge,
                outgoing: false,
                extrusion,
            },
        ]
    }
}

/// Closing fans at the vertices where quads of one volume meet.
struct Fans<'a> {
    mesh: &'a CasterMesh,
    light: &'a AreaLight,
    params: &'a VolumeParams,
}

impl Fans<'_> {
    /// At every vertex shared by extruded edges of `ends`, add a fan of `kind` between the quads of
    /// each pair of edges that meet there ([`Fans::pairs`]). Returns the number of fans.
    ///
    /// The fan's rays `v + s(v − q)`, for rim points `q` between the two extrusion points, join
    /// the two quads' end rays at `v`, so the surface is closed whether the quads leave a gap
    /// there (a convex corner of the penumbra silhouette, a reflex one of the umbra silhouette,
    /// or consecutive edges that are nearly collinear, where a gap opens *along* the chain) or
    /// cross. Where they cross, the fan lies outside the umbra or inside the penumbra, where the
    /// D-buffer rules (nearest umbra exit, nearest penumbra entry) never let it win. Deciding
    /// "gap or cross" by which side of the other quad's plane each far edge falls is unreliable
    /// for nearly collinear edges: it sees only the offset across the chain.
    ///
    /// Returns the number of fans, or `None` as soon as `volumes` would pass `limit` triangles.
    fn close(
        &self,
        volumes: &mut VolumeMesh,
        ends: &mut [EdgeEnd],
        kind: VolumeKind,
        limit: usize,
    ) -> Option<usize> {
        ends.sort_unstable_by_key(|e| (e.vertex, e.edge, e.outgoing));
        let mut count = 0;
        for group in ends.chunk_by(|x, y| x.vertex == y.vertex) {
            let apex = self.mesh.position(group[0].vertex);
            for (i, j) in self.pairs(group) {
                let before = volumes.triangle_count();
                if before + MAX_FAN_TRIANGLES > limit {
                    return None;
                }
                let turn = self.support_turn(apex, &group[i], &group[j]);
                self.push_fan(
                    volumes,
                    apex,
                    [group[i].extrusion, group[j].extrusion],
                    turn,
                    kind,
                );
                let made = volumes.triangle_count() - before;
                if made > 0 {
                    let ends = [self.far_end(&group[i]), self.far_end(&group[j])];
                    let behind = apex + (apex - 0.5 * (group[i].extrusion + group[j].extrusion));
                    let convex = self.corner_convexity(apex, [&group[i], &group[j]], ends, behind);
                    volumes.corners.push(FanCorner {
                        first: before as u32,
                        count: made as u32,
                        apex,
                        ends,
                        normals: [self.normals(&group[i]), self.normals(&group[j])],
                        supports: [group[i].extrusion, group[j].extrusion],
                        exact: convex == Some(true) && self.caster_in_wedge(apex, ends, behind),
                    });
                }
                count += usize::from(made > 0);
            }
        }
        Some(count)
    }

    /// Which edge ends at one vertex belong together. Two: each other. More (silhouette chains
    /// touching at a vertex): each chain arrives and leaves, so an incoming end pairs with an
    /// outgoing one, the closest on the disk rim first; ends left over (inconsistent winding)
    /// pair by distance alone.
    ///
    /// Every pair is a candidate in a group of up to [`EXACT_PAIRING`] ends. A larger group (the
    /// apex of a cone of thousands of segments, or rim vertices welded together) would make
    /// that quadratic in time and memory: there each end's candidates are its
    /// [`PAIRING_WINDOW`] nearest neighbours on each side around the rim (the extrusion points
    /// lie on the rim circle, so the nearest by angle are the nearest by distance).
    fn pairs(&self, group: &[EdgeEnd]) -> Vec<(usize, usize)> {
        if group.len() == 2 {
            return vec![(0, 1)];
        }
        let candidate = |i: usize, j: usize| {
            let mixed = group[i].outgoing != group[j].outgoing;
            let gap = group[i].extrusion.distance(group[j].extrusion);
            (!mixed, gap, i.min(j), i.max(j))
        };
        let mut candidates: Vec<(bool, f32, usize, usize)> = Vec::new();
        if group.len() <= EXACT_PAIRING {
            for i in 0..group.len() {
                for j in i + 1..group.len() {
                    candidates.push(candidate(i, j));
                }
            }
        } else {
            let (u, w) = self.light.basis();
            let c = self.light.center;
            let angle = |e: &EdgeEnd| (e.extrusion - c).dot(w).atan2((e.extrusion - c).dot(u));
            let mut around: Vec<usize> = (0..group.len()).collect();
            around.sort_by(|&a, &b| angle(&group[a]).total_cmp(&angle(&group[b])));
            for (k, &i) in around.iter().enumerate() {
                for d in 1..=PAIRING_WINDOW.min(group.len() - 1) {
                    candidates.push(candidate(i, around[(k + d) % around.len()]));
                }
            }
            candidates.sort_by_key(|&(_, _, i, j)| (i, j));
            candidates.dedup_by_key(|&mut (_, _, i, j)| (i, j));
        }
        candidates.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut used = vec![false; group.len()];
        let mut pairs = Vec::new();
        for (_, _, i, j) in candidates {
            if !used[i] && !used[j] {
                used[i] = true;
                used[j] = true;
                pairs.push((i, j));
            }
        }
        pairs
    }

    /// Whether the caster lies inside the wedge of the corner at `apex` seen from `from` (behind
    /// it), near the corner: for each edge, the side of the plane through `from` and the edge the
    /// caster is on (against its outward direction there, the sum of the edge's faces' normals),
    /// against the side the other edge's far end is on. `Some(false)`: a reflex corner; `None`:
    /// the two edges disagree, or a side is not defined.
    fn corner_convexity(
        &self,
        apex: Vec3,
        ends: [&EdgeEnd; 2],
        far: [Vec3; 2],
        from: Vec3,
    ) -> Option<bool> {
        let mut inside = [false; 2];
        for k in 0..2 {
            let n = (far[k] - apex).cross(from - apex);
            let other = n.dot(far[1 - k] - apex);
            let e = &self.mesh.edges[ends[k].edge as usize];
            let outward: Vec3 = e
                .faces
                .iter()
                .filter_map(|&f| self.mesh.faces.get(f as usize))
                .map(|f| f.normal)
                .sum();
            let caster = -n.dot(outward);
            if other.is_nan() || caster.is_nan() || other == 0.0 || caster == 0.0 {
                return None;
            }
            inside[k] = other.signum() == caster.signum();
        }
        (inside[0] == inside[1]).then_some(inside[0])
    }

    /// Whether every vertex of the caster lies inside the wedge of the convex corner at `apex`
    /// seen from `from` ([`FanCorner::exact`]): true for a caster bounding a convex solid, false
    /// for one of more than [`CORNER_CHECK_VERTICES`] vertices.
    fn caster_in_wedge(&self, apex: Vec3, far: [Vec3; 2], from: Vec3) -> bool {
        if self.mesh.convex {
            return true;
        }
        if self.mesh.positions.len() > CORNER_CHECK_VERTICES {
            return false;
        }
        let mut planes = [(Vec3::ZERO, 0.0f32); 2];
        for k in 0..2 {
            let n = (far[k] - apex).cross(from - apex).normalize_or_zero();
            let n = if n.dot(far[1 - k] - apex) < 0.0 {
                -n
            } else {
                n
            };
            planes[k] = (n, n.dot(apex));
        }
        let tol = 1e-4 * apex.distance(far[0]).max(apex.distance(far[1]));
        self.mesh
            .positions
            .iter()
            .all(|&p| planes.iter().all(|&(n, d)| n.dot(p) - d >= -tol))
    }

    /// The unit normals of the faces of an end's edge (the second zero on an open edge).
    fn normals(&self, end: &EdgeEnd) -> [Vec3; 2] {
        let e = &self.mesh.edges[end.edge as usize];
        e.faces.map(|f| {
            self.mesh
                .faces
                .get(f as usize)
                .map_or(Vec3::ZERO, |f| f.normal)
        })
    }

    /// The other vertex of the edge an end belongs to.
    fn far_end(&self, end: &EdgeEnd) -> Vec3 {
        let e = &self.mesh.edges[end.edge as usize];
        let other = if e.v[0] == end.vertex { e.v[1] } else { e.v[0] };
        self.mesh.position(other)
    }

    /// Which way round the light's boundary the supports move from one edge end's to the
    /// other's at `apex`: the sign of the turn from the first touching plane's outward direction
    /// in the light's plane to the second's, the short way (a silhouette turns by less than 180°
    /// at a vertex, and the touching point of a convex light moves the way its direction turns).
    /// 0 where a direction is not defined (the plane is parallel to the light's): the shorter
    /// way round then.
    fn support_turn(&self, apex: Vec3, a: &EdgeEnd, b: &EdgeEnd) -> f32 {
        let (u, w) = self.light.basis();
        let c = self.light.center;
        let outward = |end: &EdgeEnd| {
            let n = (self.far_end(end) - apex).cross(end.extrusion - apex);
            let m = glam::Vec2::new(n.dot(u), n.dot(w));
            // The light lies on the side away from m: the support maximises m · p.
            let to_center = glam::Vec2::new((c - end.extrusion).dot(u), (c - end.extrusion).dot(w));
            if m.dot(to_center) > 0.0 {
                -m
            } else {
                m
            }
        };
        let turn = outward(a).perp_dot(outward(b));
        if turn.is_finite() {
            turn.signum() * f32::from(turn != 0.0)
        } else {
            0.0
        }
    }

    /// The fan at `apex` between the quads of its two edges, from `p1` to `p2` round the
    /// light's boundary the way `turn` says ([`Self::support_turn`]; for a disk the shorter arc,
    /// which is that way).
    fn push_fan(
        &self,
        volumes: &mut VolumeMesh,
        apex: Vec3,
        [p1, p2]: [Vec3; 2],
        turn: f32,
        kind: VolumeKind,
    ) {
        if p1 == p2 {
            return;
        }
        let light = self.light;
        let c = light.center;
        let step = self.params.fan_step_deg.to_radians().max(1e-3);
        let mut rim = vec![p1];
        rim.extend(super::outline::boundary_between(light, p1, p2, turn, step));
        rim.push(p2);
        let n = rim.len() - 1;
        let rim = |k: usize| rim[k];
        let extrude = |q: Vec3| extrude_away(apex, q, self.params.far);
        for k in 0..n {
            let (q0, q1) = (rim(k), rim(k + 1));
            let template = VolumeVertex {
                position: apex,
                kind,
                edge: [apex, apex],
                extrusion: q0,
            };
            let corners = [apex, extrude(q0), extrude(q1)];
            volumes.push_polygon(&corners, template, c, !kind.is_umbra());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ray::intersect_triangle;
    use crate::scene::Mesh;

    fn cube(center: Vec3, half: f32) -> Mesh {
        let positions = (0..8)
            .map(|i| {
                center
                    + half
                        * Vec3::new(
                            if i & 1 == 0 { -1.0 } else { 1.0 },
                            if i & 2 == 0 { -1.0 } else { 1.0 },
                            if i & 4 == 0 { -1.0 } else { 1.0 },
                        )
            })
            .collect();
        let triangles = vec![
            [0, 1, 5],
            [0, 5, 4],
            [2, 6, 7],
            [2, 7, 3],
            [0, 4, 6],
            [0, 6, 2],
            [1, 3, 7],
            [1, 7, 5],
            [0, 2, 3],
            [0, 3, 1],
            [4, 5, 7],
            [4, 7, 6],
        ];
        Mesh::new(positions, triangles)
    }

    fn light(r: f32) -> AreaLight {
        AreaLight {
            center: Vec3::new(0.0, 4.0, 0.0),
            normal: Vec3::NEG_Y,
            radius: r,
            intensity: 1.0,
            outline: Outline::Disk,
        }
    }

    #[test]
    fn cube_volumes_are_oriented_and_closed_by_fans() {
        let mesh = CasterMesh::new("cube", &cube(Vec3::new(0.0, 1.5, 0.0), 0.5));
        let l = light(1.0);
        let g = build_caster(&mesh, &l, &VolumeParams::default());
        assert_eq!(g.stats.umbra_edges, 4);
        assert_eq!(g.stats.penumbra_edges, 4);
        assert_eq!(
            g.stats.fans, 4,
            "one penumbra fan per corner of the top rim"
        );
        assert_eq!(
            g.stats.umbra_fans, 4,
            "one umbra fan per corner of the bottom rim"
        );
        assert_eq!(g.stats.silhouette_a, 8);
        assert!(g.warnings.is_empty(), "{:?}", g.warnings);
        for i in 0..g.volumes.triangle_count() {
            let (t, attrs) = g.volumes.triangle(i);
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let facing_c = n.dot(l.center - t[0]) > 0.0;
            match attrs.kind {
                VolumeKind::UmbraQuad | VolumeKind::UmbraFan | VolumeKind::SilhouetteFaceA => {
                    assert!(!facing_c)
                }
                VolumeKind::PenumbraQuad | VolumeKind::PenumbraFan => assert!(facing_c),
                VolumeKind::SilhouetteFaceB => {}
            }
        }
        // The penumbra surface is closed: every ray from c that misses the cube crosses it
        // exactly once (quads and fans neither overlap nor leave gaps). Rays (a, −1, b) with
        // |a|, |b| ≤ 0.5 all reach the penumbra; those with |a|, |b| < 0.3 hit the cube first.
        let penumbra: Vec<[Vec3; 3]> = (0..g.volumes.triangle_count())
            .map(|i| g.volumes.triangle(i))
            .filter(|(_, a)| !a.kind.is_umbra())
            .map(|(t, _)| t)
            .collect();
        let mut checked = 0;
        for i in 0..48 {
            for j in 0..48 {
                let (a, b) = (-0.5 + i as f32 / 47.0 + 1e-3, -0.5 + j as f32 / 47.0 + 2e-3);
                if a.abs() < 0.3 && b.abs() < 0.3 {
                    continue;
                }
                let dir = Vec3::new(a, -1.0, b).normalize();
                let hits = penumbra
                    .iter()
                    .filter(|t| intersect_triangle(l.center, dir, t).is_some_and(|s| s > 0.0))
                    .count();
                assert_eq!(
                    hits, 1,
                    "ray {dir} crosses the penumbra surface {hits} times"
                );
                checked += 1;
            }
        }
        assert!(checked > 1000);
    }

    #[test]
    fn volumes_over_the_budget_are_not_built() {
        let mesh = CasterMesh::new("cube", &cube(Vec3::new(0.0, 1.0, 0.0), 0.5));
        let l = light(0.5);
        let params = VolumeParams::default();
        let full = build_caster(&mesh, &l, &params);
        let needed = full.volumes.triangle_count();
        assert!(
            needed > 0 && full.warnings.is_empty(),
            "{:?}",
            full.warnings
        );
        // Exactly enough, give or take a fan (the fans are checked conservatively).
        let roomy = build_caster_within(&mesh, &l, &params, needed + MAX_FAN_TRIANGLES);
        assert_eq!(roomy.volumes.triangle_count(), needed);
        // Too little: no volumes at all (never half of them), and a warning naming the budget.
        for limit in [0, needed / 2, needed - 1] {
            let g = build_caster_within(&mesh, &l, &params, limit);
            assert_eq!(g.volumes.triangle_count(), 0, "limit {limit}");
            assert_eq!(g.classes, full.classes);
            let w = g.warnings.join("\n");
            assert!(
                w.contains("MAX_VOLUME_TRIANGLES") && w.contains("casts no shadow"),
                "{w}"
            );
        }
    }

    #[test]
    fn fan_rim_points_follow_the_shorter_arc() {
        let mesh = CasterMesh::new("cube", &cube(Vec3::new(0.0, 1.5, 0.0), 0.5));
        let l = light(1.0);
        let g = build_caster(&mesh, &l, &VolumeParams::default());
        for v in g
            .volumes
            .vertices
            .iter()
            .filter(|v| v.kind == VolumeKind::PenumbraFan)
        {
            assert!(
                ((v.extrusion - l.center).length() - 1.0).abs() < 1e-4,
                "on the rim"
            );
            // Rim points of the fan at a corner lie on the opposite side of c from the corner.
            let corner = v.edge[0];
            let radial = (v.extrusion - l.center).normalize();
            assert!(
                radial.x * corner.x <= 1e-4 && radial.z * corner.z <= 1e-4,
                "{v:?}"
            );
        }
    }

    #[test]
    fn edge_plane_distance_matches_eq2_in_words() {
        let l = light(1.0);
        // A quad extruded from an edge at height 1.5 (2.5 below the light): any ray from c meets
        // the plane through the edge parallel to the disk at 2.5 / cos(angle to the normal).
        let v = VolumeVertex {
            position: Vec3::ZERO,
            kind: VolumeKind::PenumbraQuad,
            edge: [Vec3::new(-0.5, 1.5, 0.5), Vec3::new(0.5, 1.5, 0.5)],
            extrusion: Vec3::new(0.0, 4.0, -1.0),
        };
        let hit = Vec3::new(0.2, 1.5, 0.5) + 3.0 * (Vec3::new(0.2, 1.5, 0.5) - v.extrusion);
        let dir = (hit - l.center).normalize();
        let expected = 2.5 / dir.dot(l.normal);
        assert!((v.edge_plane_distance(hit, dir, &l) - expected).abs() < 1e-4);
        // A tilted edge: the edge point is the one on the line from the extrusion point.
        let tilted = VolumeVertex {
            edge: [Vec3::new(-0.5, 1.0, 0.5), Vec3::new(0.5, 2.0, 0.5)],
            ..v
        };
        let e = Vec3::new(0.25, 1.75, 0.5);
        let hit = e + 2.0 * (e - v.extrusion);
        let dir = (hit - l.center).normalize();
        let expected = (4.0 - 1.75) / dir.dot(l.normal);
        assert!((tilted.edge_plane_distance(hit, dir, &l) - expected).abs() < 1e-4);
        // A silhouette face is its own edge.
        let face = VolumeVertex {
            kind: VolumeKind::SilhouetteFaceA,
            ..v
        };
        assert!((face.edge_plane_distance(hit, dir, &l) - (hit - l.center).length()).abs() < 1e-5);
    }

    #[test]
    fn caster_through_the_light_plane_warns_without_panicking() {
        let mesh = CasterMesh::new("tall", &cube(Vec3::new(0.3, 4.0, 0.0), 0.5));
        let g = build_caster(&mesh, &light(0.5), &VolumeParams::default());
        assert!(
            g.warnings
                .iter()
                .any(|w| w.contains("reaches the light plane")),
            "{:?}",
            g.warnings
        );
        for v in &g.volumes.vertices {
            assert!(v.position.is_finite());
        }
    }
}
