//! The geometry stage: everything about the disk light and the casters that needs no GPU.
//!
//! Data flow for one light position (seed 000 §2.1): [`adjacency`] prepares each caster once
//! (welding, edges); [`classify`] sorts its faces against the disk; [`silhouette`] finds the umbra
//! and penumbra silhouettes and their extrusion points; [`volumes`] extrudes and closes the
//! volumes. [`twin`] is the CPU twin of the D-buffer lookup; the visibility oracle is the ground
//! truth every test compares against.

pub mod adjacency;
pub mod bvh;
pub mod classify;
pub mod hard_volume;
pub mod hull;
pub mod light_view;
pub mod line_light;
pub mod metrics;
pub mod oracle;
pub mod progressive;
pub mod ray;
pub mod silhouette;
pub mod ssm;
pub mod twin;
pub mod view;
pub mod visibility;
pub mod volumes;
pub mod wedges;

pub use adjacency::{CasterMesh, MeshReport};
pub use classify::FaceClass;
pub use twin::DBufferTwin;
pub use visibility::{Branch, VtVariant};
pub use volumes::{CasterGeometry, GeometryStats, VolumeKind, VolumeMesh, VolumeParams};

use crate::scene::{DiskLight, Scene};

/// The casters of a scene, prepared once (welding, adjacency, face planes). Only
/// [`PreparedCasters::build`] runs again when the light moves (seed 000 §6.1).
#[derive(Clone, Debug, Default)]
pub struct PreparedCasters {
    pub meshes: Vec<CasterMesh>,
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
        }
    }

    /// Classes, silhouettes and volumes of every caster for this light.
    pub fn build(&self, light: &DiskLight, params: &VolumeParams) -> SceneGeometry {
        let casters: Vec<CasterGeometry> = self
            .meshes
            .iter()
            .map(|m| volumes::build_caster(m, light, params))
            .collect();
        let mut stats = GeometryStats::default();
        let mut warnings = Vec::new();
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
