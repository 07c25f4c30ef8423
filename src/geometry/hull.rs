//! Convex hulls of point sets (incremental, O(n²)): random convex casters for the property tests
//! and a `hull` of any mesh for users who want a convex stand-in.

use glam::Vec3;

use crate::scene::Mesh;

/// The convex hull of `points` as a closed, outward-wound mesh, or `None` when the points do not
/// span a volume (fewer than four, or all coplanar) or are not finite.
pub fn convex_hull(points: &[Vec3]) -> Option<Mesh> {
    if points.len() < 4 || points.iter().any(|p| !p.is_finite()) {
        return None;
    }
    let scale = points
        .iter()
        .fold(0.0f32, |m, p| m.max(p.abs().max_element()))
        .max(f32::MIN_POSITIVE);
    let eps = scale * 1e-5;

    // A first tetrahedron from extreme points.
    let i0 = 0;
    let i1 = farthest(points, |p| (p - points[i0]).length())?;
    let line = points[i1] - points[i0];
    let i2 = farthest(points, |p| {
        line.cross(p - points[i0]).length() / line.length()
    })?;
    let normal = line.cross(points[i2] - points[i0]).normalize_or_zero();
    let i3 = farthest(points, |p| normal.dot(p - points[i0]).abs())?;
    if normal.dot(points[i3] - points[i0]).abs() <= eps || line.length() <= eps {
        return None;
    }
    let inside = (points[i0] + points[i1] + points[i2] + points[i3]) / 4.0;

    let mut faces: Vec<[usize; 3]> = Vec::new();
    let oriented = |f: [usize; 3]| {
        let n = (points[f[1]] - points[f[0]]).cross(points[f[2]] - points[f[0]]);
        if n.dot(points[f[0]] - inside) < 0.0 {
            [f[0], f[2], f[1]]
        } else {
            f
        }
    };
    for f in [[i0, i1, i2], [i0, i1, i3], [i0, i2, i3], [i1, i2, i3]] {
        faces.push(oriented(f));
    }
    let above = |f: &[usize; 3], p: Vec3| {
        let n = (points[f[1]] - points[f[0]])
            .cross(points[f[2]] - points[f[0]])
            .normalize_or_zero();
        n.dot(p - points[f[0]])
    };

    for (k, &p) in points.iter().enumerate() {
        if [i0, i1, i2, i3].contains(&k) {
            continue;
        }
        let visible: Vec<bool> = faces.iter().map(|f| above(f, p) > eps).collect();
        if !visible.iter().any(|&v| v) {
            continue;
        }
        let mut edges = std::collections::HashSet::new();
        for (f, _) in faces.iter().zip(&visible).filter(|(_, &v)| v) {
            for j in 0..3 {
                edges.insert((f[j], f[(j + 1) % 3]));
            }
        }
        let horizon: Vec<(usize, usize)> = edges
            .iter()
            .copied()
            .filter(|&(a, b)| !edges.contains(&(b, a)))
            .collect();
        let mut keep = visible.iter();
        faces.retain(|_| !keep.next().copied().unwrap_or(false));
        faces.extend(horizon.into_iter().map(|(a, b)| [a, b, k]));
    }

    // Compact to the used points.
    let mut remap = vec![u32::MAX; points.len()];
    let mut positions = Vec::new();
    let triangles = faces
        .iter()
        .map(|f| {
            f.map(|i| {
                if remap[i] == u32::MAX {
                    remap[i] = positions.len() as u32;
                    positions.push(points[i]);
                }
                remap[i]
            })
        })
        .collect();
    Some(Mesh::new(positions, triangles))
}

fn farthest(points: &[Vec3], key: impl Fn(Vec3) -> f32) -> Option<usize> {
    points
        .iter()
        .enumerate()
        .map(|(i, &p)| (i, key(p)))
        .filter(|(_, d)| d.is_finite())
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::adjacency::CasterMesh;

    #[test]
    fn hull_of_cube_corners_and_interior_points() {
        let mut pts: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        pts.extend([Vec3::splat(0.5), Vec3::new(0.2, 0.3, 0.4)]);
        let m = convex_hull(&pts).expect("a cube spans a volume");
        assert_eq!(m.positions.len(), 8);
        let caster = CasterMesh::new("hull", &m);
        assert!(caster.report.is_closed_manifold(), "{:?}", caster.report);
        // Outward: every point is on or behind every face plane.
        for f in 0..caster.faces.len() as u32 {
            let (normal, offset) = caster.plane(f);
            for p in &pts {
                assert!(normal.dot(*p) - offset < 1e-4);
            }
        }
    }

    #[test]
    fn degenerate_inputs_give_none() {
        assert!(convex_hull(&[Vec3::ZERO, Vec3::X, Vec3::Y]).is_none());
        let flat: Vec<Vec3> = (0..10)
            .map(|i| Vec3::new(i as f32, (i * i) as f32, 0.0))
            .collect();
        assert!(convex_hull(&flat).is_none());
        assert!(convex_hull(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::NAN]).is_none());
    }
}
