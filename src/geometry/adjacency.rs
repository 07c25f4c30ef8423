//! A caster prepared for silhouette work: welded positions, face planes, and edge adjacency.
//!
//! OBJ files duplicate vertices (one per position/normal/uv combination), so adjacency is built
//! on *welded* positions: positions that are bitwise equal (with −0 = +0) are one vertex.
//!
//! Meshes from users are not always closed 2-manifolds, and this module handles that on purpose:
//! - a zero-area face is skipped (it has no normal), which opens its neighbours' edges;
//! - an edge used by one face is a *boundary* edge; the face on its other side is taken to be the
//!   face's own back side (an open surface is a two-sided sheet), see [`FaceClass::mirrored`];
//! - an edge used by more than two faces is split into pairs, opposite directions first; a face
//!   left over borders its own back side like a boundary edge;
//! - two faces that use a shared edge in the same direction are wound inconsistently.
//!
//! Each of these is counted in [`MeshReport`], which the caller turns into one warning per mesh.
//!
//! [`FaceClass::mirrored`]: super::classify::FaceClass::mirrored

use std::collections::HashMap;

use glam::Vec3;

use crate::scene::Mesh;

/// Sentinel for "no face": the other side of a boundary edge.
pub const NO_FACE: u32 = u32::MAX;

/// One non-degenerate triangle of the caster.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Face {
    /// Welded vertex indices, counter-clockwise seen from the front.
    pub v: [u32; 3],
    /// Unit normal.
    pub normal: Vec3,
    /// `normal · v0`: the face plane is `normal · p = offset`.
    pub offset: f32,
    /// Index of the triangle in the source mesh.
    pub source: u32,
}

/// An edge between two faces (or one face and its own back side).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    /// Welded vertex indices, in the direction face `faces[0]` traverses the edge.
    pub v: [u32; 2],
    /// The two faces; `faces[1] == NO_FACE` for a boundary edge.
    pub faces: [u32; 2],
}

impl Edge {
    pub fn is_boundary(&self) -> bool {
        self.faces[1] == NO_FACE
    }
}

/// What was unusual about a mesh. All zero for a closed, consistently wound 2-manifold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeshReport {
    pub degenerate_faces: usize,
    pub boundary_edges: usize,
    /// Edges shared by more than two faces (counted once per such edge).
    pub non_manifold_edges: usize,
    /// Shared edges whose two faces traverse them in the same direction.
    pub inconsistent_edges: usize,
}

impl MeshReport {
    pub fn is_closed_manifold(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0 && self.inconsistent_edges == 0
    }

    /// One line for the user, or `None` for a clean mesh.
    pub fn warning(&self, mesh_name: &str) -> Option<String> {
        if self.is_closed_manifold() && self.degenerate_faces == 0 {
            return None;
        }
        let mut parts = Vec::new();
        if self.boundary_edges > 0 {
            parts.push(format!(
                "{} open boundary edges (treated as bordering the face's own back side)",
                self.boundary_edges
            ));
        }
        if self.non_manifold_edges > 0 {
            parts.push(format!(
                "{} edges shared by more than two faces (paired up, the rest treated as boundary)",
                self.non_manifold_edges
            ));
        }
        if self.inconsistent_edges > 0 {
            parts.push(format!(
                "{} edges between inconsistently wound faces",
                self.inconsistent_edges
            ));
        }
        if self.degenerate_faces > 0 {
            parts.push(format!("{} zero-area faces skipped", self.degenerate_faces));
        }
        Some(format!(
            "mesh '{mesh_name}' is not a closed 2-manifold: {}",
            parts.join(", ")
        ))
    }
}

/// A caster mesh ready for classification: faces with planes, and edges with their two faces.
#[derive(Clone, Debug, Default)]
pub struct CasterMesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub faces: Vec<Face>,
    pub edges: Vec<Edge>,
    pub report: MeshReport,
}

fn weld_key(p: Vec3) -> [u32; 3] {
    // +0.0 for -0.0 so that the two zeros weld.
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

impl CasterMesh {
    /// Weld, compute face planes and build edge adjacency. Non-finite positions make their faces
    /// degenerate (skipped and counted) rather than poisoning the classification.
    pub fn new(name: &str, mesh: &Mesh) -> CasterMesh {
        let mut remap = Vec::with_capacity(mesh.positions.len());
        let mut positions: Vec<Vec3> = Vec::new();
        let mut welded: HashMap<[u32; 3], u32> = HashMap::with_capacity(mesh.positions.len());
        for &p in &mesh.positions {
            let next = positions.len() as u32;
            let id = *welded.entry(weld_key(p)).or_insert(next);
            if id == next {
                positions.push(p);
            }
            remap.push(id);
        }

        let mut report = MeshReport::default();
        let mut faces = Vec::with_capacity(mesh.triangles.len());
        for (i, tri) in mesh.triangles.iter().enumerate() {
            let Some(v) = tri
                .iter()
                .map(|&k| remap.get(k as usize).copied())
                .collect::<Option<Vec<u32>>>()
            else {
                report.degenerate_faces += 1;
                continue;
            };
            let v = [v[0], v[1], v[2]];
            let [a, b, c] = v.map(|k| positions[k as usize]);
            let n = (b - a).cross(c - a);
            let len = n.length();
            if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] || !len.is_finite() || len <= 0.0 {
                report.degenerate_faces += 1;
                continue;
            }
            let normal = n / len;
            faces.push(Face {
                v,
                normal,
                offset: normal.dot(a),
                source: i as u32,
            });
        }

        let edges = build_edges(&faces, &mut report);
        CasterMesh {
            name: name.to_string(),
            positions,
            faces,
            edges,
            report,
        }
    }

    /// The vertex of face `f` that is not on edge `e`.
    pub fn opposite_vertex(&self, f: u32, e: &Edge) -> Vec3 {
        let face = &self.faces[f as usize];
        let k = face
            .v
            .iter()
            .copied()
            .find(|&k| k != e.v[0] && k != e.v[1])
            .unwrap_or(face.v[0]);
        self.positions[k as usize]
    }

    pub fn position(&self, v: u32) -> Vec3 {
        self.positions[v as usize]
    }
}

