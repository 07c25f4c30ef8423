//! The floor (`shaders/passes/floor.wgsl`): the scene drawn with a flat colour into Rgba8 and a
//! depth buffer, the cheapest image of it. `dbuffer bench` gives every frame as a ratio to it, so
//! what a method costs beyond drawing the scene at all is plain.

use std::sync::Arc;

use glam::Mat4;

use super::camera::{self, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::gpu_scene::GpuScene;
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, opaque, pipeline_layout, render_pipeline, shader_module, uniform_buffer,
    uniform_entry, GpuContext, PipelineSpec, SurfaceVertex, Texture,
};
use crate::scene::Scene;

/// The pipeline, built once per device.
pub struct FloorPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl FloorPass {
    pub fn get(ctx: &GpuContext) -> Arc<FloorPass> {
        ctx.shared(|device| {
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("FloorPass::layout"),
                entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX)],
            });
            let module = shader_module(device, "passes/floor.wgsl");
            let pipeline = render_pipeline(
                device,
                &PipelineSpec {
                    label: "FloorPass::pipeline",
                    module: &module,
                    layout: &pipeline_layout(device, "FloorPass::pipeline_layout", &[&layout]),
                    vs: "vs_main",
                    fs: Some("fs_main"),
                    buffers: &[Some(SurfaceVertex::layout())],
                    targets: &[opaque(COLOR_FORMAT)],
                    cull: None,
                    depth: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Greater),
                        stencil: wgpu::StencilState::default(),
                        bias: wgpu::DepthBiasState::default(),
                    }),
                },
            );
            FloorPass { pipeline, layout }
        })
    }
}

/// The floor's targets and uniforms for one view size.
pub struct Floor {
    pass: Arc<FloorPass>,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    targets: Option<(Texture, Texture)>,
}

impl Floor {
    pub fn new(ctx: &GpuContext) -> Floor {
        let pass = FloorPass::get(ctx);
        let uniforms = uniform_buffer::<[[f32; 4]; 4]>(&ctx.device, "Floor::uniforms");
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Floor::bind_group"),
            layout: &pass.layout,
            entries: &[buffer_entry(0, &uniforms)],
        });
        Floor {
            pass,
            uniforms,
            bind_group,
            targets: None,
        }
    }

    /// Record the scene in flat colour at `width`×`height`.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        scene: &Scene,
        surfaces: &GpuScene,
        (width, height): (u32, u32),
    ) {
        if self
            .targets
            .as_ref()
            .is_none_or(|(c, _)| c.texture.width() != width || c.texture.height() != height)
        {
            use wgpu::TextureUsages as U;
            let color = Texture::new(
                &ctx.device,
                "Floor::color",
                (width, height),
                COLOR_FORMAT,
                U::RENDER_ATTACHMENT,
            );
            let depth = Texture::new(
                &ctx.device,
                "Floor::depth",
                (width, height),
                DEPTH_FORMAT,
                U::RENDER_ATTACHMENT,
            );
            self.targets = Some((color, depth));
        }
        let Some((color, depth)) = &self.targets else {
            return;
        };
        let vp: Mat4 = camera::view_projection(scene, surfaces.bounds, width, height);
        ctx.queue.write_buffer(
            &self.uniforms,
            0,
            bytemuck::bytes_of(&vp.to_cols_array_2d()),
        );
        let span = rec.span("floor");
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("Floor::pass"),
            color_attachments: &[cleared(&color.view, wgpu::Color::TRANSPARENT)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth.view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pass.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        surfaces.draw(&mut pass);
    }
}
