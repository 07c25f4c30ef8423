//! Planar projected shadows (`shaders/passes/planar.wgsl`; Blinn 1988), drawn over the screen
//! prepass of [`super::stencil_volumes`]: for each receiver plane k (1-based stencil reference),
//! a **mark** of its pixels — the receiver's triangles, kept only where the surface the prepass
//! saw lies on its plane — then the **shadow**: every other caster flattened onto the plane from
//! the light, kept where the stencil holds k, each pixel darkened once (the stencil is zeroed as
//! it is drawn: the trick that stops double blending where projected triangles overlap). V is
//! multiplied into a target of its own ([`SHADE_FORMAT`], blendable on every adapter, where
//! the screen targets' R32Float visibility is not), cleared to 1: every pixel that is not a
//! receiver's stays lit, which is the method.

use std::sync::Arc;

use glam::Mat4;

use super::stencil_volumes::{depth_stencil, stencil_both, ScreenTargets};
use crate::geometry::planar::{projection, PlanarReceiver, MAX_PLANAR_RECEIVERS};
use crate::render::gpu_scene::VertexChunks;
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, pipeline_layout, shader_module, texture_entry, uniform_buffer, uniform_entry,
    view_entry, GpuContext, Texture,
};

/// V of the planar shadows: blendable without features, exact for 1, ½ and the like.
pub const SHADE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;

/// `Receiver` of `shaders/passes/planar.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ReceiverUniform {
    pub projection: [[f32; 4]; 4],
    pub plane: [f32; 4],
}

/// `PlanarUniforms` of `shaders/passes/planar.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PlanarUniforms {
    pub infinite_view_proj: [[f32; 4]; 4],
    /// x: V where a shadow lands (1 − opacity); y: the plane tolerance, relative to the distance
    /// from the eye.
    pub shade: [f32; 4],
    pub eye: [f32; 4],
    pub receivers: [ReceiverUniform; MAX_PLANAR_RECEIVERS],
}

const _: () = assert!(std::mem::size_of::<PlanarUniforms>() == 96 + 80 * MAX_PLANAR_RECEIVERS);

/// A pixel belongs to a receiver when the surface there is this close to its plane, relative to
/// its distance from the eye (the prepass's and the mark's interpolation differ by far less).
pub const PLANE_TOLERANCE: f32 = 1e-4;

impl PlanarUniforms {
    pub fn new(
        infinite_view_proj: Mat4,
        eye: glam::Vec3,
        light: glam::Vec3,
        receivers: &[PlanarReceiver],
        shadow_v: f32,
    ) -> PlanarUniforms {
        let mut u = PlanarUniforms {
            infinite_view_proj: infinite_view_proj.to_cols_array_2d(),
            shade: [shadow_v, PLANE_TOLERANCE, 0.0, 0.0],
            eye: eye.extend(1.0).to_array(),
            ..PlanarUniforms::default()
        };
        for (slot, r) in u.receivers.iter_mut().zip(receivers) {
            *slot = ReceiverUniform {
                projection: projection(r.plane, light).to_cols_array_2d(),
                plane: r.plane.to_array(),
            };
        }
        u
    }
}

/// The pipelines, built once per device (for one depth-stencil format).
pub struct PlanarPass {
    layout: wgpu::BindGroupLayout,
    mark: wgpu::RenderPipeline,
    shadow: wgpu::RenderPipeline,
}

