//! Scenes: the disk light, the camera and the objects, from TOML files or built-ins.

mod mesh;

pub use mesh::Mesh;

use glam::Vec3;

/// A one-sided disk light: centre `c`, unit normal `n_c` (the side it emits to), radius `r`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiskLight {
    pub center: Vec3,
    pub normal: Vec3,
    pub radius: f32,
    pub intensity: f32,
}

impl DiskLight {
    /// Signed distance of `p` in front of the light plane (positive on the emitting side).
    pub fn height_of(&self, p: Vec3) -> f32 {
        self.normal.dot(p - self.center)
    }

    /// Two unit vectors spanning the disk plane, orthogonal to each other and to the normal.
    pub fn basis(&self) -> (Vec3, Vec3) {
        self.normal.any_orthonormal_pair()
    }
}

/// A pinhole camera looking from `eye` at `target`, +Y up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub fov_y_deg: f32,
}

/// An object of the scene with its mesh already in world space.
#[derive(Clone, Debug)]
pub struct Object {
    pub name: String,
    pub mesh: Mesh,
    /// Casters get umbra and penumbra volumes; every object occludes in `|cx_o|` and the oracle.
    pub casts_shadow: bool,
}

/// A scene ready for the geometry stage: everything in world space.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub camera: Camera,
    pub light: DiskLight,
    pub objects: Vec<Object>,
}

impl Scene {
    /// The objects that cast shadows (and so get volumes).
    pub fn casters(&self) -> impl Iterator<Item = &Object> {
        self.objects.iter().filter(|o| o.casts_shadow)
    }

    /// Every triangle of every object, as corners in world space.
    pub fn all_triangles(&self) -> Vec<[Vec3; 3]> {
        self.objects
            .iter()
            .flat_map(|o| o.mesh.triangle_corners())
            .collect()
    }

    /// Number of triangles over all casters.
    pub fn caster_triangle_count(&self) -> usize {
        self.casters().map(|o| o.mesh.triangles.len()).sum()
    }
}
