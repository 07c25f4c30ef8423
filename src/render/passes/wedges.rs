//! Penumbra wedges over the camera's pixels (`shaders/passes/wedges.wgsl`,
//! `shaders/passes/wedges_resolve.wgsl`; CPU twin [`crate::geometry::wedges`]), after the screen
//! prepass and the hard stencil count from the disk's centre of
//! [`super::stencil_volumes::ScreenPass`] (the same targets: no second copy of either):
//!
//! 1. **coverage**: every wedge's back faces (front faces culled, no depth test: one fragment
//!    per pixel whose ray meets the wedge, the camera inside one included), each fragment
//!    adding its edge's signed coverage of the disk, as the receiver in the prepass's position
//!    target sees it, into the sum buffer's x (additive blending), and 1 into its y (the wedge
//!    fragments per pixel, the method's cost view). The buffer is `Rg32Float` where the
//!    device blends 32-bit floats (`FLOAT32_BLENDABLE`), else `Rg16Float` (11 significant bits: a
//!    sum of a few terms within about 1e-3; the 2003 papers fought 8-bit buffers);
//! 2. **resolve**: `V = clamp(1 − H − sum, 0, 1)` into the screen visibility target, `H` from
//!    the stencil test (two pipelines: count zero, count not zero).

use std::sync::Arc;

use super::stencil_volumes::{depth_stencil, stencil_both, ScreenPass};
use crate::geometry::wedges::DiskFrame;
use crate::render::gpu_scene::VertexChunks;
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, pipeline_layout, shader_module, texture_entry, uniform_buffer,
    uniform_entry, view_entry, GpuContext, Texture,
};
use crate::scene::AreaLight;

/// `WedgeDisk` of `shaders/passes/wedges.wgsl`: the disk's frame, `u × w = −normal`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WedgeDisk {
    /// xyz: the centre; w: the radius (of the disk a polygon fits in).
    pub center: [f32; 4],
    pub normal: [f32; 4],
    pub u: [f32; 4],
    pub w: [f32; 4],
    /// x: a rectangle's or polygon's corner count (0: a disk); y: their area (radius units²).
    pub polygon: [f32; 4],
    /// The corners in `(u, w)`, radius units, counter-clockwise: two per vector.
    pub corners: [[f32; 4]; 8],
}

const _: () = assert!(std::mem::size_of::<WedgeDisk>() == 208);

impl WedgeDisk {
    pub fn new(light: &AreaLight) -> WedgeDisk {
        let f = DiskFrame::new(light);
        let v = |d: glam::DVec3, w: f64| [d.x as f32, d.y as f32, d.z as f32, w as f32];
        let mut corners = [[0.0; 4]; 8];
        for (i, p) in f.corners().iter().enumerate() {
            corners[i / 2][2 * (i % 2)] = p.x as f32;
            corners[i / 2][2 * (i % 2) + 1] = p.y as f32;
        }
        WedgeDisk {
            center: v(f.center, f.radius),
            normal: v(f.normal, 0.0),
            u: v(f.u, 0.0),
            w: v(f.w, 0.0),
            polygon: [f.corners().len() as f32, f.corner_area() as f32, 0.0, 0.0],
            corners,
        }
    }
}

/// A corner of a wedge triangle and the silhouette edge the wedge belongs to (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WedgeVertex {
    pub position: [f32; 3],
    pub _pad0: f32,
    pub e0: [f32; 3],
    pub _pad1: f32,
    pub e1: [f32; 3],
    pub _pad2: f32,
}

const _: () = assert!(std::mem::size_of::<WedgeVertex>() == 48);

impl WedgeVertex {
    const ATTRIBUTES: [wgpu::VertexAttribute; 3] = [
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 0,
            shader_location: 0,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 16,
            shader_location: 1,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 32,
            shader_location: 2,
        },
    ];

    fn layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<WedgeVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Self::ATTRIBUTES,
        }
    }
}

/// The pipelines, built once per device.
pub struct WedgePass {
    /// The coverage sum's format (see the module documentation).
    pub sum_format: wgpu::TextureFormat,
    /// Under a disk and under a polygon (`POLYGON_LIGHT` of the shader): a CPU rasteriser runs
    /// every branch, so one pipeline for both paid the polygon's clip under a disk too (5× the
    /// pass on lavapipe).
    coverage: [wgpu::RenderPipeline; 2],
    coverage_layout: wgpu::BindGroupLayout,
    /// Stencil count zero, not zero.
    resolve: [wgpu::RenderPipeline; 2],
    resolve_layout: wgpu::BindGroupLayout,
}

