//! The `sampled` method's shadow maps (`shaders/passes/sample_maps.wgsl`): N stratified points on
//! the light (disk or segment), each a point light with a `size`² distance map, one layer of an
//! array texture (light-source sampling, Heckbert & Herf 1997). The method's camera pass averages their hard tests;
//! `linear-ssm` draws the same maps at its own points on a segment.
//!
//! Every point uses the D-buffer's frustum moved to that point: the frustum is fitted to the
//! directions `v − q` from every light point `q` (the disk's rim, the segment's ends) to every
//! caster vertex `v`, so it holds each caster as any light point sees it.

use std::sync::Arc;

use bytemuck::Zeroable;
use glam::{Mat4, Vec3};

use super::shadow_map::{DEPTH_FORMAT, DISTANCE_FORMAT, NO_SURFACE};
use super::{next_generation, LayeredTargets};
use crate::geometry::light_view::LightView;
use crate::geometry::outline::area_samples;
use crate::render::gpu_scene::GpuScene;
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, depth_attachment, depth_test, opaque, pipeline_layout, red,
    render_pipeline, shader_module, uniform_buffer, uniform_entry, GpuContext, PipelineSpec,
    SurfaceVertex,
};
use crate::scene::Light;

/// The most point lights (and map layers).
pub const MAX_LIGHTS: u32 = 64;

/// One point light (`shaders/shared/sample_lights.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleLight {
    pub view_proj: [[f32; 4]; 4],
    pub point: [f32; 3],
    pub _pad: f32,
}

/// Every point light and how to test against their maps.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleLights {
    pub lights: [SampleLight; MAX_LIGHTS as usize],
    pub count: u32,
    pub size: f32,
    pub texel_slope: f32,
    pub bias_constant: f32,
    pub bias_slope: f32,
    pub _pad0: f32,
    pub _pad1: f32,
    pub _pad2: f32,
}

const _: () = assert!(std::mem::size_of::<SampleLights>() == 64 * 80 + 32);

/// The N points on the light and their view-projections, with the test's bias: on a disk,
/// rectangle or polygon the oracle's stratified points, on a segment the centres of N equal pieces
/// (`a + (i + ½)/N · (b − a)`).
pub fn sample_lights(
    light: &Light,
    view: &LightView,
    n: u32,
    size: u32,
    bias: (f32, f32),
) -> SampleLights {
    let n = n.clamp(1, MAX_LIGHTS);
    let points: Vec<Vec3> = match light {
        Light::Area(d) => area_samples(d, n as usize),
        Light::Line(l) => (0..n).map(|i| l.at((i as f32 + 0.5) / n as f32)).collect(),
    };
    lights_at(light.center(), &points, view, size, bias)
}

/// Point lights at `points` (at most [`MAX_LIGHTS`]), each with `view` (the light view from
/// `center`) moved to it.
pub fn lights_at(
    center: Vec3,
    points: &[Vec3],
    view: &LightView,
    size: u32,
    bias: (f32, f32),
) -> SampleLights {
    let mut out = SampleLights::zeroed();
    let n = points.len().min(MAX_LIGHTS as usize);
    for (slot, &q) in out.lights.iter_mut().zip(&points[..n]) {
        let moved = view.view * Mat4::from_translation(center - q);
        *slot = SampleLight {
            view_proj: (view.projection * moved).to_cols_array_2d(),
            point: q.to_array(),
            _pad: 0.0,
        };
    }
    out.count = n as u32;
    out.size = size as f32;
    out.texel_slope = view.texel_slope(size);
    out.bias_constant = bias.0;
    out.bias_slope = bias.1;
    out
}

/// The pipeline, built once per device.
pub struct SampleMapsPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl SampleMapsPass {
    pub fn get(ctx: &GpuContext) -> Arc<SampleMapsPass> {
        ctx.shared(|device| {
            let module = shader_module(device, "passes/sample_maps.wgsl");
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("SampleMapsPass::layout"),
                entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
            });
            let pipeline = render_pipeline(
                device,
                &PipelineSpec {
                    label: "SampleMapsPass::pipeline",
                    module: &module,
                    layout: &pipeline_layout(device, "SampleMapsPass::pipeline_layout", &[&layout]),
                    vs: "vs_main",
                    fs: Some("fs_main"),
                    buffers: &[Some(SurfaceVertex::layout())],
                    targets: &[opaque(DISTANCE_FORMAT)],
                    cull: None,
                    depth: depth_test(wgpu::CompareFunction::Less),
                },
            );
            SampleMapsPass { pipeline, layout }
        })
    }
}

/// The array of distance maps.
pub struct SampleTargets {
    pub size: u32,
    pub layers: u32,
    /// The array texture (`linear-ssm` copies its layers out).
    pub texture: wgpu::Texture,
    /// The whole array, for the camera pass.
    pub array_view: wgpu::TextureView,
    layer_views: Vec<wgpu::TextureView>,
    depth: wgpu::TextureView,
    pub generation: u64,
}

/// A session's sampled maps.
pub struct SampleMaps {
    pass: Arc<SampleMapsPass>,
    /// The lights; the method's camera pass binds the same buffer.
    pub uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    targets: Option<SampleTargets>,
}

impl SampleMaps {
    pub fn new(ctx: &GpuContext) -> SampleMaps {
        let pass = SampleMapsPass::get(ctx);
        let uniforms = uniform_buffer::<SampleLights>(&ctx.device, "SampleMaps::uniforms");
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("SampleMaps::bind_group"),
            layout: &pass.layout,
            entries: &[buffer_entry(0, &uniforms)],
        });
        SampleMaps {
            pass,
            uniforms,
            bind_group,
            targets: None,
        }
    }

    pub fn targets(&self) -> Option<&SampleTargets> {
        self.targets.as_ref()
    }

    fn ensure_targets(&mut self, device: &wgpu::Device, size: u32, layers: u32) {
        let layers = layers.max(1);
        if self
            .targets
            .as_ref()
            .is_some_and(|t| t.size == size && t.layers == layers)
        {
            return;
        }
        let LayeredTargets {
            texture,
            array_view,
            layer_views,
            depth,
        } = LayeredTargets::new(
            device,
            "SampleTargets::maps",
            size,
            layers,
            (DISTANCE_FORMAT, DEPTH_FORMAT),
        );
        self.targets = Some(SampleTargets {
            size,
            layers,
            texture,
            array_view,
            layer_views,
            depth,
            generation: next_generation(),
        });
    }

    /// Record one render pass per layer for `lights` at `size`² texels.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        surfaces: &GpuScene,
        lights: &SampleLights,
    ) {
        self.ensure_targets(&ctx.device, lights.size as u32, lights.count);
        let Some(t) = &self.targets else { return };
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(lights));
        let span = rec.span("sample_maps");
        let last = t.layer_views.len().saturating_sub(1);
        for (layer, view) in t.layer_views.iter().enumerate() {
            let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("SampleMaps::layer"),
                color_attachments: &[cleared(view, red(NO_SURFACE))],
                depth_stencil_attachment: depth_attachment(
                    &t.depth,
                    wgpu::LoadOp::Clear(1.0),
                    false,
                ),
                timestamp_writes: span.writes(rec.timer, layer == 0, layer == last),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pass.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            let layer = layer as u32;
            surfaces.draw_instances(&mut pass, layer..layer + 1);
        }
    }
}
