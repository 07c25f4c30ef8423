//! Indexed triangle meshes, the one mesh type every layer shares.

use glam::{Affine3A, Vec3};

/// An indexed triangle mesh. Counter-clockwise triangles (seen from outside) face outward.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            positions,
            triangles,
        }
    }

    /// The three corners of triangle `i`.
    pub fn corners(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Every triangle as its three corners.
    pub fn triangle_corners(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        (0..self.triangles.len()).map(|i| self.corners(i))
    }

    /// The mesh with every position transformed. A mirroring transform (negative determinant)
    /// reverses the winding so that triangles keep facing outward.
    pub fn transformed(&self, m: &Affine3A) -> Mesh {
        let positions = self
            .positions
            .iter()
            .map(|&p| m.transform_point3(p))
            .collect();
        let triangles = if m.matrix3.determinant() < 0.0 {
            self.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect()
        } else {
            self.triangles.clone()
        };
        Mesh {
            positions,
            triangles,
        }
    }

    /// Like [`Mesh::transformed`], in place (no second copy of a large mesh).
    pub fn transform_in_place(&mut self, m: &Affine3A) {
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        if m.matrix3.determinant() < 0.0 {
            for t in &mut self.triangles {
                t.swap(1, 2);
            }
        }
    }

    /// Axis-aligned bounds `(min, max)`; `None` for a mesh without positions.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }
}
