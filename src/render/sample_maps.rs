//! The `sampled` method's shadow maps (`shaders/sample_maps.wgsl`): N stratified points on the
//! disk, each a point light with a `size`² distance map, one layer of an array texture (seed 002
//! §3.1). The camera pass averages their hard tests.
//!
//! Every point uses the D-buffer's frustum moved to that point: the frustum is fitted to the
//! directions `v − q` from every disk point `q` to every caster vertex `v`, so it holds each
//! caster as any disk point sees it.

use bytemuck::Zeroable;
use glam::Mat4;

use super::gpu_scene::GpuScene;
use super::light_pass::{DEPTH_FORMAT, DISTANCE_FORMAT, NO_SURFACE};
use super::shader;
use super::{opaque, surface_pipeline, uniform_entry, SampleLight, SampleLights};
use crate::geometry::light_view::LightView;
use crate::geometry::oracle::disk_samples;
use crate::scene::DiskLight;

/// The array of distance maps and what they were made for.
pub struct SampleTargets {
    pub size: u32,
    pub layers: u32,
    pub texture: wgpu::Texture,
    /// The whole array, for the camera pass.
    pub array_view: wgpu::TextureView,
    layer_views: Vec<wgpu::TextureView>,
    depth: wgpu::TextureView,
}

pub struct SampleMaps {
    pipeline: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    targets: Option<SampleTargets>,
}

/// The N points on the disk and their view-projections.
pub fn sample_lights(light: &DiskLight, view: &LightView, n: u32) -> SampleLights {
    let mut out = SampleLights::zeroed();
    let (e1, e2) = light.basis();
    for (slot, p) in out.lights.iter_mut().zip(disk_samples(
        n.clamp(1, super::frame::MAX_SAMPLED_LIGHTS) as usize,
    )) {
        let q = light.center + light.radius * (p.x * e1 + p.y * e2);
        let moved = view.view * Mat4::from_translation(light.center - q);
        *slot = SampleLight {
            view_proj: (view.projection * moved).to_cols_array_2d(),
            point: q.extend(1.0).to_array(),
        };
    }
    out
}

impl SampleMaps {
    pub fn new(device: &wgpu::Device) -> SampleMaps {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("SampleMaps::module"),
            source: wgpu::ShaderSource::Wgsl(shader("sample_maps.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("SampleMaps::layout"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("SampleMaps::pipeline_layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = surface_pipeline(
            device,
            "SampleMaps::pipeline",
            &module,
            &pipeline_layout,
            &[opaque(DISTANCE_FORMAT)],
        );
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("SampleMaps::uniforms"),
            size: std::mem::size_of::<SampleLights>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("SampleMaps::bind_group"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            }],
        });
        SampleMaps {
            pipeline,
            uniforms,
            bind_group,
            targets: None,
        }
    }

    /// The uniform buffer of the sample lights (the camera pass binds it too).
    pub fn uniforms(&self) -> &wgpu::Buffer {
        &self.uniforms
    }

    /// (Re)create the maps for `layers` layers of `size`²; returns whether they are new.
    pub fn resize(&mut self, device: &wgpu::Device, size: u32, layers: u32) -> bool {
        let layers = layers.max(1);
        if self
            .targets
            .as_ref()
            .is_some_and(|t| t.size == size && t.layers == layers)
        {
            return false;
        }
        let extent = |layers| wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: layers,
        };
        use wgpu::TextureUsages as U;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("SampleTargets::maps"),
            size: extent(layers),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DISTANCE_FORMAT,
            usage: U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
            view_formats: &[],
        });
        let depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("SampleTargets::depth"),
            size: extent(1),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: U::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let array_view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("SampleTargets::array_view"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let layer_views = (0..layers)
            .map(|layer| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    label: Some("SampleTargets::layer_view"),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        self.targets = Some(SampleTargets {
            size,
            layers,
            texture,
            array_view,
            layer_views,
            depth: depth.create_view(&wgpu::TextureViewDescriptor::default()),
        });
        true
    }

    pub fn targets(&self) -> Option<&SampleTargets> {
        self.targets.as_ref()
    }

    pub fn prepare(&self, queue: &wgpu::Queue, lights: &SampleLights) {
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(lights));
    }

    /// Record one render pass per layer; `timestamps` as in the light pass.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timestamps: Option<(&wgpu::QuerySet, u32, u32)>,
    ) {
        let Some(t) = &self.targets else {
            return;
        };
        let last = t.layer_views.len().saturating_sub(1);
        for (layer, view) in t.layer_views.iter().enumerate() {
            let stamps = timestamps.and_then(|(q, begin, end)| {
                let b = (layer == 0).then_some(begin);
                let e = (layer == last).then_some(end);
                (b.is_some() || e.is_some()).then_some(wgpu::RenderPassTimestampWrites {
                    query_set: q,
                    beginning_of_pass_write_index: b,
                    end_of_pass_write_index: e,
                })
            });
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("SampleMaps::layer"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: NO_SURFACE,
                            g: 0.0,
                            b: 0.0,
                            a: 0.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &t.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: stamps,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            let layer = layer as u32;
            scene.surfaces.draw_instances(&mut pass, layer..layer + 1);
        }
    }
}
