//! The light pass (`shaders/light_pass.wgsl`): the D-buffer from the light centre.
//!
//! Targets, `size`² texels each: `|cx_o|` (R32Float), umbra `(|cx_uv|, |cx_s|)` and penumbra
//! `(|cx_pv|, |cx_s|)` (Rg32Float). Recorded as: surfaces (nearest by depth); per caster, its
//! umbra exits into a scratch target (nearest by depth) merged into the umbra target (farthest by
//! depth); every penumbra entry (nearest by depth). See the shader for the rules.

use super::gpu_scene::GpuScene;
use super::shader;
use super::{opaque, texture_entry, uniform_entry};
use super::{LightUniforms, SurfaceVertex, VolumeVertex};

pub const DISTANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
pub const VOLUME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// `|cx_o|` where no surface is: far beyond any scene (inf is not a clear value everywhere).
pub const NO_SURFACE: f64 = 3.0e38;

/// A texture with its default view.
pub struct Target {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
}

impl Target {
    fn new(
        device: &wgpu::Device,
        label: &str,
        size: u32,
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> Target {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Target { texture, view }
    }
}

/// The size-dependent textures of the light pass.
pub struct LightTargets {
    pub size: u32,
    pub distance: Target,
    pub umbra: Target,
    pub penumbra: Target,
    scratch: Target,
    surface_depth: Target,
    scratch_depth: Target,
    umbra_depth: Target,
    penumbra_depth: Target,
    merge_bind_group: wgpu::BindGroup,
}

pub struct LightPass {
    surface_pipeline: wgpu::RenderPipeline,
    umbra_pipeline: wgpu::RenderPipeline,
    penumbra_pipeline: wgpu::RenderPipeline,
    merge_pipeline: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    merge_layout: wgpu::BindGroupLayout,
    targets: Option<LightTargets>,
}

fn depth_state(compare: wgpu::CompareFunction) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(true),
        depth_compare: Some(compare),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    })
}

