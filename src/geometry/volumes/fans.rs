//! The closing fans of the volumes: at every vertex where two quads of one volume meet,
//! triangles from the vertex extruded away from rim points along the shorter disk arc between
//! the two edges' extrusion points, so both surfaces are closed.

use glam::Vec3;

use super::{FanCorner, VolumeKind, VolumeMesh, VolumeParams, VolumeVertex, CORNER_CHECK_VERTICES};
use crate::geometry::adjacency::CasterMesh;
use crate::geometry::classify::FaceClass;
use crate::scene::AreaLight;

/// Largest group of silhouette edge ends at one vertex whose pairs are all compared (see
/// `Fans::pairs`).
const EXACT_PAIRING: usize = 64;
/// Neighbours around the rim each end of a larger group is compared with, on each side.
const PAIRING_WINDOW: usize = 16;

/// Most triangles of one fan: a half turn (a silhouette turns by less at a vertex) at the
/// finest step [`VolumeParams::fan_step_deg`] is meant to take (11.25° gives 16).
pub(super) const MAX_FAN_TRIANGLES: usize = crate::geometry::outline::MAX_ARC_POINTS;

/// `v` moved `far` further along the ray from the rim point `p` through it. Quads and fans both
/// extrude with this one function, so the end rays they share are bit-identical and the volume
/// surfaces stay closed (`tests/cpu/twin_builtins.rs` welds them by position).
pub(super) fn extrude_away(v: Vec3, p: Vec3, far: f32) -> Vec3 {
    v + (v - p).normalize_or_zero() * far
}

/// One end of an extruded silhouette edge.
#[derive(Clone, Copy, Debug)]
pub(super) struct EdgeEnd {
    /// Welded vertex.
    vertex: u32,
    edge: u32,
    /// The edge leaves this vertex when walked with the volume's inside face (none-front for the
    /// umbra, all-front for the penumbra) on its left.
    outgoing: bool,
    extrusion: Vec3,
}

impl EdgeEnd {
    pub(super) fn both(
        mesh: &CasterMesh,
        classes: &[FaceClass],
        edge: u32,
        inside: FaceClass,
        extrusion: Vec3,
    ) -> [EdgeEnd; 2] {
        let e = &mesh.edges[edge as usize];
        // `e.v` is the direction the first face walks the edge (counter-clockwise).
        let forward = crate::geometry::silhouette::edge_classes(e, classes).0 == inside;
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
pub(super) struct Fans<'a> {
    pub(super) mesh: &'a CasterMesh,
    pub(super) light: &'a AreaLight,
    pub(super) params: &'a VolumeParams,
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
    pub(super) fn close(
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
        rim.extend(crate::geometry::outline::boundary_between(
            light, p1, p2, turn, step,
        ));
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