/// Half-edges sorted by their undirected key, then grouped into edges.
fn build_edges(faces: &[Face], report: &mut MeshReport) -> Vec<Edge> {
    // (undirected key, face, forward?) for the three half-edges of every face.
    let mut half: Vec<(u64, u32, bool)> = Vec::with_capacity(faces.len() * 3);
    for (f, face) in faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (face.v[k], face.v[(k + 1) % 3]);
            let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
            half.push((key, f as u32, a < b));
        }
    }
    half.sort_unstable();

    let mut edges = Vec::with_capacity(half.len() / 2 + 1);
    let mut start = 0;
    while start < half.len() {
        let key = half[start].0;
        let mut end = start + 1;
        while end < half.len() && half[end].0 == key {
            end += 1;
        }
        let (lo, hi) = ((key >> 32) as u32, key as u32);
        let directed = |forward: bool| if forward { [lo, hi] } else { [hi, lo] };
        let group = &half[start..end];
        match group {
            [(_, f, dir)] => {
                report.boundary_edges += 1;
                edges.push(Edge {
                    v: directed(*dir),
                    faces: [*f, NO_FACE],
                });
            }
            [(_, f0, d0), (_, f1, d1)] => {
                if d0 == d1 {
                    report.inconsistent_edges += 1;
                }
                edges.push(Edge {
                    v: directed(*d0),
                    faces: [*f0, *f1],
                });
            }
            _ => {
                report.non_manifold_edges += 1;
                let mut fwd: Vec<u32> = group.iter().filter(|h| h.2).map(|h| h.1).collect();
                let mut back: Vec<u32> = group.iter().filter(|h| !h.2).map(|h| h.1).collect();
                while let (Some(a), Some(b)) = (fwd.last().copied(), back.last().copied()) {
                    fwd.pop();
                    back.pop();
                    edges.push(Edge {
                        v: [lo, hi],
                        faces: [a, b],
                    });
                }
                for (rest, forward) in [(fwd, true), (back, false)] {
                    for f in rest {
                        report.boundary_edges += 1;
                        edges.push(Edge {
                            v: directed(forward),
                            faces: [f, NO_FACE],
                        });
                    }
                }
            }
        }
        start = end;
    }
    edges
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Mesh {
        Mesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
    }

    #[test]
    fn closed_tetrahedron_is_manifold() {
        let m = CasterMesh::new("tetra", &tetra());
        assert_eq!(m.faces.len(), 4);
        assert_eq!(m.edges.len(), 6);
        assert!(m.report.is_closed_manifold(), "{:?}", m.report);
        assert_eq!(m.report.warning("tetra"), None);
        // Every edge is traversed by faces[0] in its stored direction.
        for e in &m.edges {
            let f = &m.faces[e.faces[0] as usize];
            let fwd = (0..3).any(|k| f.v[k] == e.v[0] && f.v[(k + 1) % 3] == e.v[1]);
            assert!(fwd, "{e:?}");
        }
    }

    #[test]
    fn duplicated_vertices_are_welded() {
        // Each triangle with its own copies of the positions, as OBJ files do; -0.0 welds to 0.0.
        let t = tetra();
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for tri in &t.triangles {
            let base = positions.len() as u32;
            for &k in tri {
                let p = t.positions[k as usize];
                positions.push(if p == Vec3::ZERO {
                    Vec3::splat(-0.0)
                } else {
                    p
                });
            }
            triangles.push([base, base + 1, base + 2]);
        }
        let m = CasterMesh::new("soup", &Mesh::new(positions, triangles));
        assert_eq!(m.positions.len(), 4);
        assert!(m.report.is_closed_manifold());
    }

    #[test]
    fn open_degenerate_and_non_manifold_meshes_are_reported() {
        let mut open = tetra();
        open.triangles.pop();
        let m = CasterMesh::new("open", &open);
        assert_eq!(m.report.boundary_edges, 3);
        assert!(m
            .report
            .warning("open")
            .is_some_and(|w| w.contains("3 open boundary")));

        let mut degenerate = tetra();
        degenerate.triangles.push([0, 1, 1]);
        degenerate.positions.push(Vec3::new(f32::NAN, 0.0, 0.0));
        degenerate.triangles.push([0, 1, 4]);
        let m = CasterMesh::new("degenerate", &degenerate);
        assert_eq!(m.report.degenerate_faces, 2);
        assert_eq!(m.faces.len(), 4);

        // Two tetrahedra sharing the edge 0-1: four faces on one edge.
        let mut two = tetra();
        two.positions.push(Vec3::new(0.5, -1.0, -1.0));
        two.triangles.extend([[0, 1, 4], [0, 4, 1]]);
        let m = CasterMesh::new("bowtie", &two);
        assert_eq!(m.report.non_manifold_edges, 1);
        assert!(m.edges.iter().all(|e| e.faces[0] != NO_FACE));

        let mut flipped = tetra();
        flipped.triangles[3] = [1, 3, 2];
        let m = CasterMesh::new("flipped", &flipped);
        assert_eq!(m.report.inconsistent_edges, 3);

        let out_of_range = Mesh::new(vec![Vec3::ZERO], vec![[0, 1, 2]]);
        let m = CasterMesh::new("bad", &out_of_range);
        assert_eq!(m.report.degenerate_faces, 1);
        assert!(m.edges.is_empty());
    }
}
