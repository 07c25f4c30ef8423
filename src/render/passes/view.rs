//! The view pass (`shaders/passes/view.wgsl`): what the lab's viewport shows of a frame, drawn on
//! the GPU into the texture the viewport samples — the final image, V, t, the classes, |ΔV|
//! against the reference, the pixels whose V or t is out of range, or the shown method's light-space maps with channel isolation, each
//! scalar through a [`Mapping`] (black/white range, colour map). The frame never leaves the GPU
//! for it. Its CPU twin is [`super::view_twin`]; a test holds the two to agree on every view.

use std::sync::{Arc, OnceLock};

use glam::Mat4;
use serde::{Deserialize, Serialize};

use super::camera::CameraTargets;
use crate::render::light_maps::{Channel, Empty, LightMaps};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, opaque, pipeline_layout, shader_module, texture_entry, uniform_buffer,
    uniform_entry, view_entry, GpuContext, Texture,
};

/// The display texture's format: egui samples it as gamma-encoded bytes.
pub const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum View {
    /// The shaded image.
    Final,
    /// V per pixel.
    Visibility,
    /// t per pixel.
    T,
    /// The branch each pixel fell on: lit, penumbra (visible / hidden from the centre), umbra.
    Classes,
    /// |ΔV| against the reference.
    Error,
    /// FLIP of the shaded image against the reference's (a map handed in, `Session::set_flip`).
    Flip,
    /// The shown method's light-space maps (the D-buffer), channels isolated or combined.
    DBuffer,
    /// The shown method's work per pixel (taps, steps, listed edges, rays: its cost view).
    Cost,
    /// The pixels whose V or t (decoded from t + 2 × branch) is NaN, infinite, below 0 or above
    /// 1, in magenta over the image in dimmed grey ([`crate::render::Frame::out_of_range`]).
    Range,
}

impl View {
    pub const ALL: [View; 9] = [
        View::Final,
        View::Visibility,
        View::T,
        View::Classes,
        View::Error,
        View::Flip,
        View::DBuffer,
        View::Cost,
        View::Range,
    ];

    pub fn name(self) -> &'static str {
        match self {
            View::Final => "final",
            View::Visibility => "V",
            View::T => "t",
            View::Classes => "classes",
            View::Error => "error",
            View::Flip => "FLIP",
            View::DBuffer => "D-buffer",
            View::Cost => "cost",
            View::Range => "NaN / range",
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            View::Final => "the shaded image",
            View::Visibility => "V, the visible fraction of the disk, per pixel",
            View::T => "t, the visibility parameter before V(t)",
            View::Classes => "lit / penumbra (visible or hidden from the centre) / umbra",
            View::Error => "|V − V_reference| against the reference at its current sample count",
            View::Flip => {
                "FLIP (Andersson et al. 2020) of the shaded image against the reference's: how \
                 different they look, 0 … 1"
            }
            View::DBuffer => "the method's light-space maps (the D-buffer), one channel or several",
            View::Cost => {
                "the method's work per pixel (its taps, steps, listed edges or rays; the \
                 inspector names the unit and the path taken)"
            }
            View::Range => {
                "in magenta the pixels whose V or t is NaN, infinite, below 0 or above 1 (what \
                 the method returned, before any clamp); the rest of the image dimmed"
            }
        }
    }

    /// `VIEW_*` of `shaders/shared/view_inputs.wgsl`.
    pub fn code(self) -> u32 {
        match self {
            View::Final => 0,
            View::Visibility => 1,
            View::T => 2,
            View::Classes => 3,
            View::Error => 4,
            View::DBuffer => 5,
            View::Cost => 6,
            View::Flip => 7,
            View::Range => 8,
        }
    }

    /// Whether it shows the light-space maps (square, the maps' size) rather than the camera's
    /// image.
    pub fn in_light_space(self) -> bool {
        self == View::DBuffer
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ColorMap {
    Gray,
    Heat,
    Turbo,
}

impl ColorMap {
    pub const ALL: [ColorMap; 3] = [ColorMap::Gray, ColorMap::Heat, ColorMap::Turbo];

    pub fn name(self) -> &'static str {
        match self {
            ColorMap::Gray => "gray",
            ColorMap::Heat => "heat",
            ColorMap::Turbo => "turbo",
        }
    }

    /// `COLORMAP_*` of `shaders/shared/view_inputs.wgsl`.
    pub fn code(self) -> u32 {
        match self {
            ColorMap::Gray => 0,
            ColorMap::Heat => 1,
            ColorMap::Turbo => 2,
        }
    }
}

