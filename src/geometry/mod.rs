//! The geometry stage: everything about the disk light and the casters that needs no GPU.
//!
//! Data flow for one light position (Jakobsen et al. 2004, §2.1): [`adjacency`] prepares each caster once
//! (welding, edges); [`classify`] sorts its faces against the disk; [`silhouette`] finds the umbra
//! and penumbra silhouettes and their extrusion points; [`volumes`] extrudes and closes the
//! volumes, and [`volume_vertices`] lays them out as the D-buffer's light pass draws them. [`twin`] is
//! the CPU twin of the D-buffer lookup; the visibility oracle is the ground
//! truth every test compares against.

pub mod adjacency;
pub mod bitmask;
pub mod bvh;
pub mod classify;
pub mod flat_caster;
pub mod flip;
pub mod fused;
pub mod hard_volume;
pub mod hull;
pub mod hybrid;
pub mod light_view;
pub mod line_light;
pub mod metrics;
pub mod moments;
pub mod oracle;
pub mod outline;
pub mod planar;
pub mod progressive;
pub mod ray;
pub mod silhouette;
pub mod ssm;
pub mod twin;
pub mod view;
pub mod visibility;
pub mod volume_vertices;
pub mod volumes;
pub mod wedges;

pub use adjacency::{CasterMesh, MeshReport};
pub use classify::FaceClass;
pub use twin::DBufferTwin;
pub use visibility::{Branch, VtVariant};
pub use volumes::{CasterGeometry, GeometryStats, VolumeKind, VolumeMesh, VolumeParams};

use crate::scene::{AreaLight, Scene};

/// The casters of a scene, prepared once (welding, adjacency, face planes). Only
/// [`PreparedCasters::build`] runs again when the light moves (Jakobsen et al. 2004, §6.1).
#[derive(Clone, Debug, Default)]
pub struct PreparedCasters {
    pub meshes: Vec<CasterMesh>,
    /// The scene's own warnings ([`Scene::warnings`]: camera, size, empty objects), passed on
    /// first in every [`SceneGeometry::warnings`].
    pub scene_warnings: Vec<String>,
}

/// The geometry of every caster for one light.
#[derive(Clone, Debug, Default)]
pub struct SceneGeometry {
    pub casters: Vec<CasterGeometry>,
    pub stats: GeometryStats,
    pub warnings: Vec<String>,
}

impl PreparedCasters {
    pub fn new(scene: &Scene) -> Self {
        Self {
            meshes: scene
                .casters()
                .map(|o| CasterMesh::new(&o.name, &o.mesh))
                .collect(),
            scene_warnings: scene.warnings(),
        }
    }

    /// Classes, silhouettes and volumes of every caster for this light, within the scene's
    /// budget of volume triangles (`MAX_VOLUME_TRIANGLES`, shared by the casters in order: one
    /// that would pass what is left casts no shadow, with a warning).
    pub fn build(&self, light: &AreaLight, params: &VolumeParams) -> SceneGeometry {
        let mut left = volumes::MAX_VOLUME_TRIANGLES as usize;
        let casters: Vec<CasterGeometry> = self
            .meshes
            .iter()
            .map(|m| {
                let c = volumes::build_caster_within(m, light, params, left);
                left -= c.volumes.triangle_count().min(left);
                c
            })
            .collect();
        let mut stats = GeometryStats::default();
        let mut warnings = self.scene_warnings.clone();
        for c in &casters {
            stats += c.stats;
            warnings.extend(c.warnings.iter().cloned());
        }
        SceneGeometry {
            casters,
            stats,
            warnings,
        }
    }
}
