//! `dbuffer-fused`'s surfaces along the light centre's rays (`shaders/passes/fused_layers.wgsl`),
//! drawn from `c` in the light view after the shadow map, once per light or caster move. CPU
//! twin: `geometry::fused::FusedTwin` (`caster_crossings`, `receiver_layers`).
//!
//! - D-buffer grid (`map_size`²): the caster surfaces each texel's centre ray crosses (R16Float,
//!   additive: exact up to 2048 crossings) and the largest height of a crossing (Depth32Float,
//!   test Greater; the height over the light view's far distance);
//! - list grid (`list_size`²): the receivers (surfaces facing `c`) along each texel's centre
//!   ray: the first, the second (peeled behind the first's depth), the last and the last on a
//!   caster as (`|p − c|`, unit normal) in Rgba32Float, and how many (R16Float, additive).
//!
//! All four draws of the scene and both grids' passes are one timed span, `fused_layers`.

use std::sync::Arc;

use crate::geometry::light_view::LightView;
use crate::render::gpu_scene::{GpuScene, CASTER_ALBEDO};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, depth_attachment, pipeline_layout, render_pipeline, shader_module,
    uniform_entry, view_entry, GpuContext, PipelineSpec, SurfaceVertex, Texture,
};
use crate::scene::AreaLight;

use super::next_generation;

/// Counts of surfaces along a ray (crossings, receivers): additive, exact to 2048.
pub const COUNT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;
/// (`|p − c|`, unit normal) of a receiver.
pub const RECEIVER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// `FusedUniforms` of `shaders/shared/fused.wgsl`: the light view, the disk and the method's
/// numbers, read by every pass of `dbuffer-fused` (layout checked by `tests/gpu/render_layout.rs`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FusedUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub center: [f32; 3],
    pub radius: f32,
    pub normal: [f32; 3],
    pub inv_far: f32,
    pub e1: [f32; 3],
    pub list_size: f32,
    pub e2: [f32; 3],
    pub half_slope: f32,
    pub map_size: f32,
    pub cap: u32,
    pub samples: u32,
    pub edge_count: u32,
    pub h_max: f32,
    pub caster_albedo: f32,
    pub all_overflow: u32,
    pub _pad: u32,
}

const _: () = assert!(std::mem::size_of::<FusedUniforms>() == 224);

/// What [`FusedUniforms::new`] needs besides the light and its view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FusedSizes {
    /// Texels per side of the D-buffer.
    pub map_size: u32,
    /// Texels per side of the list grid.
    pub list_size: u32,
    pub cap: u32,
    pub samples: u32,
    pub edge_count: u32,
    /// The largest receiver height (the proxies' extent).
    pub h_max: f32,
    /// Every list counts as overflowing.
    pub all_overflow: bool,
}

impl FusedUniforms {
    pub fn new(light: &AreaLight, view: &LightView, s: FusedSizes) -> FusedUniforms {
        let vp = view.view_projection();
        let (e1, e2) = light.basis();
        // FusedTwin::texel_ray_of's half_slope: half a list texel's diagonal, as a slope.
        let slope = glam::Vec2::new(
            2.0 / view.projection.x_axis.x.abs(),
            2.0 / view.projection.y_axis.y.abs(),
        );
        FusedUniforms {
            view_proj: vp.to_cols_array_2d(),
            inv_view_proj: vp.inverse().to_cols_array_2d(),
            center: light.center.to_array(),
            radius: light.radius,
            normal: light.normal.to_array(),
            inv_far: 1.0 / view.far,
            e1: e1.to_array(),
            list_size: s.list_size as f32,
            e2: e2.to_array(),
            half_slope: 0.5 * slope.length() / s.list_size.max(1) as f32,
            map_size: s.map_size as f32,
            cap: s.cap,
            samples: s.samples,
            edge_count: s.edge_count,
            h_max: s.h_max,
            caster_albedo: CASTER_ALBEDO,
            all_overflow: u32::from(s.all_overflow),
            _pad: 0,
        }
    }
}

/// The bind group layout of the uniforms (group 0 of every `dbuffer-fused` light pass).
pub fn uniforms_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[uniform_entry(
            0,
            wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
        )],
    })
}

/// The pipelines, built once per device.
pub struct FusedLayersPass {
    crossing_count: wgpu::RenderPipeline,
    crossing_far: wgpu::RenderPipeline,
    first: wgpu::RenderPipeline,
    receiver_count: wgpu::RenderPipeline,
    second: wgpu::RenderPipeline,
    last: wgpu::RenderPipeline,
    last_caster: wgpu::RenderPipeline,
    uniforms_layout: wgpu::BindGroupLayout,
    peel_layout: wgpu::BindGroupLayout,
}

const ADD: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};

