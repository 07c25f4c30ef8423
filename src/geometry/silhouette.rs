//! Umbra and penumbra silhouettes, and the extrusion points `p_u` / `p_p` of their edges.
//!
//! An edge is on the *umbra silhouette* if it joins a none-frontfacing face to one that is not,
//! and on the *penumbra silhouette* if it joins an all-frontfacing face to one that is not
//! (Jakobsen et al. 2004, §2.1). Across a boundary edge a face borders its own back side.
//!
//! The two planes through the line of an edge that are tangent to the disk touch it at two rim
//! points. `p_u` is the one whose plane has the disk and the caster on the same side (the umbra
//! boundary), `p_p` the one whose plane separates them (the penumbra boundary).

use glam::Vec3;
use rayon::prelude::*;

use super::adjacency::{CasterMesh, Edge, NO_FACE};
use super::classify::FaceClass;
use crate::scene::AreaLight;

/// A silhouette edge with everything volume extrusion needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SilhouetteEdge {
    /// Index into [`CasterMesh::edges`].
    pub edge: u32,
    /// End points, in the direction the edge's first face traverses it.
    pub v: [Vec3; 2],
    pub umbra: bool,
    pub penumbra: bool,
    /// A point on the caster's side of the edge: the edge midpoint moved into its faces.
    pub caster_side: Vec3,
}

/// The two rim points where planes through an edge's line touch the disk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtrusionPoints {
    /// Tangent plane with the disk and the caster on the same side.
    pub umbra: Vec3,
    /// Tangent plane separating the disk and the caster.
    pub penumbra: Vec3,
}

pub use super::outline::tangent_points;

/// `p_u` and `p_p` for the edge `v1 v2` with the caster on the side of `caster_side`.
pub fn extrusion_points(
    v1: Vec3,
    v2: Vec3,
    caster_side: Vec3,
    light: &AreaLight,
) -> Option<ExtrusionPoints> {
    let [t0, t1] = tangent_points(v1, v2, light)?;
    // For the plane through the edge and t: positive when c and the caster are on one side.
    let same_side = |t: Vec3| {
        let n = (v2 - v1).cross(t - v1);
        n.dot(light.center - v1).signum() * n.dot(caster_side - v1)
    };
    if same_side(t0) >= same_side(t1) {
        Some(ExtrusionPoints {
            umbra: t0,
            penumbra: t1,
        })
    } else {
        Some(ExtrusionPoints {
            umbra: t1,
            penumbra: t0,
        })
    }
}

fn is_umbra_pair(a: FaceClass, b: FaceClass) -> bool {
    (a == FaceClass::NoneFront) != (b == FaceClass::NoneFront)
}

fn is_penumbra_pair(a: FaceClass, b: FaceClass) -> bool {
    (a == FaceClass::AllFront) != (b == FaceClass::AllFront)
}

/// Classes on the two sides of an edge; a boundary edge borders the face's own back side.
pub fn edge_classes(edge: &Edge, classes: &[FaceClass]) -> (FaceClass, FaceClass) {
    let c0 = classes[edge.faces[0] as usize];
    let c1 = if edge.faces[1] == NO_FACE {
        c0.mirrored()
    } else {
        classes[edge.faces[1] as usize]
    };
    (c0, c1)
}

fn silhouette_edge(mesh: &CasterMesh, classes: &[FaceClass], i: usize) -> Option<SilhouetteEdge> {
    let edge = &mesh.edges[i];
    let (c0, c1) = edge_classes(edge, classes);
    let umbra = is_umbra_pair(c0, c1);
    let penumbra = is_penumbra_pair(c0, c1);
    if !umbra && !penumbra {
        return None;
    }
    let v = [mesh.position(edge.v[0]), mesh.position(edge.v[1])];
    let mid = 0.5 * (v[0] + v[1]);
    let along = (v[1] - v[0]).normalize_or_zero();
    let into_face = |f: u32| {
        let d = mesh.opposite_vertex(f, edge) - mid;
        (d - d.dot(along) * along).normalize_or_zero()
    };
    // Into the caster: along both faces and against their normals. For a nearly flat edge the
    // in-face directions cancel and the normals decide; for a sharp one the faces do. A boundary
    // edge of a sheet has only its face's direction (the back side is the same sheet).
    let f0 = edge.faces[0];
    let mut inward = into_face(f0);
    if edge.faces[1] != NO_FACE {
        let f1 = edge.faces[1];
        let normals = mesh.plane(f0).0 + mesh.plane(f1).0;
        inward += into_face(f1) - normals;
    }
    let scale = (v[1] - v[0]).length();
    Some(SilhouetteEdge {
        edge: i as u32,
        v,
        umbra,
        penumbra,
        caster_side: mid + inward * scale,
    })
}

