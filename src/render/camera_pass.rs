//! The camera pass (`shaders/camera_pass.wgsl`): every surface from the camera, with V per pixel
//! from the D-buffer. Targets, `width`×`height` each: colour (Rgba8UnormSrgb), data (Rg32Float:
//! V, and t + 2·branch so both stay exact in one channel) and world position (Rgba32Float: xyz,
//! hit). 28 bytes per pixel: wgpu allows 32 across colour attachments.

use super::gpu_scene::GpuScene;
use super::light_pass::LightTargets;
use super::shader;
use super::{CameraUniforms, SurfaceVertex};

pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
pub const DATA_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
pub const POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

pub struct CameraTargets {
    pub width: u32,
    pub height: u32,
    pub color: wgpu::Texture,
    pub data: wgpu::Texture,
    pub position: wgpu::Texture,
    views: [wgpu::TextureView; 3],
    depth: wgpu::TextureView,
}

pub struct CameraPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    targets: Option<CameraTargets>,
    /// The uniforms and the D-buffer textures; made again only when those textures are.
    bind_group: Option<wgpu::BindGroup>,
}

fn texture(
    device: &wgpu::Device,
    label: &str,
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

impl CameraPass {
    pub fn new(device: &wgpu::Device) -> CameraPass {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("CameraPass::module"),
            source: wgpu::ShaderSource::Wgsl(shader("camera_pass.wgsl").into()),
        });
        let dbuffer_texture = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("CameraPass::layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                dbuffer_texture(1),
                dbuffer_texture(2),
                dbuffer_texture(3),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("CameraPass::pipeline_layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let target = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("CameraPass::pipeline"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(SurfaceVertex::layout())],
            },
            // Surfaces are two-sided (open meshes, the ground seen from below).
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[
                    target(COLOR_FORMAT),
                    target(DATA_FORMAT),
                    target(POSITION_FORMAT),
                ],
            }),
            multiview_mask: None,
            cache: None,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("CameraPass::uniforms"),
            size: std::mem::size_of::<CameraUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        CameraPass {
            pipeline,
            layout,
            uniforms,
            targets: None,
            bind_group: None,
        }
    }

    /// (Re)create the targets for a `width`×`height` view; a no-op when unchanged.
    pub fn resize(&mut self, device: &wgpu::Device, width: u32, height: u32) {
        if self
            .targets
            .as_ref()
            .is_some_and(|t| t.width == width && t.height == height)
        {
            return;
        }
        use wgpu::TextureUsages as U;
        let usage = U::RENDER_ATTACHMENT | U::COPY_SRC | U::TEXTURE_BINDING;
        let color = texture(
            device,
            "CameraTargets::color",
            width,
            height,
            COLOR_FORMAT,
            usage,
        );
        let data = texture(
            device,
            "CameraTargets::data",
            width,
            height,
            DATA_FORMAT,
            usage,
        );
        let position = texture(
            device,
            "CameraTargets::position",
            width,
            height,
            POSITION_FORMAT,
            usage,
        );
        let depth = texture(
            device,
            "CameraTargets::depth",
            width,
            height,
            DEPTH_FORMAT,
            U::RENDER_ATTACHMENT,
        );
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        self.targets = Some(CameraTargets {
            width,
            height,
            views: [view(&color), view(&data), view(&position)],
            depth: view(&depth),
            color,
            data,
            position,
        });
    }

    pub fn targets(&self) -> Option<&CameraTargets> {
        self.targets.as_ref()
    }

    /// Bind the light pass's D-buffer; needed once, and again whenever its targets are recreated.
    pub fn bind_dbuffer(&mut self, device: &wgpu::Device, dbuffer: &LightTargets) {
        let texture = |binding, view| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(view),
        };
        self.bind_group = Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("CameraPass::bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.uniforms.as_entire_binding(),
                },
                texture(1, &dbuffer.distance.view),
                texture(2, &dbuffer.umbra.view),
                texture(3, &dbuffer.penumbra.view),
            ],
        }));
    }

    pub fn is_bound(&self) -> bool {
        self.bind_group.is_some()
    }

    pub fn prepare(&self, queue: &wgpu::Queue, uniforms: &CameraUniforms) {
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
    }

    /// Record the pass, reading the D-buffer bound by [`CameraPass::bind_dbuffer`].
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timestamps: Option<(&wgpu::QuerySet, u32, u32)>,
    ) {
        let Some(t) = &self.targets else {
            return;
        };
        let Some(bind_group) = &self.bind_group else {
            return;
        };
        let attachment = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("CameraPass::pass"),
            color_attachments: &[
                attachment(&t.views[0]),
                attachment(&t.views[1]),
                attachment(&t.views[2]),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &t.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamps.map(|(q, begin, end)| wgpu::RenderPassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: Some(begin),
                end_of_pass_write_index: Some(end),
            }),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        scene.surfaces.draw(&mut pass);
    }
}
