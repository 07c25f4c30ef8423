//! The extended light map's light pass (`shaders/passes/extended_light_map.wgsl`; Brabec,
//! Heidrich and Seidel 2000): from the light's centre, with the fitted light view, one
//! Rgba32Float target whose RGB is the light the nearest surface gets (a spotlight's falloff, a
//! projected texture from `assets/gobo.png`, the cosines) and whose A is that surface's distance
//! from the light over the view's far distance, quantised to the map's depth bits. Made once per
//! light or caster move.

use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::next_generation;
use crate::render::gpu_scene::GpuScene;
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, depth_attachment, depth_test, opaque, pipeline_layout, shader_module,
    uniform_buffer, uniform_entry, GpuContext, SurfaceVertex, Texture,
};

pub const MAP_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The projected texture, made for this project (`scripts/make_gobo.py`).
pub const GOBO_PNG: &[u8] = include_bytes!("../../../assets/gobo.png");

/// What the map shows besides the shadow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pattern {
    /// A spotlight: full inside its inner cone, smoothly to nothing at its outer one.
    Spot,
    /// The spotlight through the projected texture (a gobo).
    Texture,
    /// The same light everywhere in the map.
    Uniform,
}

impl Pattern {
    pub fn code(self) -> f32 {
        match self {
            Pattern::Spot => 0.0,
            Pattern::Texture => 1.0,
            Pattern::Uniform => 2.0,
        }
    }
}

/// `ElmUniforms` of `shaders/passes/extended_light_map.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ElmUniforms {
    pub view_proj: [[f32; 4]; 4],
    /// xyz: the light point; w: 1 / far.
    pub light: [f32; 4],
    /// xyz: the spot's axis; w: the intensity.
    pub axis: [f32; 4],
    /// cos outer, cos inner, depth levels, the pattern code (for the record: the pipeline
    /// constant `PATTERN` decides).
    pub spot: [f32; 4],
    /// xyz: the emitter's normal; w: 1 to apply its cosine.
    pub emitter: [f32; 4],
    /// x: the map's side.
    pub size: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<ElmUniforms>() == 144);

/// Everything the map is made from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElmParams {
    pub view_proj: Mat4,
    pub light: Vec3,
    pub far: f32,
    pub axis: Vec3,
    pub intensity: f32,
    /// The spot's outer and inner half-angles, radians.
    pub outer: f32,
    pub inner: f32,
    /// Bits of the distance channel.
    pub bits: u32,
    pub pattern: Pattern,
    /// The one-sided disk's normal, whose cosine the light falls off with (`None`: none).
    pub emitter: Option<Vec3>,
    pub size: u32,
}

impl ElmParams {
    /// Depth levels of the distance channel: `2^bits − 1`.
    pub fn levels(&self) -> f32 {
        ((1u64 << self.bits.min(32)) - 1) as f32
    }
}

impl ElmUniforms {
    pub fn new(p: &ElmParams) -> ElmUniforms {
        ElmUniforms {
            view_proj: p.view_proj.to_cols_array_2d(),
            light: p.light.extend(1.0 / p.far).to_array(),
            axis: p.axis.extend(p.intensity).to_array(),
            spot: [p.outer.cos(), p.inner.cos(), p.levels(), p.pattern.code()],
            emitter: p
                .emitter
                .map_or([0.0, 0.0, 1.0, 0.0], |n| n.extend(1.0).to_array()),
            size: [p.size as f32, 0.0, 0.0, 0.0],
        }
    }
}

/// The pipelines (one per pattern, made on first use), their layout and the projected texture,
/// once per device.
pub struct ElmPass {
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: [std::sync::OnceLock<wgpu::RenderPipeline>; 3],
    layout: wgpu::BindGroupLayout,
    gobo: wgpu::TextureView,
    sampler: wgpu::Sampler,
}

impl ElmPass {
    pub fn get(ctx: &GpuContext) -> Arc<ElmPass> {
        ctx.shared(|device| {
            let module = shader_module(device, "passes/extended_light_map.wgsl");
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("ElmPass::layout"),
                entries: &[
                    uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT),
                    wgpu::BindGroupLayoutEntry {
                        binding: 1,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable: true },
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                        count: None,
                    },
                    wgpu::BindGroupLayoutEntry {
                        binding: 2,
                        visibility: wgpu::ShaderStages::FRAGMENT,
                        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                        count: None,
                    },
                ],
            });
            ElmPass {
                pipeline_layout: pipeline_layout(device, "ElmPass::pipeline_layout", &[&layout]),
                module,
                pipelines: Default::default(),
                layout,
                gobo: gobo_texture(device, &ctx.queue),
                sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("ElmPass::sampler"),
                    mag_filter: wgpu::FilterMode::Linear,
                    min_filter: wgpu::FilterMode::Linear,
                    ..Default::default()
                }),
            }
        })
    }
}

impl ElmPass {
    /// The pipeline for `pattern`.
    fn pipeline(&self, device: &wgpu::Device, pattern: Pattern) -> &wgpu::RenderPipeline {
        self.pipelines[pattern.code() as usize].get_or_init(|| {
            let constants = [("PATTERN", f64::from(pattern.code()))];
            let options = wgpu::PipelineCompilationOptions {
                constants: &constants,
                ..Default::default()
            };
            let targets = [opaque(MAP_FORMAT)];
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("ElmPass::pipeline"),
                layout: Some(&self.pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some("vs_main"),
                    compilation_options: options.clone(),
                    buffers: &[Some(SurfaceVertex::layout())],
                },
                // Surfaces are two-sided.
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: depth_test(wgpu::CompareFunction::Less),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &self.module,
                    entry_point: Some("fs_main"),
                    compilation_options: options,
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        })
    }
}