/// Black and white points and a colour map; `auto` refits the range to every new image.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mapping {
    pub black: f32,
    pub white: f32,
    pub map: ColorMap,
    pub auto: bool,
}

impl Mapping {
    pub fn unit() -> Self {
        Self {
            black: 0.0,
            white: 1.0,
            map: ColorMap::Gray,
            auto: false,
        }
    }

    pub fn error() -> Self {
        Self {
            black: 0.0,
            white: 0.25,
            map: ColorMap::Heat,
            auto: false,
        }
    }

    pub fn auto() -> Self {
        Self {
            black: 0.0,
            white: 1.0,
            map: ColorMap::Turbo,
            auto: true,
        }
    }

    /// Fit black and white to `values`, from the 0.5th to the 99.5th percentile (extruded volume
    /// ends reach hundreds of metres and would squash everything else into one colour); leaves
    /// the range alone when there are no finite values.
    pub fn fit(&mut self, values: impl Iterator<Item = f32>) {
        let mut v: Vec<f32> = values.filter(|v| v.is_finite()).collect();
        if v.is_empty() {
            return;
        }
        let last = v.len() - 1;
        let lo_i = (last as f32 * 0.005).floor() as usize;
        let hi_i = ((last as f32 * 0.995).ceil() as usize).min(last);
        let (_, hi, _) = v.select_nth_unstable_by(hi_i, f32::total_cmp);
        let hi = *hi;
        let (_, lo, _) = v.select_nth_unstable_by(lo_i, f32::total_cmp);
        self.black = *lo;
        self.white = hi;
    }
}

/// How to show a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewParams {
    pub view: View,
    /// Which light-map channels the light-space view shows (R, G, B, A).
    pub channels: [bool; 4],
    pub mapping: Mapping,
}

/// At most this many light-map channels are shown.
pub const MAX_CHANNELS: usize = 4;

/// `ViewUniforms` of `shaders/shared/view_inputs.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ViewUniforms {
    pub kind: u32,
    pub channel_mask: u32,
    pub colormap: u32,
    pub has_reference: u32,
    pub black: f32,
    pub white: f32,
    pub map_size: f32,
    pub channel_count: u32,
    pub channels: [[u32; 4]; MAX_CHANNELS],
    /// Per light-map texture, its frame tag (0: read as stored).
    pub tags: [u32; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub map_view_proj: [[f32; 4]; 4],
    pub probe: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<ViewUniforms>() == 256);

/// `NO_FALLBACK` of `shaders/shared/view_inputs.wgsl`.
pub const NO_FALLBACK: u32 = 255;