fn target(
    format: wgpu::TextureFormat,
    blend: Option<wgpu::BlendState>,
    write: bool,
) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend,
        write_mask: if write {
            wgpu::ColorWrites::ALL
        } else {
            wgpu::ColorWrites::empty()
        },
    })
}

fn depth(compare: wgpu::CompareFunction, write: bool) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    })
}

impl FusedLayersPass {
    pub fn get(ctx: &GpuContext) -> Arc<FusedLayersPass> {
        ctx.shared(|device| {
            let module = shader_module(device, "passes/fused_layers.wgsl");
            let uniforms_layout = uniforms_layout(device, "FusedLayersPass::uniforms_layout");
            let peel_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("FusedLayersPass::peel_layout"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    // The depth as an unfilterable float: every backend loads it (GLSL has no
                    // `textureLoad` of a depth texture).
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                }],
            });
            let layout = pipeline_layout(device, "FusedLayersPass::layout", &[&uniforms_layout]);
            let peel = pipeline_layout(
                device,
                "FusedLayersPass::peel",
                &[&uniforms_layout, &peel_layout],
            );
            let buffers = [Some(SurfaceVertex::layout())];
            let pipeline = |label,
                            layout: &wgpu::PipelineLayout,
                            vs,
                            fs,
                            targets: &[Option<wgpu::ColorTargetState>],
                            cull,
                            depth| {
                render_pipeline(
                    device,
                    &PipelineSpec {
                        label,
                        module: &module,
                        layout,
                        vs,
                        fs: Some(fs),
                        buffers: &buffers,
                        targets,
                        cull,
                        depth,
                    },
                )
            };
            use wgpu::CompareFunction as C;
            // Caster crossings: both sides of every caster face; the count into the colour,
            // the farthest into the depth.
            let crossing_count = pipeline(
                "FusedLayersPass::crossing_count",
                &layout,
                "vs_caster",
                "fs_count",
                &[target(COUNT_FORMAT, Some(ADD), true)],
                None,
                depth(C::Always, false),
            );
            let crossing_far = pipeline(
                "FusedLayersPass::crossing_far",
                &layout,
                "vs_caster",
                "fs_far",
                &[target(COUNT_FORMAT, None, false)],
                None,
                depth(C::Greater, true),
            );
            // Receivers: surfaces facing c (counter-clockwise in the right-handed light view).
            let facing = Some(wgpu::Face::Back);
            let first = pipeline(
                "FusedLayersPass::first",
                &layout,
                "vs_surface",
                "fs_receiver_both",
                &[
                    target(RECEIVER_FORMAT, None, true),
                    target(COUNT_FORMAT, Some(ADD), false),
                ],
                facing,
                depth(C::Less, true),
            );
            let receiver_count = pipeline(
                "FusedLayersPass::receiver_count",
                &layout,
                "vs_surface",
                "fs_receiver_both",
                &[
                    target(RECEIVER_FORMAT, None, false),
                    target(COUNT_FORMAT, Some(ADD), true),
                ],
                facing,
                depth(C::Always, false),
            );
            let second = pipeline(
                "FusedLayersPass::second",
                &peel,
                "vs_surface",
                "fs_peel",
                &[target(RECEIVER_FORMAT, None, true)],
                facing,
                depth(C::Less, true),
            );
            let last = pipeline(
                "FusedLayersPass::last",
                &layout,
                "vs_surface",
                "fs_receiver",
                &[target(RECEIVER_FORMAT, None, true)],
                facing,
                depth(C::Greater, true),
            );
            let last_caster = pipeline(
                "FusedLayersPass::last_caster",
                &layout,
                "vs_caster",
                "fs_receiver",
                &[target(RECEIVER_FORMAT, None, true)],
                facing,
                depth(C::Greater, true),
            );
            FusedLayersPass {
                crossing_count,
                crossing_far,
                first,
                receiver_count,
                second,
                last,
                last_caster,
                uniforms_layout,
                peel_layout,
            }
        })
    }
}

/// The passes' textures.
pub struct LayerTargets {
    pub map_size: u32,
    pub list_size: u32,
    /// Caster crossings along each D-buffer texel's ray.
    pub crossings: Texture,
    /// The largest crossing height, over the light view's far distance.
    pub crossing_far: Texture,
    pub first: Texture,
    pub second: Texture,
    pub last: Texture,
    pub last_caster: Texture,
    /// Receivers along each list texel's ray.
    pub receivers: Texture,
    first_depth: Texture,
    scratch_depth: Texture,
    peel_group: wgpu::BindGroup,
    /// Changes whenever the textures are made again.
    pub generation: u64,
}

/// A session's `dbuffer-fused` layers.
pub struct FusedLayers {
    pass: Arc<FusedLayersPass>,
    bind_group: wgpu::BindGroup,
    targets: Option<LayerTargets>,
}

