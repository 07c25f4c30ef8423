//! The variance shadow map's moments (Donnelly & Lauritzen 2006): the centre's shadow map's
//! `(|cx_o|, |cx_o|²)` box-filtered over `(2R + 1)²` texels in two separable draws into
//! `Rg32Float` targets (`shaders/passes/moments.wgsl`). The filter is what makes the map
//! "filterable": a receiver reads one texel and gets the mean and variance of the depths around
//! it.

use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, fullscreen_pass, texture_entry, uniform_entry, view_entry, GpuContext,
    Texture,
};

use super::next_generation;

pub const MOMENTS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// `MomentUniforms` of `shaders/passes/moments.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MomentUniforms {
    pub step: [i32; 2],
    pub radius: i32,
    pub from_distance: u32,
    pub far: f32,
    pub _pad: [f32; 3],
}

struct MomentsPipeline {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

/// The filtered moments, and a number that changes whenever they are made again.
pub struct MomentTargets {
    pub size: u32,
    /// After the first (horizontal) draw.
    across: Texture,
    /// The filtered moments the camera pass reads.
    pub moments: Texture,
    pub generation: u64,
}

pub struct Moments {
    uniforms: [wgpu::Buffer; 2],
    targets: Option<MomentTargets>,
}

impl Moments {
    pub fn new(ctx: &GpuContext) -> Moments {
        let buffer = |label| crate::render::uniform_buffer::<MomentUniforms>(&ctx.device, label);
        Moments {
            uniforms: [buffer("Moments::across"), buffer("Moments::down")],
            targets: None,
        }
    }

    pub fn targets(&self) -> Option<&MomentTargets> {
        self.targets.as_ref()
    }

    /// Filter `distance` (the centre's `size`² distance map) with radius `radius` texels into
    /// the moments; `far`: the light view's far plane, the distance where no surface is.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        distance: &wgpu::TextureView,
        size: u32,
        radius: u32,
        far: f32,
    ) {
        let pipe = ctx.shared(|device| {
            let (pipeline, layout) = fullscreen_pass(
                device,
                "Moments",
                "passes/moments.wgsl",
                &[
                    uniform_entry(0, wgpu::ShaderStages::FRAGMENT),
                    texture_entry(
                        1,
                        wgpu::ShaderStages::FRAGMENT,
                        wgpu::TextureViewDimension::D2,
                    ),
                ],
                MOMENTS_FORMAT,
            );
            MomentsPipeline { pipeline, layout }
        });
        if self.targets.as_ref().is_none_or(|t| t.size != size) {
            use wgpu::TextureUsages as U;
            let target = |label| {
                Texture::new(
                    &ctx.device,
                    label,
                    (size, size),
                    MOMENTS_FORMAT,
                    U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
                )
            };
            self.targets = Some(MomentTargets {
                size,
                across: target("Moments::across"),
                moments: target("Moments::moments"),
                generation: 0,
            });
        }
        let Some(t) = &mut self.targets else { return };
        t.generation = next_generation();
        let radius = radius.min(64) as i32;
        for (i, (step, from_distance)) in [([1, 0], 1u32), ([0, 1], 0u32)].into_iter().enumerate() {
            let u = MomentUniforms {
                step,
                radius,
                from_distance,
                far,
                _pad: [0.0; 3],
            };
            ctx.queue
                .write_buffer(&self.uniforms[i], 0, bytemuck::bytes_of(&u));
        }
        let groups: Vec<wgpu::BindGroup> = [
            (distance, &t.across.view),
            (&t.across.view, &t.moments.view),
        ]
        .iter()
        .enumerate()
        .map(|(i, (input, _))| {
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("Moments::bind_group"),
                layout: &pipe.layout,
                entries: &[buffer_entry(0, &self.uniforms[i]), view_entry(1, input)],
            })
        })
        .collect();
        let span = rec.span("vsm_moments");
        for (i, out) in [&t.across.view, &t.moments.view].into_iter().enumerate() {
            let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("Moments::pass"),
                color_attachments: &[cleared(out, wgpu::Color::TRANSPARENT)],
                depth_stencil_attachment: None,
                timestamp_writes: span.writes(rec.timer, i == 0, i == 1),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipe.pipeline);
            pass.set_bind_group(0, &groups[i], &[]);
            pass.draw(0..3, 0..1);
        }
    }
}