impl ViewUniforms {
    pub fn new(
        params: &ViewParams,
        camera_view_proj: Mat4,
        maps: Option<(&LightMaps<'_>, u32)>,
        has_reference: bool,
    ) -> ViewUniforms {
        let mut channels = [[0, 0, 0, NO_FALLBACK]; MAX_CHANNELS];
        let mut tags = [0; 4];
        let (count, size, map_vp) = match maps {
            Some((m, _)) => {
                for (slot, c) in channels.iter_mut().zip(m.channels) {
                    *slot = channel_code(c);
                }
                for (slot, t) in tags.iter_mut().zip(m.tags) {
                    *slot = t.bits();
                }
                (
                    m.channels.len().min(MAX_CHANNELS) as u32,
                    m.size,
                    m.view_proj,
                )
            }
            None => (0, 0, Mat4::IDENTITY),
        };
        let mask = params
            .channels
            .iter()
            .enumerate()
            .filter(|(_, on)| **on)
            .fold(0u32, |m, (i, _)| m | (1 << i));
        ViewUniforms {
            kind: params.view.code(),
            channel_mask: mask,
            colormap: params.mapping.map.code(),
            has_reference: u32::from(has_reference),
            black: params.mapping.black,
            white: params.mapping.white,
            map_size: size as f32,
            channel_count: count,
            channels,
            tags,
            inv_view_proj: camera_view_proj.inverse().to_cols_array_2d(),
            map_view_proj: map_vp.to_cols_array_2d(),
            probe: [0; 4],
        }
    }
}

/// A channel as the shader reads it: texture, component, `EMPTY_*`, fallback.
fn channel_code(c: &Channel) -> [u32; 4] {
    [
        c.texture,
        c.component,
        match c.empty {
            Empty::Far => 0,
            Empty::NonPositive => 1,
        },
        c.or.map_or(NO_FALLBACK, |(t, k)| t * 4 + k),
    ]
}

/// What the view pass and the probe read: the camera targets, the reference V, the light maps.
pub struct ViewInputs<'a> {
    pub camera: &'a CameraTargets,
    pub camera_view_proj: Mat4,
    /// The reference V texture and its generation, when it holds V of this frame's size.
    pub reference: Option<(&'a wgpu::TextureView, u64)>,
    pub maps: Option<LightMaps<'a>>,
}

/// The layout and the stand-in textures the view pass and the probe share, built once per device.
pub struct ViewLayout {
    pub layout: wgpu::BindGroupLayout,
    /// 1×1 stand-ins where a frame has no reference or no light maps.
    blank_float: Texture,
}

impl ViewLayout {
    pub fn get(ctx: &GpuContext) -> Arc<ViewLayout> {
        ctx.shared(|device| {
            use wgpu::ShaderStages as S;
            use wgpu::TextureViewDimension as D;
            let both = S::FRAGMENT | S::COMPUTE;
            let float = |b| texture_entry(b, both, D::D2);
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("ViewLayout::layout"),
                entries: &[
                    uniform_entry(0, both),
                    float(1),
                    float(2),
                    wgpu::BindGroupLayoutEntry {
                        binding: 3,
                        visibility: both,
                        // An unfilterable float: GLSL has no `textureLoad` of a depth texture.
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable: false },
                            view_dimension: D::D2,
                            multisampled: false,
                        },
                        count: None,
                    },
                    float(4),
                    float(5),
                    float(6),
                    float(7),
                    float(8),
                ],
            });
            let blank_float = Texture::new(
                device,
                "ViewLayout::blank",
                (1, 1),
                wgpu::TextureFormat::R32Float,
                wgpu::TextureUsages::TEXTURE_BINDING,
            );
            ViewLayout {
                layout,
                blank_float,
            }
        })
    }
}

/// A uniform buffer and the bind group over a frame's inputs, made again only when an input's
/// textures are.
pub struct ViewBindings {
    shared: Arc<ViewLayout>,
    pub uniforms: wgpu::Buffer,
    bind_group: Option<(wgpu::BindGroup, [u64; 3])>,
}

impl ViewBindings {
    pub fn new(ctx: &GpuContext, label: &str) -> ViewBindings {
        ViewBindings {
            shared: ViewLayout::get(ctx),
            uniforms: uniform_buffer::<ViewUniforms>(&ctx.device, label),
            bind_group: None,
        }
    }

    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.shared.layout
    }

    /// The bind group for `inputs`, with `uniforms` written.
    pub fn bind(
        &mut self,
        ctx: &GpuContext,
        inputs: &ViewInputs<'_>,
        uniforms: &ViewUniforms,
    ) -> &wgpu::BindGroup {
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
        let key = [
            inputs.camera.generation,
            inputs.reference.map_or(0, |(_, g)| g),
            inputs.maps.as_ref().map_or(0, |m| m.generation),
        ];
        if self.bind_group.as_ref().is_some_and(|(_, k)| *k != key) {
            self.bind_group = None;
        }
        let (shared, buffer) = (&self.shared, &self.uniforms);
        let (group, _) = self.bind_group.get_or_insert_with(|| {
            let blank = &shared.blank_float.view;
            let reference = inputs.reference.map_or(blank, |(v, _)| v);
            let maps = inputs
                .maps
                .as_ref()
                .map_or([blank, blank, blank], |m| m.textures);
            let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("ViewBindings::bind_group"),
                layout: &shared.layout,
                entries: &[
                    buffer_entry(0, buffer),
                    view_entry(1, &inputs.camera.color_bytes),
                    view_entry(2, &inputs.camera.data.view),
                    view_entry(3, &inputs.camera.depth.view),
                    view_entry(4, reference),
                    view_entry(5, maps[0]),
                    view_entry(6, maps[1]),
                    view_entry(7, maps[2]),
                    view_entry(8, &inputs.camera.cost.view),
                ],
            });
            (group, key)
        });
        group
    }
}