impl PlanarPass {
    pub fn get(ctx: &GpuContext, format: wgpu::TextureFormat) -> Arc<PlanarPass> {
        let name = if format == wgpu::TextureFormat::Depth32FloatStencil8 {
            "d32s8"
        } else {
            "d24s8"
        };
        ctx.shared_named(name, |device| {
            let module = shader_module(device, "passes/planar.wgsl");
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("PlanarPass::layout"),
                entries: &[
                    uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT),
                    texture_entry(
                        1,
                        wgpu::ShaderStages::FRAGMENT,
                        wgpu::TextureViewDimension::D2,
                    ),
                ],
            });
            let pl = pipeline_layout(device, "PlanarPass::pipeline_layout", &[&layout]);
            let buffers = [Some(super::stencil_volumes::volume_vertex_layout())];
            let make = |label: &str,
                        vs: &str,
                        fs: &str,
                        target: wgpu::ColorTargetState,
                        stencil: wgpu::StencilState| {
                let targets = [Some(target)];
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&pl),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(vs),
                        compilation_options: Default::default(),
                        buffers: &buffers,
                    },
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: depth_stencil(
                        format,
                        false,
                        wgpu::CompareFunction::Always,
                        stencil,
                    ),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fs),
                        compilation_options: Default::default(),
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
            let mark = make(
                "PlanarPass::mark",
                "vs_mark",
                "fs_mark",
                wgpu::ColorTargetState {
                    format: SHADE_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::empty(),
                },
                stencil_both(
                    wgpu::StencilFaceState {
                        compare: wgpu::CompareFunction::Always,
                        fail_op: wgpu::StencilOperation::Keep,
                        depth_fail_op: wgpu::StencilOperation::Keep,
                        pass_op: wgpu::StencilOperation::Replace,
                    },
                    0xff,
                ),
            );
            // V·shade: each marked pixel darkened once (the stencil then reads 0).
            let multiply = wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::Src,
                operation: wgpu::BlendOperation::Add,
            };
            let shadow = make(
                "PlanarPass::shadow",
                "vs_shadow",
                "fs_shadow",
                wgpu::ColorTargetState {
                    format: SHADE_FORMAT,
                    blend: Some(wgpu::BlendState {
                        color: multiply,
                        alpha: multiply,
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                },
                stencil_both(
                    wgpu::StencilFaceState {
                        compare: wgpu::CompareFunction::Equal,
                        fail_op: wgpu::StencilOperation::Keep,
                        depth_fail_op: wgpu::StencilOperation::Keep,
                        pass_op: wgpu::StencilOperation::Zero,
                    },
                    0xff,
                ),
            );
            PlanarPass {
                layout,
                mark,
                shadow,
            }
        })
    }
}

/// One receiver's geometry on the GPU: its own triangles, and every caster but itself.
pub struct ReceiverDraws {
    pub surface: VertexChunks,
    pub casters: Vec<Arc<VertexChunks>>,
}

/// A method state's planar pass: uniforms and bind group.
pub struct Planar {
    pass: Arc<PlanarPass>,
    uniforms: wgpu::Buffer,
    /// V per pixel, and the generation of the screen targets it was made for.
    shade: Option<(Texture, u64)>,
    /// The bind group and the generation of the screen targets it binds.
    bind_group: Option<(wgpu::BindGroup, u64)>,
}

impl Planar {
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat) -> Planar {
        Planar {
            pass: PlanarPass::get(ctx, format),
            uniforms: uniform_buffer::<PlanarUniforms>(&ctx.device, "Planar::uniforms"),
            shade: None,
            bind_group: None,
        }
    }

    /// V per pixel of the last frame (the screen targets' size; remade with them).
    pub fn shade(&self) -> Option<&Texture> {
        self.shade.as_ref().map(|(t, _)| t)
    }

    /// Darken the receivers' pixels of [`Planar::shade`] where the casters' projections land;
    /// it is cleared to 1 first. `targets` holds this frame's prepass.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        targets: &ScreenTargets,
        uniforms: &PlanarUniforms,
        receivers: &[ReceiverDraws],
    ) {
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
        if self
            .shade
            .as_ref()
            .is_none_or(|(_, g)| *g != targets.generation)
        {
            let texture = Texture::new(
                &ctx.device,
                "Planar::shade",
                (targets.width, targets.height),
                SHADE_FORMAT,
                wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
            );
            self.shade = Some((texture, targets.generation));
        }
        let Some((shade, _)) = &self.shade else {
            return;
        };
        if self
            .bind_group
            .as_ref()
            .is_none_or(|(_, g)| *g != targets.generation)
        {
            let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("Planar::bind_group"),
                layout: &self.pass.layout,
                entries: &[
                    buffer_entry(0, &self.uniforms),
                    view_entry(1, &targets.position.view),
                ],
            });
            self.bind_group = Some((group, targets.generation));
        }
        let Some((group, _)) = &self.bind_group else {
            return;
        };
        let span = rec.span("planar_shadows");
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("Planar::pass"),
            color_attachments: &[crate::render::cleared(&shade.view, crate::render::red(1.0))],
            depth_stencil_attachment: targets.read_only_depth_stencil(),
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, group, &[]);
        for (k, r) in receivers.iter().enumerate().take(MAX_PLANAR_RECEIVERS) {
            let k = k as u32;
            pass.set_stencil_reference(k + 1);
            pass.set_pipeline(&self.pass.mark);
            r.surface.draw_instance(&mut pass, k);
            pass.set_pipeline(&self.pass.shadow);
            for c in &r.casters {
                c.draw_instance(&mut pass, k);
            }
        }
    }
}
