//! `reference`: the ray-cast ground truth as a render method. V per pixel comes from rays to K
//! stratified disk samples ([`crate::render::reference`], on the CPU), is handed to the GPU as a
//! texture (the session's), and the camera pass shades it like every other method's
//! (`shaders/methods/reference.wgsl`).

use super::{
    v_texture_entries, CameraGroup, Cost, Knob, MethodSpec, MethodState, Prepare, Quality,
};
use crate::render::{
    buffer_entry, uniform_buffer, uniform_entry, view_entry, GpuContext, RenderError,
};

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

pub static REFERENCE: MethodSpec =
    MethodSpec::new("reference", SHADER, |ctx| Box::new(Reference::new(ctx)))
        .about("ray-cast ground truth (K disk samples per pixel)")
        .knobs(&[&SAMPLES])
        .cpu_side()
        .cost(
            Cost::counted("rays so far")
                .constant("every pixel in front of the light has cast the samples taken so far"),
        )
        // Each timed frame takes one more sample per pixel, of a budget that never ends.
        .bench("reference 1 spp", &[(&SAMPLES, MAX_SAMPLES)])
        // Rays on the CPU: the study times its wall clock, as the bench does.
        .sweep(&[Quality::Knob(&SAMPLES)], &[&[1], &[4], &[16], &[64]]);

const SHADER: &str = "methods/reference.wgsl";

pub struct Reference {
    /// Bound for the generation of the V handed in.
    camera: CameraGroup,
    rays: RaysUniform,
}

impl Reference {
    pub fn new(ctx: &GpuContext) -> Reference {
        Reference {
            camera: CameraGroup::new(ctx, SHADER, &camera_entries()),
            rays: RaysUniform::new(ctx),
        }
    }
}

/// Group 1 of `methods/reference.wgsl` (this method's and `reference-hard`'s): V per pixel and
/// the rays per pixel behind it.
pub(super) fn camera_entries() -> [wgpu::BindGroupLayoutEntry; 2] {
    let [v] = v_texture_entries();
    [v, uniform_entry(1, wgpu::ShaderStages::FRAGMENT)]
}

/// `ReferenceParams` of `methods/reference.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ReferenceParams {
    /// The rays each pixel in front of the light has cast, for the cost view.
    pub rays: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// The buffer of its [`ReferenceParams`] (this method's and `reference-hard`'s).
pub(super) struct RaysUniform {
    pub buffer: wgpu::Buffer,
}

impl RaysUniform {
    pub fn new(ctx: &GpuContext) -> RaysUniform {
        RaysUniform {
            buffer: uniform_buffer::<ReferenceParams>(&ctx.device, "reference::params"),
        }
    }

    pub fn write(&self, ctx: &GpuContext, rays: u32) {
        let params = ReferenceParams {
            rays,
            ..ReferenceParams::default()
        };
        ctx.queue
            .write_buffer(&self.buffer, 0, bytemuck::bytes_of(&params));
    }
}

impl MethodState for Reference {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, ..) = p;
        let Some(v) = inputs.external else {
            return Err(RenderError::Request(
                "the reference needs V per pixel: none has been computed for this frame".into(),
            ));
        };
        self.rays.write(inputs.ctx, v.rays);
        self.camera.bind(
            &inputs.ctx.device,
            v.generation,
            &[view_entry(0, v.view), buffer_entry(1, &self.rays.buffer)],
        );
        Ok(&self.camera)
    }
}