/// The pipelines, one per view and colour map (made on first use), built once per device.
pub struct ViewPass {
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    pipelines: [OnceLock<wgpu::RenderPipeline>; 9 * 3],
}

impl ViewPass {
    pub fn get(ctx: &GpuContext) -> Arc<ViewPass> {
        ctx.shared(|device| {
            let layout = ViewLayout::get(ctx);
            ViewPass {
                module: shader_module(device, "passes/view.wgsl"),
                layout: pipeline_layout(device, "ViewPass::layout", &[&layout.layout]),
                pipelines: Default::default(),
            }
        })
    }

    /// The pipeline drawing `params`'s view (and colour map, for the scalar views).
    fn pipeline(&self, device: &wgpu::Device, params: &ViewParams) -> &wgpu::RenderPipeline {
        let map = match params.view {
            View::Visibility | View::T | View::Error | View::Flip | View::DBuffer | View::Cost => {
                params.mapping.map.code()
            }
            View::Final | View::Classes | View::Range => 0,
        };
        let slot = (params.view.code() * 3 + map) as usize;
        self.pipelines[slot.min(9 * 3 - 1)].get_or_init(|| {
            let constants = [
                ("VIEW_KIND", f64::from(params.view.code())),
                ("COLORMAP", f64::from(map)),
            ];
            let options = wgpu::PipelineCompilationOptions {
                constants: &constants,
                ..Default::default()
            };
            let targets = [opaque(DISPLAY_FORMAT)];
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("ViewPass::pipeline"),
                layout: Some(&self.layout),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some("vs_main"),
                    compilation_options: options.clone(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
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

/// The texture the viewport shows.
pub struct Display {
    pub texture: Texture,
    pub width: u32,
    pub height: u32,
    /// Changes whenever the texture is made again (the viewport registers it again).
    pub generation: u64,
}

/// A session's view pass: its uniforms, bind group and display texture.
pub struct ViewTarget {
    pass: Arc<ViewPass>,
    bindings: ViewBindings,
    display: Option<Display>,
}

impl ViewTarget {
    pub fn new(ctx: &GpuContext) -> ViewTarget {
        ViewTarget {
            pass: ViewPass::get(ctx),
            bindings: ViewBindings::new(ctx, "ViewTarget::uniforms"),
            display: None,
        }
    }

    pub fn display(&self) -> Option<&Display> {
        self.display.as_ref()
    }

    /// Draw `params`'s view of `inputs` into the display texture (sized for the view: the camera
    /// image, or the light maps' square).
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        inputs: &ViewInputs<'_>,
        params: &ViewParams,
    ) {
        let (width, height) = match (&inputs.maps, params.view.in_light_space()) {
            (Some(m), true) => (m.size, m.size),
            _ => (inputs.camera.width, inputs.camera.height),
        };
        if self
            .display
            .as_ref()
            .is_none_or(|d| d.width != width || d.height != height)
        {
            use wgpu::TextureUsages as U;
            self.display = Some(Display {
                texture: Texture::new(
                    &ctx.device,
                    "ViewTarget::display",
                    (width, height),
                    DISPLAY_FORMAT,
                    U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
                ),
                width,
                height,
                generation: super::next_generation(),
            });
        }
        let uniforms = ViewUniforms::new(
            params,
            inputs.camera_view_proj,
            inputs.maps.as_ref().map(|m| (m, m.size)),
            inputs.reference.is_some(),
        );
        let group = self.bindings.bind(ctx, inputs, &uniforms);
        let Some(display) = &self.display else { return };
        let span = rec.span("view_pass");
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("ViewTarget::pass"),
            color_attachments: &[cleared(&display.texture.view, wgpu::Color::BLACK)],
            depth_stencil_attachment: None,
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(self.pass.pipeline(&ctx.device, params));
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}
