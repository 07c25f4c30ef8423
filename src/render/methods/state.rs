//! A method's GPU state for one scene ([`MethodState`]) and the light-space products the session
//! shares between methods ([`SharedMaps`]).

use super::{CameraGroup, Prepare};
use crate::geometry::SceneGeometry;
use crate::render::light_maps::LightMaps;
use crate::render::passes::shadow_map::ShadowMap;
use crate::render::{GpuContext, RenderError};

/// The session's light-space products several methods share (the centre shadow map of `hard`,
/// `pcf`, `pcss` and the D-buffer's `|cx_o|`), each made once per revision.
pub struct SharedMaps {
    pub shadow_map: ShadowMap,
}

/// A method's GPU state for one scene.
pub trait MethodState: Send {
    /// Bring the light-space products up to date for `inputs`, recording the passes that make
    /// them only when they are stale, and write this frame's uniforms; what the camera pass
    /// draws the frame with (its [`CameraGroup`], bound for this frame).
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError>;

    /// Its light-space maps, if it has any.
    fn light_maps<'a>(&'a self, _shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        None
    }

    /// The geometry stage's output its light pass was built from (overlays, stats).
    fn geometry(&self) -> Option<&SceneGeometry> {
        None
    }

    /// CPU milliseconds of its last geometry build, and how many builds it has made.
    fn geometry_builds(&self) -> (u64, f64) {
        (0, 0.0)
    }

    /// Its geometry stage on the GPU, where its last build ran there.
    fn gpu_geometry(&self) -> Option<&crate::render::passes::geometry_gpu::GpuGeometry> {
        None
    }

    /// Forget the light-space products: the next frame remakes them (to time them).
    fn invalidate(&mut self) {}
    /// A temporal method: forget the frames before, so the next frame is a first one.
    fn reset_history(&mut self) {}
    /// A temporal method: whether more frames of a still view would still change its image
    /// (its history is not full yet), so a window keeps drawing.
    fn settling(&self) -> bool {
        false
    }

    /// For a method that counts shadow volumes over the screen: the mean number of volume
    /// fragments per pixel of its last frame (the fill it pays), measured with a pass of its
    /// own; `None` for every other method.
    fn stencil_fill(&self, _ctx: &GpuContext) -> Option<Result<f64, RenderError>> {
        None
    }

    /// Pick up what the GPU hands back a frame or more later for the overlays and the stats
    /// (`hybrid`'s walls, the GPU geometry stage's counts), without waiting; `true` while
    /// something is on its way or has just arrived (a window repaints then).
    fn poll_geometry(&mut self) -> bool {
        false
    }
}
