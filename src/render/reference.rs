//! The ray-cast reference as a render method: a frame gives the surface point under every pixel,
//! the geometry oracle gives V there ([`ProgressiveReference`]: all `K` samples at once for
//! `dbuffer render`, a few per frame in a [`super::session::Session`]), and the camera pass
//! shades that V like any other method's.

use glam::Vec3;

use super::frame::{Frame, FrameRequest, Method};
use crate::geometry::oracle::Oracle;
use crate::geometry::progressive::ProgressiveReference;
use crate::scene::{Camera, DiskLight, Scene};

/// The frame that finds the surface points: the cheapest method, no light-view readback.
pub fn positions_request(request: &FrameRequest) -> FrameRequest {
    FrameRequest {
        method: Method::Hard,
        read_dbuffer: false,
        ..*request
    }
}

/// A reference with nothing sampled yet, for the points `frame` hit.
pub fn start(scene: &Scene, frame: &Frame, samples: u32) -> ProgressiveReference {
    let points = frame
        .position
        .iter()
        .map(|p| (p[3] > 0.5).then(|| Vec3::new(p[0], p[1], p[2])))
        .collect();
    ProgressiveReference::new(Oracle::from_scene(scene, samples as usize), points)
}

/// What a reference image depends on: it starts again when any of it changes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceKey {
    pub light: DiskLight,
    pub camera: Camera,
    pub width: u32,
    pub height: u32,
    pub samples: u32,
    /// Bumped whenever an object's mesh changes.
    pub meshes: u64,
}

impl ReferenceKey {
    pub fn new(scene: &Scene, request: &FrameRequest, meshes: u64) -> ReferenceKey {
        ReferenceKey {
            light: scene.light,
            camera: scene.camera,
            width: request.width,
            height: request.height,
            samples: request.params.reference_samples,
            meshes,
        }
    }
}
