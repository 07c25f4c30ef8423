//! `reference`: the ray-cast ground truth as a render method. V per pixel comes from rays to K
//! stratified disk samples ([`crate::render::reference`], on the CPU), is handed to the GPU as a
//! texture (the session's), and the camera pass shades it like every other method's
//! (`shaders/methods/reference.wgsl`).

use std::sync::Arc;

use super::{
    Bench, CameraBindings, FrameInputs, Knob, MethodPipeline, MethodSpec, MethodState, SharedMaps,
};
use crate::geometry::VtVariant;
use crate::render::timer::Recorder;
use crate::render::{texture_entry, view_entry, GpuContext, RenderError};

/// The most disk samples per pixel (the budget's).
pub const MAX_SAMPLES: u32 = crate::budget::MAX_REFERENCE_SAMPLES;

/// K, the disk samples per pixel.
pub static SAMPLES: Knob = Knob::int(
    "samples",
    "reference: rays to this many stratified disk samples per pixel (K)",
    1..=MAX_SAMPLES,
    crate::geometry::oracle::DEFAULT_SAMPLES as u32,
)
.budget("MAX_REFERENCE_SAMPLES");

pub static REFERENCE: MethodSpec = MethodSpec {
    name: "reference",
    description: "ray-cast ground truth (K disk samples per pixel)",
    shader: SHADER,
    knobs: &[&SAMPLES],
    cpu_side: true,
    hard: false,
    lights: None,
    adapter: super::needs::CAMERA_ONLY,
    bench: Bench {
        // Each timed frame takes one more sample per pixel, of a budget that never ends.
        label: Some("reference 1 spp"),
        knobs: &[(&SAMPLES, MAX_SAMPLES)],
    },
    overlay_note: None,
    line_samples: None,
    new: |ctx| Box::new(Reference::new(ctx)),
};

const SHADER: &str = "methods/reference.wgsl";

pub struct Reference {
    pipeline: Arc<MethodPipeline>,
    /// The bind group and the generation of the texture it binds.
    bind_group: Option<(wgpu::BindGroup, u64)>,
}

impl Reference {
    pub fn new(ctx: &GpuContext) -> Reference {
        let entries = [texture_entry(
            0,
            wgpu::ShaderStages::FRAGMENT,
            wgpu::TextureViewDimension::D2,
        )];
        Reference {
            pipeline: MethodPipeline::get(ctx, SHADER, &entries),
            bind_group: None,
        }
    }
}

impl MethodState for Reference {
    fn prepare(
        &mut self,
        inputs: &FrameInputs<'_>,
        _shared: &mut SharedMaps,
        _rec: &mut Recorder<'_>,
    ) -> Result<(), RenderError> {
        let Some(v) = inputs.external else {
            return Err(RenderError::Request(
                "the reference needs V per pixel: none has been computed for this frame".into(),
            ));
        };
        if self
            .bind_group
            .as_ref()
            .is_none_or(|(_, g)| *g != v.generation)
        {
            let group = inputs
                .ctx
                .device
                .create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("Reference::bind_group"),
                    layout: &self.pipeline.layout,
                    entries: &[view_entry(0, v.view)],
                });
            self.bind_group = Some((group, v.generation));
        }
        Ok(())
    }

    fn camera(&self, device: &wgpu::Device, vt: VtVariant) -> Option<CameraBindings<'_>> {
        self.bind_group.as_ref().map(|(g, _)| CameraBindings {
            pipeline: self.pipeline.pipeline(device, vt),
            bind_group: g,
        })
    }
}