impl LightPass {
    pub fn new(device: &wgpu::Device) -> LightPass {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("LightPass::module"),
            source: wgpu::ShaderSource::Wgsl(shader("light_pass.wgsl").into()),
        });
        let uniforms_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("LightPass::uniforms_layout"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let merge_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("LightPass::merge_layout"),
            entries: &[texture_entry(0, wgpu::TextureViewDimension::D2)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("LightPass::layout"),
            bind_group_layouts: &[Some(&uniforms_layout)],
            immediate_size: 0,
        });
        let merge_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("LightPass::merge_pipeline_layout"),
                bind_group_layouts: &[Some(&uniforms_layout), Some(&merge_layout)],
                immediate_size: 0,
            });
        let pipeline = |label: &str,
                        layout: &wgpu::PipelineLayout,
                        vs: &str,
                        fs: &str,
                        buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                        format: wgpu::TextureFormat,
                        compare: wgpu::CompareFunction| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                // Volumes and surfaces are two-sided here; the fragment shader decides by the
                // triangle's normal which crossings count.
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: depth_state(compare),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[opaque(format)],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        use wgpu::CompareFunction::{Greater, Less};
        let surface_pipeline = pipeline(
            "LightPass::surface_pipeline",
            &layout,
            "vs_surface",
            "fs_surface",
            &[Some(SurfaceVertex::layout())],
            DISTANCE_FORMAT,
            Less,
        );
        let umbra_pipeline = pipeline(
            "LightPass::umbra_pipeline",
            &layout,
            "vs_volume",
            "fs_umbra",
            &[Some(VolumeVertex::layout())],
            VOLUME_FORMAT,
            Less,
        );
        let penumbra_pipeline = pipeline(
            "LightPass::penumbra_pipeline",
            &layout,
            "vs_volume",
            "fs_penumbra",
            &[Some(VolumeVertex::layout())],
            VOLUME_FORMAT,
            Less,
        );
        let merge_pipeline = pipeline(
            "LightPass::merge_pipeline",
            &merge_pipeline_layout,
            "vs_fullscreen",
            "fs_merge",
            &[],
            VOLUME_FORMAT,
            Greater,
        );

        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("LightPass::uniforms"),
            size: std::mem::size_of::<LightUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("LightPass::bind_group"),
            layout: &uniforms_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            }],
        });
        LightPass {
            surface_pipeline,
            umbra_pipeline,
            penumbra_pipeline,
            merge_pipeline,
            uniforms,
            bind_group,
            merge_layout,
            targets: None,
        }
    }

    /// (Re)create the targets for a `size`² D-buffer; a no-op when the size is unchanged.
    /// Returns whether the targets are new (whoever binds them must bind them again).
    pub fn resize(&mut self, device: &wgpu::Device, size: u32) -> bool {
        if self.targets.as_ref().is_some_and(|t| t.size == size) {
            return false;
        }
        use wgpu::TextureUsages as U;
        let color = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
        let scratch = Target::new(device, "LightTargets::scratch", size, VOLUME_FORMAT, color);
        let merge_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("LightTargets::merge_bind_group"),
            layout: &self.merge_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&scratch.view),
            }],
        });
        let depth = |label| Target::new(device, label, size, DEPTH_FORMAT, U::RENDER_ATTACHMENT);
        self.targets = Some(LightTargets {
            size,
            distance: Target::new(
                device,
                "LightTargets::distance",
                size,
                DISTANCE_FORMAT,
                color,
            ),
            umbra: Target::new(device, "LightTargets::umbra", size, VOLUME_FORMAT, color),
            penumbra: Target::new(device, "LightTargets::penumbra", size, VOLUME_FORMAT, color),
            scratch,
            surface_depth: depth("LightTargets::surface_depth"),
            scratch_depth: depth("LightTargets::scratch_depth"),
            umbra_depth: depth("LightTargets::umbra_depth"),
            penumbra_depth: depth("LightTargets::penumbra_depth"),
            merge_bind_group,
        });
        true
    }

    pub fn targets(&self) -> Option<&LightTargets> {
        self.targets.as_ref()
    }

    pub fn prepare(&self, queue: &wgpu::Queue, uniforms: &LightUniforms) {
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
    }

    /// Record every draw of the light pass. `timestamps`: a query set and the indices to write at
    /// the start of the first and the end of the last render pass. Without `volumes` only
    /// `|cx_o|` is drawn (the shadow map of `hard`, `pcf` and `pcss`); the volume targets are
    /// cleared to "no crossing".
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        timestamps: Option<(&wgpu::QuerySet, u32, u32)>,
        volumes: bool,
    ) {
        let Some(t) = &self.targets else {
            return;
        };
        let color = |view, clear: f64| wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color {
                    r: clear,
                    g: 0.0,
                    b: 0.0,
                    a: 0.0,
                }),
                store: wgpu::StoreOp::Store,
            },
        };
        let keep = |view| wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        };
        let depth = |view, load: wgpu::LoadOp<f32>| {
            Some(wgpu::RenderPassDepthStencilAttachment {
                view,
                depth_ops: Some(wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            })
        };
        let first = timestamps.map(|(q, begin, _)| wgpu::RenderPassTimestampWrites {
            query_set: q,
            beginning_of_pass_write_index: Some(begin),
            end_of_pass_write_index: None,
        });
        let last = timestamps.map(|(q, _, end)| wgpu::RenderPassTimestampWrites {
            query_set: q,
            beginning_of_pass_write_index: None,
            end_of_pass_write_index: Some(end),
        });

        // |cx_o|: every surface, nearest wins.
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("LightPass::surfaces"),
                color_attachments: &[Some(color(&t.distance.view, NO_SURFACE))],
                depth_stencil_attachment: depth(&t.surface_depth.view, wgpu::LoadOp::Clear(1.0)),
                timestamp_writes: first,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.surface_pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            scene.surfaces.draw(&mut pass);
        }
        // The umbra target starts empty (0: no exit) with depth 0 for "farthest wins".
        {
            encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("LightPass::umbra_clear"),
                color_attachments: &[Some(color(&t.umbra.view, 0.0))],
                depth_stencil_attachment: depth(&t.umbra_depth.view, wgpu::LoadOp::Clear(0.0)),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
        }
        let casters = if volumes { &scene.casters[..] } else { &[] };
        for caster in casters {
            // This caster's nearest umbra exit...
            {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("LightPass::umbra_caster"),
                    color_attachments: &[Some(color(&t.scratch.view, 0.0))],
                    depth_stencil_attachment: depth(
                        &t.scratch_depth.view,
                        wgpu::LoadOp::Clear(1.0),
                    ),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.umbra_pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                caster.umbra.draw(&mut pass);
            }
            // ...kept where it is farther than the other casters' (depth test Greater).
            {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("LightPass::umbra_merge"),
                    color_attachments: &[Some(keep(&t.umbra.view))],
                    depth_stencil_attachment: depth(&t.umbra_depth.view, wgpu::LoadOp::Load),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.merge_pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_bind_group(1, &t.merge_bind_group, &[]);
                pass.draw(0..3, 0..1);
            }
        }
        // |cx_pv|: the nearest penumbra entry over all casters.
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("LightPass::penumbra"),
                color_attachments: &[Some(color(&t.penumbra.view, 0.0))],
                depth_stencil_attachment: depth(&t.penumbra_depth.view, wgpu::LoadOp::Clear(1.0)),
                timestamp_writes: last,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if volumes {
                pass.set_pipeline(&self.penumbra_pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                scene.penumbra.draw(&mut pass);
            }
        }
    }
}