/// `assets/gobo.png` as an sRGB texture (a white texel if it cannot be decoded: the embedded file
/// is checked by a test).
fn gobo_texture(device: &wgpu::Device, queue: &wgpu::Queue) -> wgpu::TextureView {
    use wgpu::util::DeviceExt;
    let (w, h, texels) = match image::load_from_memory(GOBO_PNG) {
        Ok(img) => {
            let rgba = img.to_rgba8();
            (rgba.width(), rgba.height(), rgba.into_raw())
        }
        Err(_) => (1, 1, vec![255; 4]),
    };
    device
        .create_texture_with_data(
            queue,
            &wgpu::TextureDescriptor {
                label: Some("ElmPass::gobo"),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8UnormSrgb,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            &texels,
        )
        .create_view(&wgpu::TextureViewDescriptor::default())
}

/// The map's textures.
pub struct ElmTargets {
    pub size: u32,
    pub map: Texture,
    pub depth: Texture,
    pub generation: u64,
}

/// A method state's extended light map: uniforms, bind group, targets.
pub struct ExtendedLightMap {
    pass: Arc<ElmPass>,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    targets: Option<ElmTargets>,
}

impl ExtendedLightMap {
    pub fn new(ctx: &GpuContext) -> ExtendedLightMap {
        let pass = ElmPass::get(ctx);
        let uniforms = uniform_buffer::<ElmUniforms>(&ctx.device, "ExtendedLightMap::uniforms");
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ExtendedLightMap::bind_group"),
            layout: &pass.layout,
            entries: &[
                buffer_entry(0, &uniforms),
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&pass.gobo),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&pass.sampler),
                },
            ],
        });
        ExtendedLightMap {
            pass,
            uniforms,
            bind_group,
            targets: None,
        }
    }

    pub fn targets(&self) -> Option<&ElmTargets> {
        self.targets.as_ref()
    }

    /// Make the map for `params` (recorded now; the caller decides when it is stale).
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        params: &ElmParams,
        surfaces: &GpuScene,
    ) {
        let size = params.size;
        if self.targets.as_ref().is_none_or(|t| t.size != size) {
            use wgpu::TextureUsages as U;
            self.targets = Some(ElmTargets {
                size,
                map: Texture::new(
                    &ctx.device,
                    "ExtendedLightMap::map",
                    (size, size),
                    MAP_FORMAT,
                    U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
                ),
                depth: Texture::new(
                    &ctx.device,
                    "ExtendedLightMap::depth",
                    (size, size),
                    wgpu::TextureFormat::Depth32Float,
                    U::RENDER_ATTACHMENT,
                ),
                generation: next_generation(),
            });
        }
        let Some(t) = &self.targets else { return };
        ctx.queue.write_buffer(
            &self.uniforms,
            0,
            bytemuck::bytes_of(&ElmUniforms::new(params)),
        );
        let span = rec.span("extended_light_map");
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("ExtendedLightMap::pass"),
            // No surface: no light, the farthest distance.
            color_attachments: &[cleared(
                &t.map.view,
                wgpu::Color {
                    r: 0.0,
                    g: 0.0,
                    b: 0.0,
                    a: 1.0,
                },
            )],
            depth_stencil_attachment: depth_attachment(
                &t.depth.view,
                wgpu::LoadOp::Clear(1.0),
                false,
            ),
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(self.pass.pipeline(&ctx.device, params.pattern));
        pass.set_bind_group(0, &self.bind_group, &[]);
        surfaces.draw(&mut pass);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_projected_texture_decodes_and_is_coloured() {
        let img = image::load_from_memory(GOBO_PNG)
            .expect("assets/gobo.png")
            .to_rgb8();
        assert_eq!(img.dimensions(), (128, 128));
        let p = |x, y| img.get_pixel(x, y).0;
        // Four tinted panes between dark mullions and a dark frame.
        assert_eq!(p(64, 64), [0, 0, 0]);
        assert_eq!(p(1, 1), [0, 0, 0]);
        let panes = [p(30, 30), p(100, 30), p(30, 100), p(100, 100)];
        for (i, a) in panes.iter().enumerate() {
            assert!(a.iter().all(|&c| c >= 140), "pane {i}: {a:?}");
            assert!(
                panes[..i].iter().all(|b| b != a),
                "pane {i} repeats a colour"
            );
        }
    }

    #[test]
    fn levels_of_the_distance_channel() {
        let p = |bits| ElmParams {
            view_proj: Mat4::IDENTITY,
            light: Vec3::ZERO,
            far: 10.0,
            axis: Vec3::NEG_Y,
            intensity: 1.0,
            outer: 0.5,
            inner: 0.3,
            bits,
            pattern: Pattern::Spot,
            emitter: None,
            size: 64,
        };
        assert_eq!(p(8).levels(), 255.0);
        assert_eq!(p(16).levels(), 65535.0);
        assert_eq!(p(24).levels(), 16_777_215.0);
    }
}
