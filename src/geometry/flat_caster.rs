//! A caster's adjacency as flat words, built once per mesh, for the geometry stage on the GPU
//! (`render::passes::geometry_gpu`, `shaders/passes/geometry_gpu.wgsl`). The same
//! [`CasterMesh`] the CPU stage walks, laid out as the compute passes read it: no GPU type here.
//!
//! - `topo` (`u32`): per face its three welded vertices and a zero, per edge its two vertices
//!   (in the direction its first face walks it) and its two faces (the second
//!   [`NO_FACE`] for an open boundary edge, or for the face left over of an edge with more than
//!   two faces: [`CasterMesh`] has already paired those up), then per vertex the offset of its
//!   run of edge ends (`vertices + 1` offsets: a vertex's edges, counted once per edge end).
//! - `geo` (`[f32; 4]`): the welded positions, then per face its plane (unit normal, offset
//!   `normal · v0`, the same `f32`s [`CasterMesh::plane`] gives, so the classes match bit for bit).

use super::adjacency::{CasterMesh, NO_FACE};

/// A caster's faces, edges and positions as flat words ([module docs](self)).
#[derive(Clone, Debug, Default)]
pub struct FlatCaster {
    pub topo: Vec<u32>,
    pub geo: Vec<[f32; 4]>,
    pub faces: u32,
    pub edges: u32,
    pub vertices: u32,
    /// The most edges at one vertex.
    pub max_vertex_edges: u32,
    /// Whether the mesh bounds a convex solid ([`CasterMesh::convex`]).
    pub convex: bool,
}

impl FlatCaster {
    pub fn new(mesh: &CasterMesh) -> FlatCaster {
        let (faces, edges, vertices) = (mesh.faces.len(), mesh.edges.len(), mesh.positions.len());
        let mut topo = Vec::with_capacity(4 * faces + 4 * edges + vertices + 1);
        for f in &mesh.faces {
            topo.extend([f.v[0], f.v[1], f.v[2], 0]);
        }
        for e in &mesh.edges {
            topo.extend([e.v[0], e.v[1], e.faces[0], e.faces[1]]);
        }
        let mut degree = vec![0u32; vertices];
        for e in &mesh.edges {
            degree[e.v[0] as usize] += 1;
            degree[e.v[1] as usize] += 1;
        }
        let mut at = 0u32;
        for &d in &degree {
            topo.push(at);
            at += d;
        }
        topo.push(at);
        let mut geo = Vec::with_capacity(vertices + faces);
        geo.extend(mesh.positions.iter().map(|p| p.extend(0.0).to_array()));
        geo.extend((0..faces as u32).map(|f| {
            let (n, d) = mesh.plane(f);
            n.extend(d).to_array()
        }));
        FlatCaster {
            topo,
            geo,
            faces: faces as u32,
            edges: edges as u32,
            vertices: vertices as u32,
            max_vertex_edges: degree.iter().copied().max().unwrap_or(0),
            convex: mesh.convex,
        }
    }

    /// The words the GPU stage's work buffer takes: per face its class, per vertex two end
    /// counts, per edge four end slots and two extrusion points (eight words).
    pub fn work_words(&self) -> u64 {
        self.faces as u64 + 2 * self.vertices as u64 + 12 * self.edges as u64
    }

    /// Whether an edge is an open boundary (its second face is the first's back side).
    pub fn is_boundary(&self, edge: u32) -> bool {
        self.topo[(4 * self.faces + 4 * edge + 3) as usize] == NO_FACE
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Mesh;
    use glam::Vec3;

    #[test]
    fn a_quad_sheet_has_its_edges_and_vertex_runs() {
        let quad = Mesh::new(
            vec![
                Vec3::new(-1.0, -2.0, -1.0),
                Vec3::new(1.0, -2.0, -1.0),
                Vec3::new(1.0, -2.0, 1.0),
                Vec3::new(-1.0, -2.0, 1.0),
            ],
            vec![[0, 2, 1], [0, 3, 2]],
        );
        let mesh = CasterMesh::new("sheet", &quad);
        let flat = FlatCaster::new(&mesh);
        assert_eq!((flat.faces, flat.edges, flat.vertices), (2, 5, 4));
        let offsets = &flat.topo[(4 * 2 + 4 * 5) as usize..];
        // Corners 0 and 2 hold the diagonal: three edges each, the others two.
        assert_eq!(offsets, &[0, 3, 5, 8, 10]);
        assert_eq!(flat.max_vertex_edges, 3);
        assert_eq!((0..5).filter(|&e| flat.is_boundary(e)).count(), 4);
        assert_eq!(flat.geo.len(), 4 + 2);
        assert_eq!(flat.geo[4], {
            let (n, d) = mesh.plane(0);
            n.extend(d).to_array()
        });
    }
}