impl WedgePass {
    pub fn get(ctx: &GpuContext, screen: &ScreenPass) -> Arc<WedgePass> {
        ctx.shared(|device| {
            let sum_format = if device
                .features()
                .contains(wgpu::Features::FLOAT32_BLENDABLE)
            {
                wgpu::TextureFormat::Rg32Float
            } else {
                wgpu::TextureFormat::Rg16Float
            };
            let module = shader_module(device, "passes/wedges.wgsl");
            let coverage_layout =
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("WedgePass::coverage_layout"),
                    entries: &[
                        uniform_entry(0, wgpu::ShaderStages::FRAGMENT),
                        texture_entry(
                            1,
                            wgpu::ShaderStages::FRAGMENT,
                            wgpu::TextureViewDimension::D2,
                        ),
                    ],
                });
            let layout = pipeline_layout(
                device,
                "WedgePass::coverage",
                &[&screen.pass.layout, &coverage_layout],
            );
            let add = wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            };
            let targets = [Some(wgpu::ColorTargetState {
                format: sum_format,
                blend: Some(wgpu::BlendState {
                    color: add,
                    alpha: add,
                }),
                write_mask: wgpu::ColorWrites::RED | wgpu::ColorWrites::GREEN,
            })];
            let coverage = [0.0, 1.0].map(|polygon| {
                let constants = [("POLYGON_LIGHT", polygon)];
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("WedgePass::coverage"),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_wedge"),
                        compilation_options: Default::default(),
                        buffers: &[Some(WedgeVertex::layout())],
                    },
                    // Back faces only: one fragment per pixel whose ray meets the (convex) wedge.
                    primitive: wgpu::PrimitiveState {
                        cull_mode: Some(wgpu::Face::Front),
                        ..Default::default()
                    },
                    depth_stencil: None,
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_wedge"),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants: &constants,
                            ..Default::default()
                        },
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            });

            let module = shader_module(device, "passes/wedges_resolve.wgsl");
            let resolve_layout =
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("WedgePass::resolve_layout"),
                    entries: &[texture_entry(
                        0,
                        wgpu::ShaderStages::FRAGMENT,
                        wgpu::TextureViewDimension::D2,
                    )],
                });
            let layout = pipeline_layout(device, "WedgePass::resolve", &[&resolve_layout]);
            let resolve = [
                ("fs_outside", wgpu::CompareFunction::Equal),
                ("fs_inside", wgpu::CompareFunction::NotEqual),
            ]
            .map(|(fs, compare)| {
                let test = stencil_both(
                    wgpu::StencilFaceState {
                        compare,
                        fail_op: wgpu::StencilOperation::Keep,
                        depth_fail_op: wgpu::StencilOperation::Keep,
                        pass_op: wgpu::StencilOperation::Keep,
                    },
                    0,
                );
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(fs),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: depth_stencil(
                        screen.pass.format,
                        false,
                        wgpu::CompareFunction::Always,
                        test,
                    ),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fs),
                        compilation_options: Default::default(),
                        targets: &[crate::render::opaque(
                            super::stencil_volumes::VISIBILITY_FORMAT,
                        )],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            });
            WedgePass {
                sum_format,
                coverage,
                coverage_layout,
                resolve,
                resolve_layout,
            }
        })
    }
}

/// The wedge passes' bind groups, made for one generation of the screen targets.
struct WedgeGroups {
    coverage: wgpu::BindGroup,
    resolve: wgpu::BindGroup,
    generation: u64,
}

/// One method state's wedge passes: the disk's uniforms, the sum target and the bind groups.
pub struct Wedges {
    pass: Arc<WedgePass>,
    disk: wgpu::Buffer,
    sum: Option<Texture>,
    /// The bind groups and the screen targets' generation they bind.
    groups: Option<WedgeGroups>,
}

impl Wedges {
    pub fn new(ctx: &GpuContext, screen: &ScreenPass) -> Wedges {
        Wedges {
            pass: WedgePass::get(ctx, screen),
            disk: uniform_buffer::<WedgeDisk>(&ctx.device, "Wedges::disk"),
            sum: None,
            groups: None,
        }
    }

    /// The sum target's format.
    pub fn sum_format(&self) -> wgpu::TextureFormat {
        self.pass.sum_format
    }

    /// The coverage sum (the camera pass reads it on sides turned away from the centre), once
    /// [`Wedges::record`] made it.
    pub fn sum(&self) -> Option<&Texture> {
        self.sum.as_ref()
    }

    /// After `screen`'s prepass and z-fail count: the wedges' coverage into the sum, then V into
    /// `screen`'s visibility target, timed under `span` (the method's name: its one pass of its
    /// own).
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        span: &'static str,
        screen: &ScreenPass,
        light: &AreaLight,
        wedges: &VertexChunks,
    ) {
        let Some(t) = screen.targets() else { return };
        if self
            .sum
            .as_ref()
            .is_none_or(|s| s.texture.size() != t.position.texture.size())
        {
            self.sum = Some(Texture::new(
                &ctx.device,
                "Wedges::sum",
                (t.width, t.height),
                self.pass.sum_format,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            ));
            self.groups = None;
        }
        let Some(sum) = &self.sum else { return };
        ctx.queue
            .write_buffer(&self.disk, 0, bytemuck::bytes_of(&WedgeDisk::new(light)));
        if self
            .groups
            .as_ref()
            .is_none_or(|g| g.generation != t.generation)
        {
            let coverage = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("Wedges::coverage_group"),
                layout: &self.pass.coverage_layout,
                entries: &[buffer_entry(0, &self.disk), view_entry(1, &t.position.view)],
            });
            let resolve = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("Wedges::resolve_group"),
                layout: &self.pass.resolve_layout,
                entries: &[view_entry(0, &sum.view)],
            });
            self.groups = Some(WedgeGroups {
                coverage,
                resolve,
                generation: t.generation,
            });
        }
        let Some(WedgeGroups {
            coverage, resolve, ..
        }) = &self.groups
        else {
            return;
        };
        let span = rec.span(span);
        {
            let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("Wedges::coverage"),
                color_attachments: &[cleared(&sum.view, wgpu::Color::TRANSPARENT)],
                depth_stencil_attachment: None,
                timestamp_writes: span.writes(rec.timer, true, false),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pass.coverage[usize::from(light.corners().is_some())]);
            pass.set_bind_group(0, &screen.bind_group, &[]);
            pass.set_bind_group(1, coverage, &[]);
            wedges.draw(&mut pass);
        }
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("Wedges::resolve"),
            color_attachments: &[cleared(&t.visibility.view, crate::render::red(1.0))],
            depth_stencil_attachment: t.read_only_depth_stencil(),
            timestamp_writes: span.writes(rec.timer, false, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, resolve, &[]);
        pass.set_stencil_reference(0);
        for pipeline in &self.pass.resolve {
            pass.set_pipeline(pipeline);
            pass.draw(0..3, 0..1);
        }
    }
}
