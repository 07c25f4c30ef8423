//! What a method sees of the session while it records a frame ([`FrameInputs`]) and what
//! [`MethodState::prepare`](super::MethodState::prepare) works with ([`Prepare`]).

use std::cell::OnceCell;

use super::{Knobs, SharedMaps};
use crate::geometry::light_view::LightView;
use crate::geometry::{PreparedCasters, VtVariant};
use crate::render::gpu_scene::GpuScene;
use crate::render::passes::camera::ScreenView;
use crate::render::passes::shadow_map::MapInputs;
use crate::render::timer::Recorder;
use crate::render::{GpuContext, RenderError};
use crate::scene::{AreaLight, Scene};

/// What a method sees of the session while it records a frame.
pub struct FrameInputs<'a> {
    pub ctx: &'a GpuContext,
    pub scene: &'a Scene,
    pub surfaces: &'a GpuScene,
    /// The casters welded with their adjacency, prepared on first use ([`FrameInputs::prepared`]).
    pub prepared: &'a OnceCell<PreparedCasters>,
    pub light_view: &'a LightView,
    /// Bumped whenever the light or a caster changed: light-space products made for an older
    /// revision are stale.
    pub revision: u64,
    /// Bumped whenever an object's mesh changed (what a BVH of the scene is built from).
    pub meshes: u64,
    /// The D-buffer and shadow maps are this many texels square.
    pub map_size: u32,
    pub vt: VtVariant,
    pub knobs: &'a Knobs,
    /// V per pixel handed in from outside (the ray-cast reference), if any.
    pub external: Option<External<'a>>,
    /// The camera of this frame and its image size (screen-space methods draw before the camera
    /// pass; a light-space method ignores it).
    pub view: ScreenView,
}

impl FrameInputs<'_> {
    /// The casters welded with their adjacency (built once per mesh, on first use: methods
    /// without volumes never pay for it).
    pub fn prepared(&self) -> &PreparedCasters {
        self.prepared
            .get_or_init(|| PreparedCasters::new(self.scene))
    }

    /// The scene's disk light, for a method that needs one; an error naming `method` for a
    /// line light (the session refuses such a frame before it gets here).
    pub fn area(&self, method: &str) -> Result<&AreaLight, RenderError> {
        self.scene.light.as_area().ok_or_else(|| {
            RenderError::Request(format!(
                "method '{method}' needs a planar light (disk, rect or polygon), and this \
                 scene's light is a line"
            ))
        })
    }
}

/// What [`MethodState::prepare`](super::MethodState::prepare) works with: the frame's inputs, the light-space maps the
/// session shares between methods, and the frame's encoder (a method takes them apart with
/// `let Prepare(inputs, shared, rec) = p;`).
pub struct Prepare<'p, 'r>(
    pub &'p FrameInputs<'p>,
    pub &'p mut SharedMaps,
    pub &'p mut Recorder<'r>,
);

/// V per pixel handed in from outside, and a number that changes when its texture does.
#[derive(Clone, Copy)]
pub struct External<'a> {
    pub view: &'a wgpu::TextureView,
    pub generation: u64,
    /// The rays each pixel in front of the light has cast for it (the reference's samples so
    /// far; its cost view).
    pub rays: u32,
}

impl<'b, 'a: 'b> From<&'b FrameInputs<'a>> for MapInputs<'b> {
    fn from(inputs: &'b FrameInputs<'a>) -> MapInputs<'b> {
        MapInputs {
            ctx: inputs.ctx,
            scene: inputs.scene,
            surfaces: inputs.surfaces,
            light_view: inputs.light_view,
            revision: inputs.revision,
            size: inputs.map_size,
        }
    }
}
