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

use glam::Vec3;

use crate::scene::Mesh;

/// Sentinel for "no face": the other side of a boundary edge.
pub const NO_FACE: u32 = u32::MAX;

/// One non-degenerate triangle of the caster.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Face {
    /// Welded vertex indices, counter-clockwise seen from the front.
    pub v: [u32; 3],
    /// Unit normal (the plane's offset is `normal · v0`: see [`CasterMesh::plane`]).
    pub normal: Vec3,
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
    /// Whether it bounds a convex solid ([`CasterMesh::bounds_convex_solid`]): seen from any
    /// point, its faces cover one convex region, two layers deep. `dbuffer-fused` reads its
    /// exact area there without counting samples.
    pub convex: bool,
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
    ///
    /// Memory: besides the result (24 bytes per face, 16 per edge, 12 per vertex), at most 20
    /// bytes per input vertex while welding and 4 per half-edge (12 per face) and 4 per vertex
    /// while pairing edges; nothing of either is held at the same time as the other.
    pub fn new(name: &str, mesh: &Mesh) -> CasterMesh {
        let (positions, remap) = weld(&mesh.positions);

        let mut report = MeshReport::default();
        let mut faces = Vec::with_capacity(mesh.triangles.len());
        for tri in &mesh.triangles {
            let [Some(v0), Some(v1), Some(v2)] = tri.map(|k| remap.get(k as usize).copied()) else {
                report.degenerate_faces += 1;
                continue;
            };
            let v = [v0, v1, v2];
            let [a, b, c] = v.map(|k| positions[k as usize]);
            let n = (b - a).cross(c - a);
            let len = n.length();
            if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] || !len.is_finite() || len <= 0.0 {
                report.degenerate_faces += 1;
                continue;
            }
            faces.push(Face { v, normal: n / len });
        }
        drop(remap);
        faces.shrink_to_fit();

        let edges = build_edges(&faces, positions.len(), &mut report);
        let mut out = CasterMesh {
            // Repeated in one-line warnings: control characters escaped, cut if long.
            name: crate::scene::shown(name),
            positions,
            faces,
            edges,
            report,
            convex: false,
        };
        out.convex = out.bounds_convex_solid();
        out
    }

    /// Whether the mesh is the boundary of a convex solid: a closed, consistently wound
    /// 2-manifold without degenerate faces, in one piece, convex at every edge (the far vertex
    /// of each face is not in front of its neighbour's plane), with its centroid behind every
    /// face (so its faces point outward). A closed connected surface convex at every edge bounds
    /// a convex solid; the centroid test also catches a surface wound twice round. Within a
    /// tolerance of 10⁻⁵ of the mesh's extent, so flat parts split into triangles stay convex.
    pub fn bounds_convex_solid(&self) -> bool {
        if !self.report.is_closed_manifold()
            || self.report.degenerate_faces > 0
            || self.faces.len() < 4
        {
            return false;
        }
        let scale = self
            .positions
            .iter()
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        let tol = 1e-5 * (1.0 + scale);
        let convex_edges = self.edges.iter().all(|e| {
            let (n0, d0) = self.plane(e.faces[0]);
            n0.dot(self.opposite_vertex(e.faces[1], e)) - d0 <= tol
        });
        if !convex_edges {
            return false;
        }
        let centroid = self.positions.iter().copied().sum::<Vec3>() / self.positions.len() as f32;
        if !(0..self.faces.len() as u32).all(|f| {
            let (n, d) = self.plane(f);
            n.dot(centroid) - d < tol
        }) {
            return false;
        }
        // One piece: every face reached from the first across edges.
        let mut parent: Vec<u32> = (0..self.faces.len() as u32).collect();
        fn root(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                let up = parent[parent[i as usize] as usize];
                parent[i as usize] = up;
                i = up;
            }
            i
        }
        for e in &self.edges {
            let (a, b) = (root(&mut parent, e.faces[0]), root(&mut parent, e.faces[1]));
            parent[a as usize] = b;
        }
        let first = root(&mut parent, 0);
        (0..self.faces.len() as u32).all(|f| root(&mut parent, f) == first)
    }

    /// The plane of face `f`: its unit normal `n` and offset `n · v0` (the plane is
    /// `n · p = offset`). The offset is computed when asked rather than stored (a face is 24
    /// bytes, not 32: 134 MB less for a 16M-triangle caster, for one vertex load per face and
    /// light move; recomputing the normal too would save as much again but made classification
    /// three times slower, every corner a cache miss).
    pub fn plane(&self, f: u32) -> (Vec3, f32) {
        let face = &self.faces[f as usize];
        (
            face.normal,
            face.normal.dot(self.positions[face.v[0] as usize]),
        )
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

/// Welds bitwise-equal positions (−0 = +0): the welded positions, in order of first occurrence,
/// and each input position's welded index. Sorts (position, index) pairs, 16 bytes per
/// position, rather than filling a hash map (about twice that at its load factor).
fn weld(input: &[Vec3]) -> (Vec<Vec3>, Vec<u32>) {
    let mut sorted: Vec<([u32; 3], u32)> = input
        .iter()
        .enumerate()
        .map(|(i, &p)| (weld_key(p), i as u32))
        .collect();
    sorted.sort_unstable();
    // The first (smallest) input index of each run of equal positions.
    let mut remap = vec![0u32; input.len()];
    for run in sorted.chunk_by(|a, b| a.0 == b.0) {
        for &(_, i) in run {
            remap[i as usize] = run[0].1;
        }
    }
    drop(sorted);
    // Number the runs in order of first occurrence; a run's first index comes before the rest.
    let mut positions = Vec::new();
    for i in 0..input.len() {
        let first = remap[i] as usize;
        remap[i] = if first == i {
            positions.push(input[i]);
            (positions.len() - 1) as u32
        } else {
            remap[first]
        };
    }
    (positions, remap)
}

/// Half-edges grouped by their undirected key `(lo, hi)`, then into edges, in the order of
/// the key, then the face, then the direction (backward first).
///
/// The half-edges (`3·face + k`, 4 bytes each) are bucketed by their smaller vertex (a counting
/// sort, plus 4 bytes per vertex) and each small bucket is sorted by `(hi, face, forward)`,
/// which gives the same order as sorting all half-edges by `(key, face, forward)`. The edges
/// are counted first and allocated once.
fn build_edges(faces: &[Face], vertices: usize, report: &mut MeshReport) -> Vec<Edge> {
    // (lo, hi, forward) of half-edge h: the edge from corner k to corner k + 1 of its face.
    let half_edge = |h: u32| {
        let (f, k) = ((h / 3) as usize, (h % 3) as usize);
        let v = faces[f].v;
        let (a, b) = (v[k], v[(k + 1) % 3]);
        (a.min(b), a.max(b), a < b)
    };
    let sort_key = |h: &u32| {
        let (_, hi, forward) = half_edge(*h);
        (hi, *h / 3, forward)
    };
    let halves = (faces.len() * 3) as u32;
    // Bucket starts by the smaller vertex.
    let mut start = vec![0u32; vertices + 1];
    for h in 0..halves {
        start[half_edge(h).0 as usize + 1] += 1;
    }
    for i in 0..vertices {
        start[i + 1] += start[i];
    }
    let mut bucketed = vec![0u32; halves as usize];
    {
        let mut next = start.clone();
        for h in 0..halves {
            let slot = &mut next[half_edge(h).0 as usize];
            bucketed[*slot as usize] = h;
            *slot += 1;
        }
    }
    let bucket = |lo: usize| start[lo] as usize..start[lo + 1] as usize;
    for lo in 0..vertices {
        bucketed[bucket(lo)].sort_unstable_by_key(sort_key);
    }

    // Each run of one key (lo, hi) is one edge, or several where more than two faces meet.
    let runs = |lo: usize| bucketed[bucket(lo)].chunk_by(|&a, &b| half_edge(a).1 == half_edge(b).1);
    let face = |h: u32| h / 3;
    let forward = |h: u32| half_edge(h).2;
    let count: usize = (0..vertices)
        .flat_map(runs)
        .map(|run| {
            let fwd = run.iter().filter(|&&h| forward(h)).count();
            match run.len() {
                1 | 2 => 1,
                n => fwd.max(n - fwd),
            }
        })
        .sum();
    let mut edges = Vec::with_capacity(count);
    for lo in 0..vertices {
        for run in runs(lo) {
            let (lo, hi, _) = half_edge(run[0]);
            let directed = |forward: bool| if forward { [lo, hi] } else { [hi, lo] };
            match *run {
                [h] => {
                    report.boundary_edges += 1;
                    edges.push(Edge {
                        v: directed(forward(h)),
                        faces: [face(h), NO_FACE],
                    });
                }
                [h0, h1] => {
                    if forward(h0) == forward(h1) {
                        report.inconsistent_edges += 1;
                    }
                    edges.push(Edge {
                        v: directed(forward(h0)),
                        faces: [face(h0), face(h1)],
                    });
                }
                _ => {
                    report.non_manifold_edges += 1;
                    let mut fwd: Vec<u32> = run
                        .iter()
                        .filter(|&&h| forward(h))
                        .map(|&h| face(h))
                        .collect();
                    let mut back: Vec<u32> = run
                        .iter()
                        .filter(|&&h| !forward(h))
                        .map(|&h| face(h))
                        .collect();
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
        }
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
    fn convex_solids_are_told_from_the_rest() {
        use crate::scene::shapes;
        let convex = |m: &Mesh| CasterMesh::new("m", m).convex;
        for m in [
            tetra(),
            shapes::cube(),
            shapes::sphere(16, 8),
            shapes::rounded_box(48, 16),
            shapes::icosphere(0),
            shapes::cylinder(24),
        ] {
            assert!(convex(&m), "{} triangles", m.triangles.len());
        }
        // Concave, open, in two pieces, or turned inside out: not one convex solid.
        let mut two = shapes::cube();
        let far: Vec<Vec3> = two.positions.iter().map(|p| *p + Vec3::X * 3.0).collect();
        let base = two.positions.len() as u32;
        two.positions.extend(far);
        let more: Vec<[u32; 3]> = two.triangles.iter().map(|t| t.map(|k| k + base)).collect();
        two.triangles.extend(more);
        let mut open = shapes::cube();
        open.triangles.pop();
        let mut inside_out = shapes::sphere(16, 8);
        for t in &mut inside_out.triangles {
            t.swap(1, 2);
        }
        for m in [
            shapes::torus(24, 12),
            shapes::l_prism(),
            two,
            open,
            inside_out,
        ] {
            assert!(!convex(&m), "{} triangles", m.triangles.len());
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

    /// The edge pairing as it was written before it bucketed (one global sort of 16-byte
    /// half-edges): the bucketed one must give the same edges in the same order.
    fn edges_by_global_sort(faces: &[Face]) -> (Vec<Edge>, MeshReport) {
        let mut report = MeshReport::default();
        let mut half: Vec<(u64, u32, bool)> = Vec::new();
        for (f, face) in faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (face.v[k], face.v[(k + 1) % 3]);
                let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                half.push((key, f as u32, a < b));
            }
        }
        half.sort_unstable();
        let mut edges = Vec::new();
        for group in half.chunk_by(|x, y| x.0 == y.0) {
            let (lo, hi) = ((group[0].0 >> 32) as u32, group[0].0 as u32);
            let directed = |forward: bool| if forward { [lo, hi] } else { [hi, lo] };
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
        }
        (edges, report)
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

        /// Random triangles over few vertices (so edges are shared by 1, 2 or many faces, in
        /// both directions, and some faces repeat): the same edges, in the same order, with the
        /// same report as the global sort.
        #[test]
        fn bucketed_edges_match_the_global_sort(
            tris in proptest::collection::vec((0u32..7, 0u32..7, 0u32..7), 1..40),
        ) {
            let positions: Vec<Vec3> = (0..7)
                .map(|i| Vec3::new(i as f32, (i * i % 5) as f32, (i % 3) as f32 * 0.5))
                .collect();
            let mesh = Mesh::new(positions, tris.iter().map(|&(a, b, c)| [a, b, c]).collect());
            let m = CasterMesh::new("random", &mesh);
            let (edges, report) = edges_by_global_sort(&m.faces);
            proptest::prop_assert_eq!(&m.edges, &edges);
            proptest::prop_assert_eq!(m.report.boundary_edges, report.boundary_edges);
            proptest::prop_assert_eq!(m.report.non_manifold_edges, report.non_manifold_edges);
            proptest::prop_assert_eq!(m.report.inconsistent_edges, report.inconsistent_edges);
        }

        /// Welding by sorting numbers positions in order of first occurrence, as the hash map
        /// it replaced did.
        #[test]
        fn weld_numbers_in_order_of_first_occurrence(
            points in proptest::collection::vec((0i8..3, 0i8..3, -1i8..2), 0..30),
        ) {
            let input: Vec<Vec3> = points
                .iter()
                .map(|&(x, y, z)| Vec3::new(f32::from(x), f32::from(y), if z == 0 { -0.0 } else { f32::from(z) }))
                .collect();
            let (positions, remap) = weld(&input);
            let mut expected: Vec<Vec3> = Vec::new();
            let mut ids = std::collections::HashMap::new();
            for (i, &p) in input.iter().enumerate() {
                let next = expected.len() as u32;
                let id = *ids.entry(weld_key(p)).or_insert_with(|| {
                    expected.push(p);
                    next
                });
                proptest::prop_assert_eq!(remap[i], id);
            }
            proptest::prop_assert_eq!(positions, expected);
        }
    }
}
