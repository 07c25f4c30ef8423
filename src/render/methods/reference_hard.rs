//! `reference-hard`: the exact hard shadow, the oracle for every method that uses the light's
//! centre as a point light. One ray per pixel from the surface point under the pixel's centre to
//! the light's centre through the CPU's BVH ([`crate::render::reference::compute_hard`]), made
//! again when the camera, the light, a mesh or the image size changed (or the bench asks, by
//! [`MethodState::invalidate`]); the camera pass shades it like the area reference
//! (`shaders/methods/reference.wgsl`). The lab casts those rays on a worker thread instead and
//! hands V in (`Session::set_reference_hard`, seen here as [`super::FrameInputs::external`]):
//! a frame with V handed in only binds it, and never casts a ray on the thread that records it.

use std::time::Instant;

use super::reference::{camera_entries, RaysUniform};
use super::{CameraGroup, Cost, MethodSpec, MethodState, Prepare};
use crate::render::passes::next_generation;
use crate::render::{buffer_entry, view_entry, GpuContext, RenderError, Texture};
use crate::scene::Camera;

pub static REFERENCE_HARD: MethodSpec = MethodSpec::new("reference-hard", SHADER, |ctx| {
    Box::new(ReferenceHard::new(ctx))
})
.about("exact hard shadow: one ray per pixel to the light centre")
.cpu_side()
.hard()
.cost(Cost::counted("rays").constant("one ray to the light's centre per pixel in front of it"))
.fixed_quality("the exact hard shadow: one ray a pixel");

/// The area reference's camera shader: V from a texture at the pixel.
const SHADER: &str = "methods/reference.wgsl";

/// What the image depends on.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Key {
    revision: u64,
    camera: Camera,
    width: u32,
    height: u32,
}

/// Which texture the bind group holds, by its generation.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Bound {
    /// This method's own texture (rays cast in `prepare`).
    Own(u64),
    /// V handed in from outside.
    External(u64),
}

pub struct ReferenceHard {
    camera: CameraGroup,
    /// 1: one ray a pixel (the cost view).
    rays: RaysUniform,
    /// Its own texture and that texture's generation.
    texture: Option<(Texture, u64)>,
    key: Option<Key>,
    builds: u64,
    ms: f64,
}

impl ReferenceHard {
    pub fn new(ctx: &GpuContext) -> ReferenceHard {
        ReferenceHard {
            camera: CameraGroup::new(ctx, SHADER, &camera_entries()),
            rays: RaysUniform::new(ctx),
            texture: None,
            key: None,
            builds: 0,
            ms: 0.0,
        }
    }
}

impl MethodState for ReferenceHard {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, ..) = p;
        let device = &inputs.ctx.device;
        self.rays.write(inputs.ctx, 1);
        if let Some(v) = inputs.external {
            // Computed off this thread for exactly this view: bind it.
            let bound = Bound::External(v.generation);
            self.camera.bind(
                device,
                bound,
                &[view_entry(0, v.view), buffer_entry(1, &self.rays.buffer)],
            );
            return Ok(&self.camera);
        }
        let (w, h) = (inputs.view.width, inputs.view.height);
        let key = Key {
            revision: inputs.revision,
            camera: inputs.scene.camera,
            width: w,
            height: h,
        };
        if self.key != Some(key) {
            let t = Instant::now();
            let computed = crate::render::reference::compute_hard(inputs.scene, w, h);
            if self
                .texture
                .as_ref()
                .is_none_or(|(t, _)| (t.texture.width(), t.texture.height()) != (w, h))
            {
                let texture = Texture::new(
                    device,
                    "ReferenceHard::visibility",
                    (w, h),
                    wgpu::TextureFormat::R32Float,
                    wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                );
                self.texture = Some((texture, next_generation()));
            }
            if let Some((texture, _)) = &self.texture {
                inputs.ctx.queue.write_texture(
                    texture.texture.as_image_copy(),
                    bytemuck::cast_slice(&computed.visibility),
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(w * 4),
                        rows_per_image: Some(h),
                    },
                    texture.texture.size(),
                );
            }
            self.key = Some(key);
            self.builds += 1;
            self.ms = t.elapsed().as_secs_f64() * 1e3;
        }
        if let Some((t, generation)) = &self.texture {
            let bound = Bound::Own(*generation);
            self.camera.bind(
                device,
                bound,
                &[view_entry(0, &t.view), buffer_entry(1, &self.rays.buffer)],
            );
        }
        Ok(&self.camera)
    }

    /// The rays of the last image: how many images were made and the last one's milliseconds.
    fn geometry_builds(&self) -> (u64, f64) {
        (self.builds, self.ms)
    }

    fn invalidate(&mut self) {
        self.key = None;
    }
}
