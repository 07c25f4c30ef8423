//! `reference-hard`: the exact hard shadow, the oracle for every method that uses the light's
//! centre as a point light. One ray per pixel from the surface point under the pixel's centre to
//! the light's centre through the CPU's BVH ([`crate::render::reference::compute_hard`]), made
//! again when the camera, the light, a mesh or the image size changed (or the bench asks, by
//! [`MethodState::invalidate`]); the camera pass shades it like the area reference
//! (`shaders/methods/reference.wgsl`). The lab casts those rays on a worker thread instead and
//! hands V in (`Session::set_reference_hard`, seen here as [`FrameInputs::external`]): a frame
//! with V handed in only binds it, and never casts a ray on the thread that records it.

use std::sync::Arc;
use std::time::Instant;

use super::{
    Bench, CameraBindings, FrameInputs, MethodPipeline, MethodSpec, MethodState, SharedMaps,
};
use crate::geometry::VtVariant;
use crate::render::timer::Recorder;
use crate::render::{texture_entry, view_entry, GpuContext, RenderError, Texture};
use crate::scene::Camera;

pub static REFERENCE_HARD: MethodSpec = MethodSpec {
    name: "reference-hard",
    description: "exact hard shadow: one ray per pixel to the light centre",
    shader: SHADER,
    knobs: &[],
    cpu_side: true,
    hard: true,
    lights: None,
    adapter: super::needs::CAMERA_ONLY,
    bench: Bench::DEFAULTS,
    overlay_note: None,
    line_samples: None,
    new: |ctx| Box::new(ReferenceHard::new(ctx)),
};

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

/// Which texture the bind group holds.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Bound {
    /// This method's own texture (rays cast in `prepare`).
    Own,
    /// V handed in from outside, by its generation.
    External(u64),
}

pub struct ReferenceHard {
    pipeline: Arc<MethodPipeline>,
    texture: Option<Texture>,
    bind_group: Option<(wgpu::BindGroup, Bound)>,
    key: Option<Key>,
    builds: u64,
    ms: f64,
}

impl ReferenceHard {
    pub fn new(ctx: &GpuContext) -> ReferenceHard {
        let entries = [texture_entry(
            0,
            wgpu::ShaderStages::FRAGMENT,
            wgpu::TextureViewDimension::D2,
        )];
        ReferenceHard {
            pipeline: MethodPipeline::get(ctx, SHADER, &entries),
            texture: None,
            bind_group: None,
            key: None,
            builds: 0,
            ms: 0.0,
        }
    }
}

impl ReferenceHard {
    fn bind(&self, device: &wgpu::Device, view: &wgpu::TextureView) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ReferenceHard::bind_group"),
            layout: &self.pipeline.layout,
            entries: &[view_entry(0, view)],
        })
    }
}

impl MethodState for ReferenceHard {
    fn prepare(
        &mut self,
        inputs: &FrameInputs<'_>,
        _shared: &mut SharedMaps,
        _rec: &mut Recorder<'_>,
    ) -> Result<(), RenderError> {
        if let Some(v) = inputs.external {
            // Computed off this thread for exactly this view: bind it.
            if self
                .bind_group
                .as_ref()
                .is_none_or(|(_, b)| *b != Bound::External(v.generation))
            {
                let group = self.bind(&inputs.ctx.device, v.view);
                self.bind_group = Some((group, Bound::External(v.generation)));
            }
            return Ok(());
        }
        let (w, h) = (inputs.view.width, inputs.view.height);
        let key = Key {
            revision: inputs.revision,
            camera: inputs.scene.camera,
            width: w,
            height: h,
        };
        if self.key == Some(key) {
            if let (Some(t), Some((_, Bound::External(_)))) = (&self.texture, &self.bind_group) {
                let group = self.bind(&inputs.ctx.device, &t.view);
                self.bind_group = Some((group, Bound::Own));
            }
            return Ok(());
        }
        let t = Instant::now();
        let computed = crate::render::reference::compute_hard(inputs.scene, w, h);
        let device = &inputs.ctx.device;
        let mut fresh = false;
        if self
            .texture
            .as_ref()
            .is_none_or(|t| (t.texture.width(), t.texture.height()) != (w, h))
        {
            let texture = Texture::new(
                device,
                "ReferenceHard::visibility",
                (w, h),
                wgpu::TextureFormat::R32Float,
                wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            );
            self.texture = Some(texture);
            fresh = true;
        }
        if fresh
            || self
                .bind_group
                .as_ref()
                .is_none_or(|(_, b)| *b != Bound::Own)
        {
            if let Some(t) = &self.texture {
                let group = self.bind(device, &t.view);
                self.bind_group = Some((group, Bound::Own));
            }
        }
        if let Some(texture) = &self.texture {
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
        Ok(())
    }

    fn camera(&self, device: &wgpu::Device, vt: VtVariant) -> Option<CameraBindings<'_>> {
        self.bind_group.as_ref().map(|(g, _)| CameraBindings {
            pipeline: self.pipeline.pipeline(device, vt),
            bind_group: g,
        })
    }

    /// The rays of the last image: how many images were made and the last one's milliseconds.
    fn geometry_builds(&self) -> (u64, f64) {
        (self.builds, self.ms)
    }

    fn invalidate(&mut self) {
        self.key = None;
    }
}
