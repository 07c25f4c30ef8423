//! The camera pass (`shaders/camera_pass.wgsl`): every surface from the camera, with V per pixel
//! from the D-buffer. Targets, `width`×`height` each: colour (Rgba8UnormSrgb), data (Rg32Float:
//! V, and t + 2·branch so both stay exact in one channel) and world position (Rgba32Float: xyz,
//! hit). 28 bytes per pixel: wgpu allows 32 across colour attachments.

use super::gpu_scene::GpuScene;
use super::light_pass::LightTargets;
use super::sample_maps::SampleMaps;
use super::shader;
use super::{opaque, surface_pipeline, texture_entry, uniform_entry};
use super::{CameraUniforms, MethodUniforms};

pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
pub const DATA_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
pub const POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// V given per pixel by the caller (the ray-cast reference).
pub const EXTERNAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// `n` points in the unit disk by Mitchell's best-candidate algorithm (deterministic): each new
/// point is the farthest of a few candidates from those before it, so every prefix is spread over
/// the disk and a method may use the first k taps of one table.
pub fn poisson_disk(n: usize) -> Vec<glam::Vec2> {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        // SplitMix64.
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut points: Vec<glam::Vec2> = Vec::with_capacity(n);
    while points.len() < n {
        let candidates = 8 * (points.len() + 1);
        let mut best = glam::Vec2::ZERO;
        let mut best_d = -1.0f32;
        for _ in 0..candidates {
            let p = crate::geometry::oracle::concentric(next(), next());
            let d = points
                .iter()
                .map(|q| q.distance_squared(p))
                .fold(f32::MAX, f32::min);
            if d > best_d {
                best_d = d;
                best = p;
            }
        }
        points.push(best);
    }
    points
}

pub struct CameraTargets {
    pub width: u32,
    pub height: u32,
    pub color: wgpu::Texture,
    pub data: wgpu::Texture,
    pub position: wgpu::Texture,
    /// V per pixel for method 5, written by [`CameraPass::set_external_visibility`].
    pub external: wgpu::Texture,
    views: [wgpu::TextureView; 3],
    external_view: wgpu::TextureView,
    depth: wgpu::TextureView,
}

pub struct CameraPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    targets: Option<CameraTargets>,
    /// The uniforms and the D-buffer textures; made again only when those textures are.
    bind_group: Option<wgpu::BindGroup>,
    methods_layout: wgpu::BindGroupLayout,
    method_uniforms: wgpu::Buffer,
    /// The method uniforms, the sampled maps and the external V; made again when those change.
    methods_bind_group: Option<wgpu::BindGroup>,
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
        use wgpu::ShaderStages as S;
        use wgpu::TextureViewDimension as D;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("CameraPass::layout"),
            entries: &[
                uniform_entry(0, S::VERTEX_FRAGMENT),
                texture_entry(1, D::D2),
                texture_entry(2, D::D2),
                texture_entry(3, D::D2),
            ],
        });
        let methods_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("CameraPass::methods_layout"),
            entries: &[
                uniform_entry(0, S::FRAGMENT),
                texture_entry(1, D::D2Array),
                uniform_entry(2, S::FRAGMENT),
                texture_entry(3, D::D2),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("CameraPass::pipeline_layout"),
            bind_group_layouts: &[Some(&layout), Some(&methods_layout)],
            immediate_size: 0,
        });
        let pipeline = surface_pipeline(
            device,
            "CameraPass::pipeline",
            &module,
            &pipeline_layout,
            &[
                opaque(COLOR_FORMAT),
                opaque(DATA_FORMAT),
                opaque(POSITION_FORMAT),
            ],
        );
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("CameraPass::uniforms"),
            size: std::mem::size_of::<CameraUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let method_uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("CameraPass::method_uniforms"),
            size: std::mem::size_of::<MethodUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        CameraPass {
            pipeline,
            layout,
            uniforms,
            targets: None,
            bind_group: None,
            methods_layout,
            method_uniforms,
            methods_bind_group: None,
        }
    }

    /// (Re)create the targets for a `width`×`height` view; a no-op when unchanged. Returns
    /// whether they are new (the methods must be bound again).
    pub fn resize(&mut self, device: &wgpu::Device, width: u32, height: u32) -> bool {
        if self
            .targets
            .as_ref()
            .is_some_and(|t| t.width == width && t.height == height)
        {
            return false;
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
        let external = texture(
            device,
            "CameraTargets::external",
            width,
            height,
            EXTERNAL_FORMAT,
            U::TEXTURE_BINDING | U::COPY_DST,
        );
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        self.targets = Some(CameraTargets {
            width,
            height,
            views: [view(&color), view(&data), view(&position)],
            external_view: view(&external),
            depth: view(&depth),
            color,
            data,
            position,
            external,
        });
        self.methods_bind_group = None;
        true
    }

    /// Bind the method uniforms, the `sampled` maps and the external V (after either is
    /// recreated).
    pub fn bind_methods(&mut self, device: &wgpu::Device, maps: &SampleMaps) {
        let (Some(t), Some(m)) = (&self.targets, maps.targets()) else {
            self.methods_bind_group = None;
            return;
        };
        let texture = |binding, view| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(view),
        };
        self.methods_bind_group = Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("CameraPass::methods_bind_group"),
            layout: &self.methods_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.method_uniforms.as_entire_binding(),
                },
                texture(1, &m.array_view),
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: maps.uniforms().as_entire_binding(),
                },
                texture(3, &t.external_view),
            ],
        }));
    }

    pub fn methods_bound(&self) -> bool {
        self.methods_bind_group.is_some()
    }

    /// Upload V per pixel for the external method (row-major, `width`×`height` of the targets).
    pub fn set_external_visibility(&self, queue: &wgpu::Queue, v: &[f32]) -> bool {
        let Some(t) = &self.targets else {
            return false;
        };
        if v.len() != (t.width * t.height) as usize {
            return false;
        }
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &t.external,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(v),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(t.width * 4),
                rows_per_image: Some(t.height),
            },
            wgpu::Extent3d {
                width: t.width,
                height: t.height,
                depth_or_array_layers: 1,
            },
        );
        true
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

    pub fn prepare(
        &self,
        queue: &wgpu::Queue,
        uniforms: &CameraUniforms,
        methods: &MethodUniforms,
    ) {
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
        queue.write_buffer(&self.method_uniforms, 0, bytemuck::bytes_of(methods));
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
        let (Some(bind_group), Some(methods)) = (&self.bind_group, &self.methods_bind_group) else {
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
        pass.set_bind_group(1, methods, &[]);
        scene.surfaces.draw(&mut pass);
    }
}