impl FusedLayers {
    /// `uniforms`: the method's [`FusedUniforms`] buffer (written before each record).
    pub fn new(ctx: &GpuContext, uniforms: &wgpu::Buffer) -> FusedLayers {
        let pass = FusedLayersPass::get(ctx);
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("FusedLayers::bind_group"),
            layout: &pass.uniforms_layout,
            entries: &[buffer_entry(0, uniforms)],
        });
        FusedLayers {
            pass,
            bind_group,
            targets: None,
        }
    }

    pub fn targets(&self) -> Option<&LayerTargets> {
        self.targets.as_ref()
    }

    fn ensure_targets(&mut self, device: &wgpu::Device, map_size: u32, list_size: u32) {
        if self
            .targets
            .as_ref()
            .is_some_and(|t| t.map_size == map_size && t.list_size == list_size)
        {
            return;
        }
        use wgpu::TextureUsages as U;
        let read = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING;
        let tex =
            |label, size: u32, format| Texture::new(device, label, (size, size), format, read);
        let first_depth = tex("LayerTargets::first_depth", list_size, DEPTH_FORMAT);
        let peel_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("LayerTargets::peel_group"),
            layout: &self.pass.peel_layout,
            entries: &[view_entry(0, &first_depth.view)],
        });
        self.targets = Some(LayerTargets {
            map_size,
            list_size,
            crossings: tex("LayerTargets::crossings", map_size, COUNT_FORMAT),
            crossing_far: tex("LayerTargets::crossing_far", map_size, DEPTH_FORMAT),
            first: tex("LayerTargets::first", list_size, RECEIVER_FORMAT),
            second: tex("LayerTargets::second", list_size, RECEIVER_FORMAT),
            last: tex("LayerTargets::last", list_size, RECEIVER_FORMAT),
            last_caster: tex("LayerTargets::last_caster", list_size, RECEIVER_FORMAT),
            receivers: tex("LayerTargets::receivers", list_size, COUNT_FORMAT),
            first_depth,
            scratch_depth: Texture::new(
                device,
                "LayerTargets::scratch_depth",
                (list_size, list_size),
                DEPTH_FORMAT,
                U::RENDER_ATTACHMENT,
            ),
            peel_group,
            generation: next_generation(),
        });
    }

    /// Record the layers of `surfaces` at a `map_size`² D-buffer and a `list_size`² list grid;
    /// the uniforms buffer must hold this light and view.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        surfaces: &GpuScene,
        map_size: u32,
        list_size: u32,
    ) {
        self.ensure_targets(&ctx.device, map_size, list_size);
        let Some(t) = self.targets.as_ref() else {
            return;
        };
        let pass = &self.pass;
        let span = rec.span("fused_layers");
        let zero = wgpu::Color::TRANSPARENT;
        let draw = |rec: &mut Recorder<'_>,
                    label,
                    colors: &[Option<wgpu::RenderPassColorAttachment<'_>>],
                    depth: (&Texture, f32, bool),
                    (first, last): (bool, bool),
                    pipelines: &[(&wgpu::RenderPipeline, bool)]| {
            let mut p = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(label),
                color_attachments: colors,
                depth_stencil_attachment: depth_attachment(
                    &depth.0.view,
                    wgpu::LoadOp::Clear(depth.1),
                    depth.2,
                ),
                timestamp_writes: span.writes(rec.timer, first, last),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            for (pipeline, peel) in pipelines {
                p.set_pipeline(pipeline);
                p.set_bind_group(0, &self.bind_group, &[]);
                if *peel {
                    p.set_bind_group(1, &t.peel_group, &[]);
                }
                surfaces.draw(&mut p);
            }
        };
        draw(
            rec,
            "FusedLayers::crossings",
            &[cleared(&t.crossings.view, zero)],
            (&t.crossing_far, 0.0, true),
            (true, false),
            &[(&pass.crossing_count, false), (&pass.crossing_far, false)],
        );
        draw(
            rec,
            "FusedLayers::first",
            &[
                cleared(&t.first.view, zero),
                cleared(&t.receivers.view, zero),
            ],
            (&t.first_depth, 1.0, true),
            (false, false),
            &[(&pass.first, false), (&pass.receiver_count, false)],
        );
        draw(
            rec,
            "FusedLayers::second",
            &[cleared(&t.second.view, zero)],
            (&t.scratch_depth, 1.0, false),
            (false, false),
            &[(&pass.second, true)],
        );
        draw(
            rec,
            "FusedLayers::last",
            &[cleared(&t.last.view, zero)],
            (&t.scratch_depth, 0.0, false),
            (false, false),
            &[(&pass.last, false)],
        );
        draw(
            rec,
            "FusedLayers::last_caster",
            &[cleared(&t.last_caster.view, zero)],
            (&t.scratch_depth, 0.0, false),
            (false, true),
            &[(&pass.last_caster, false)],
        );
    }
}