/// How many edges are on the umbra silhouette and how many on the penumbra one (an edge can be
/// on both), without building them: what the volumes will cost, known before they are made.
pub fn count_silhouettes(mesh: &CasterMesh, classes: &[FaceClass]) -> (usize, usize) {
    let count = |edge: &Edge| {
        let (c0, c1) = edge_classes(edge, classes);
        (
            usize::from(is_umbra_pair(c0, c1)),
            usize::from(is_penumbra_pair(c0, c1)),
        )
    };
    let add = |a: (usize, usize), b: (usize, usize)| (a.0 + b.0, a.1 + b.1);
    if mesh.edges.len() > 32 * 1024 {
        mesh.edges
            .par_iter()
            .with_min_len(8192)
            .map(count)
            .reduce(|| (0, 0), add)
    } else {
        mesh.edges.iter().map(count).fold((0, 0), add)
    }
}

/// Every edge on the umbra or penumbra silhouette, in edge order.
pub fn find_silhouettes(mesh: &CasterMesh, classes: &[FaceClass]) -> Vec<SilhouetteEdge> {
    const PARALLEL_ABOVE: usize = 32 * 1024;
    if mesh.edges.len() > PARALLEL_ABOVE {
        (0..mesh.edges.len())
            .into_par_iter()
            .with_min_len(8192)
            .filter_map(|i| silhouette_edge(mesh, classes, i))
            .collect()
    } else {
        (0..mesh.edges.len())
            .filter_map(|i| silhouette_edge(mesh, classes, i))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::classify::classify;
    use crate::scene::Mesh;

    fn light() -> AreaLight {
        AreaLight {
            center: Vec3::ZERO,
            normal: Vec3::NEG_Y,
            radius: 0.5,
            intensity: 1.0,
            outline: crate::scene::Outline::Disk,
        }
    }

    fn is_tangent(t: Vec3, v1: Vec3, v2: Vec3, l: &AreaLight) -> bool {
        // On the rim, and the plane through the edge and t meets the disk plane in the tangent
        // line at t: the in-plane normal of that plane is parallel to t − c.
        let on_rim = ((t - l.center).length() - l.radius).abs() < 1e-4;
        let n = (v2 - v1).cross(t - v1).normalize();
        let in_plane = (n - n.dot(l.normal) * l.normal).normalize();
        let radial = (t - l.center).normalize();
        on_rim && in_plane.cross(radial).length() < 1e-3
    }

    #[test]
    fn edge_parallel_to_the_disk_plane() {
        // Edge along x, 2 below the light, at z = 1; the caster lies toward −z (behind the edge).
        let l = light();
        let (v1, v2) = (Vec3::new(-1.0, -2.0, 1.0), Vec3::new(1.0, -2.0, 1.0));
        let m = Vec3::new(0.0, -2.0, 0.0);
        let p = extrusion_points(v1, v2, m, &l).expect("outside the cone");
        // By hand: tangent points c ± r ẑ; the umbra plane has the disk on the caster's side, so
        // it passes through the rim point beyond the edge, (0, 0, +r).
        assert!(
            (p.umbra - Vec3::new(0.0, 0.0, 0.5)).length() < 1e-6,
            "{p:?}"
        );
        assert!(
            (p.penumbra - Vec3::new(0.0, 0.0, -0.5)).length() < 1e-6,
            "{p:?}"
        );
        // On the ground (y = −4, twice as far as the edge) the centre projects the edge to z = 2;
        // by similar triangles the umbra boundary is at 1 + (1 − 0.5) = 1.5 and the penumbra
        // boundary at 1 + (1 + 0.5) = 2.5.
        let ground = |p: Vec3| v1.z + (v1.z - p.z) * (-4.0 - v1.y) / (v1.y - p.y);
        assert!((ground(p.umbra) - 1.5).abs() < 1e-5);
        assert!((ground(p.penumbra) - 2.5).abs() < 1e-5);
    }

    #[test]
    fn tilted_edge_tangent_points() {
        let l = AreaLight {
            center: Vec3::new(0.2, 3.0, -0.1),
            normal: Vec3::new(0.3, -1.0, 0.2).normalize(),
            radius: 0.7,
            intensity: 1.0,
            outline: crate::scene::Outline::Disk,
        };
        let (v1, v2) = (Vec3::new(1.0, 1.0, 0.3), Vec3::new(1.6, 0.2, -0.5));
        let [t0, t1] = tangent_points(v1, v2, &l).expect("line meets the plane outside the disk");
        assert!(is_tangent(t0, v1, v2, &l) && is_tangent(t1, v1, v2, &l));
        assert!((t0 - t1).length() > 0.1);
        // The caster side decides which is which: swapping the side swaps the points.
        let m = Vec3::new(0.0, 0.6, 0.0);
        let a = extrusion_points(v1, v2, m, &l).expect("defined");
        let mirror = 2.0 * (0.5 * (v1 + v2)) - m;
        let b = extrusion_points(v1, v2, mirror, &l).expect("defined");
        assert!(a.umbra == b.penumbra && a.penumbra == b.umbra);
    }

    #[test]
    fn edge_whose_line_meets_the_disk_has_no_extrusion() {
        let l = light();
        // A vertical edge right under the disk: its line pierces the disk at (0.1, 0, 0).
        let (v1, v2) = (Vec3::new(0.1, -1.0, 0.0), Vec3::new(0.1, -2.0, 0.0));
        assert_eq!(tangent_points(v1, v2, &l), None);
        assert_eq!(
            extrusion_points(v1, v2, Vec3::new(0.0, -1.5, 0.0), &l),
            None
        );
        // Just outside the rim it is defined again.
        let (v1, v2) = (Vec3::new(0.6, -1.0, 0.0), Vec3::new(0.6, -2.0, 0.0));
        assert!(tangent_points(v1, v2, &l).is_some());
        // Degenerate input: no panic.
        assert_eq!(tangent_points(v1, v1, &l), None);
        assert_eq!(tangent_points(Vec3::NAN, v1, &l), None);
    }

    #[test]
    fn cube_under_a_small_light_has_two_loops() {
        // Unit cube 2..3 below the light. With r = 0.25 the side planes (|x|, |z| = 0.5) miss
        // the disk: the top is all-front and everything else none-front.
        let mut positions = Vec::new();
        for i in 0..8 {
            positions.push(Vec3::new(
                if i & 1 == 0 { -0.5 } else { 0.5 },
                if i & 2 == 0 { -3.0 } else { -2.0 },
                if i & 4 == 0 { -0.5 } else { 0.5 },
            ));
        }
        let triangles = vec![
            [0, 1, 5],
            [0, 5, 4], // bottom (y = −3), facing −y
            [2, 6, 7],
            [2, 7, 3], // top, facing +y
            [0, 4, 6],
            [0, 6, 2], // x = −0.5
            [1, 3, 7],
            [1, 7, 5], // x = +0.5
            [0, 2, 3],
            [0, 3, 1], // z = −0.5
            [4, 5, 7],
            [4, 7, 6], // z = +0.5
        ];
        let mesh = CasterMesh::new("cube", &Mesh::new(positions, triangles));
        assert!(mesh.report.is_closed_manifold(), "{:?}", mesh.report);
        let small = AreaLight {
            radius: 0.25,
            ..light()
        };
        let classes = classify(&mesh, &small);
        let sil = find_silhouettes(&mesh, &classes);
        // Sides face away from the whole small disk: the top rim is both silhouettes at once.
        assert_eq!(sil.len(), 4);
        assert!(sil.iter().all(|s| s.umbra && s.penumbra));

        // A light wider than the cube: the side planes cut the disk, the sides become silhouette
        // faces, the top rim is only the penumbra silhouette and the bottom rim only the umbra one.
        let wide = AreaLight {
            radius: 1.0,
            ..light()
        };
        let classes = classify(&mesh, &wide);
        assert_eq!(
            classes
                .iter()
                .filter(|c| **c == FaceClass::SilhouetteA)
                .count(),
            8
        );
        let sil = find_silhouettes(&mesh, &classes);
        let top = sil.iter().filter(|s| s.v[0].y == -2.0 && s.v[1].y == -2.0);
        assert!(top.clone().count() == 4 && top.clone().all(|s| s.penumbra && !s.umbra));
        let bottom = sil.iter().filter(|s| s.v[0].y == -3.0 && s.v[1].y == -3.0);
        assert!(bottom.clone().count() == 4 && bottom.clone().all(|s| s.umbra && !s.penumbra));
        assert_eq!(sil.len(), 8);
    }

    #[test]
    fn open_sheet_edges_are_both_silhouettes() {
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
        let classes = classify(&mesh, &light());
        let sil = find_silhouettes(&mesh, &classes);
        assert_eq!(
            sil.len(),
            4,
            "the four rim edges; the diagonal joins two alike faces"
        );
        assert!(sil.iter().all(|s| s.umbra && s.penumbra));
    }
}
