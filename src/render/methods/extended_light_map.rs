//! `extended-light-map`: Brabec, Heidrich and Seidel's extended light maps (2000): do as much as
//! possible in the light's pass. One pass from the light's centre writes the light each surface
//! gets in RGB (a spotlight's falloff, or the spotlight through a projected texture from
//! `assets/gobo.png`, with the cosines) and its distance from the light in A
//! (`passes::extended_light_map`); the camera pass takes light and shadow from that one lookup
//! (`shaders/methods/extended_light_map.wgsl`). The map's four channels are the lab's light maps,
//! like the D-buffer's.
//!
//! Its errors are the shadow map's (aliasing at texel size, the bias), the alpha channel's
//! precision (`--elm-depth-bits 8` is the 2000 hardware's: acne or light leaking by up to a
//! level of the far distance), and lighting computed at the map's resolution for the surface the
//! light sees (blocky under magnification, wrong beside silhouettes where a texel belongs to
//! another surface).

use super::Cost;
use super::{AdapterNeeds, Quality, SHADOW_MAP};
use crate::render::adapter::{FormatNeed, Usage};
use glam::{Mat4, Vec3, Vec4};
use wgpu::TextureFormat as F;

use super::{
    require, CameraGroup, Channel, Choice, Empty, FrameInputs, Knob, Knobs, LightMaps, MethodSpec,
    MethodState, Prepare, SharedMaps,
};
use crate::geometry::light_view::LightView;
use crate::render::passes::extended_light_map::{ElmParams, ExtendedLightMap, Pattern};
use crate::render::passes::shadow_map::{lookup_entries, ShadowUniforms, PARAMS_BINDING};
use crate::render::{
    buffer_entry, uniform_buffer, uniform_entry, view_entry, GpuContext, RenderError,
};

/// Bits of the distance in the alpha channel.
pub static DEPTH_BITS: Knob = Knob::int(
    "elm-depth-bits",
    "extended-light-map: bits of the light's distance in the map's alpha channel (8 = the \
     2000 hardware's alpha channel)",
    8..=24,
    16,
);

/// What the RGB holds.
pub static PATTERN: Choice = Choice::new(
    "elm-pattern",
    "extended-light-map: the light in RGB: 0 = a spotlight's falloff, 1 = the spotlight \
     through the projected texture assets/gobo.png, 2 = uniform",
    &["spotlight", "gobo", "uniform"],
    0,
);

pub static EXTENDED_LIGHT_MAP: MethodSpec = MethodSpec::new("extended-light-map", SHADER, |ctx| {
    Box::new(ElmMethod::new(ctx))
})
.adapter(NEEDS)
.about("extended light map (Brabec et al. 2000): light colour in RGB, distance in A")
.knobs(&[&DEPTH_BITS, &PATTERN.0])
.hard()
.overlay_note("extended-light-map: its channels are in the View panel")
.cost(Cost::counted("light-map taps").constant("one lookup"))
.sweep(&[Quality::Knob(&DEPTH_BITS)], &[&[8], &[16], &[24]]);

/// What it needs of the adapter: float maps and the light's gobo, filtered.
const NEEDS: AdapterNeeds = AdapterNeeds::formats(&[
    SHADOW_MAP[0],
    SHADOW_MAP[1],
    FormatNeed::new(Usage::Render, &[F::Rgba32Float]),
    FormatNeed::new(Usage::Filter, &[F::Rgba8UnormSrgb]),
]);

const SHADER: &str = "methods/extended_light_map.wgsl";

/// The inner cone of the spot, as a share of its outer one.
pub const INNER_SHARE: f32 = 0.6;

/// The map's channels: the light's colour and the distance.
pub const CHANNELS: &[Channel] = &[
    Channel::new("light R", 0, 0, Empty::NonPositive),
    Channel::new("light G", 0, 1, Empty::NonPositive),
    Channel::new("light B", 0, 2, Empty::NonPositive),
    Channel::new("distance (A)", 0, 3, Empty::Far),
];

/// The pattern the knob asks for.
pub fn pattern(knobs: &Knobs) -> Pattern {
    match knobs.get(&PATTERN) {
        1 => Pattern::Texture,
        2 => Pattern::Uniform,
        _ => Pattern::Spot,
    }
}

/// The largest angle between `axis` and a direction the light view covers (its four corners).
pub fn half_angle(view: &LightView, apex: Vec3, axis: Vec3) -> f32 {
    let inv = view.view_projection().inverse();
    let mut widest = 0.0f32;
    for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let p = inv * Vec4::new(x, y, 0.5, 1.0);
        let dir = (p.truncate() / p.w - apex).normalize_or_zero();
        widest = widest.max(dir.dot(axis).clamp(-1.0, 1.0).acos());
    }
    widest
}

/// What the map of this frame is made from.
pub fn elm_params(inputs: &FrameInputs<'_>) -> ElmParams {
    let light = inputs.scene.light;
    let view = inputs.light_view;
    // A disk's spotlight points along its normal; a line's along the view fitted to the casters.
    let axis = light.as_area().map_or_else(
        || {
            view.view
                .inverse()
                .transform_vector3(Vec3::NEG_Z)
                .normalize_or(Vec3::NEG_Y)
        },
        |d| d.normal,
    );
    let outer = half_angle(view, light.center(), axis);
    ElmParams {
        view_proj: view.view_projection(),
        light: light.center(),
        far: view.far,
        axis,
        intensity: light.intensity(),
        outer,
        inner: INNER_SHARE * outer,
        bits: inputs.knobs.get(&DEPTH_BITS),
        pattern: pattern(inputs.knobs),
        emitter: light.as_area().map(|d| d.normal),
        size: inputs.map_size,
    }
}

/// The map's RGB at world point `y` with unit normal `n` for a spotlight or uniform pattern: the
/// CPU twin of `light_rgb` in `shaders/passes/extended_light_map.wgsl` (the projected texture
/// aside).
pub fn light_rgb(p: &ElmParams, y: Vec3, n: Vec3) -> Vec3 {
    let dir = (y - p.light).normalize_or_zero();
    let smoothstep = |e0: f32, e1: f32, x: f32| {
        let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    let spot = match p.pattern {
        Pattern::Uniform => 1.0,
        _ => smoothstep(p.outer.cos(), p.inner.cos(), dir.dot(p.axis)),
    };
    let cos_receiver = n.dot(dir).abs();
    let cos_emitter = p.emitter.map_or(1.0, |e| dir.dot(e).max(0.0));
    Vec3::splat(p.intensity * spot * cos_receiver * cos_emitter)
}

/// `ExtendedLightMapParams` of `shaders/methods/extended_light_map.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ExtendedLightMapParams {
    /// 1 / the light view's far distance: the alpha channel's scale.
    pub inv_far: f32,
    /// The alpha channel's depth levels, `2^bits − 1`.
    pub levels: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

impl ExtendedLightMapParams {
    pub fn new(p: &ElmParams) -> ExtendedLightMapParams {
        ExtendedLightMapParams {
            inv_far: 1.0 / p.far,
            // At most 2^24 − 1: exact in the f32 `levels()` is.
            levels: p.levels() as u32,
            ..ExtendedLightMapParams::default()
        }
    }
}

/// What the map was made from.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Made {
    revision: u64,
    bits: u32,
    pattern: Pattern,
    size: u32,
}

pub struct ElmMethod {
    elm: ExtendedLightMap,
    /// Bound for the map's generation.
    camera: CameraGroup,
    uniforms: wgpu::Buffer,
    params: wgpu::Buffer,
    made: Option<Made>,
    view_proj: Mat4,
}

impl ElmMethod {
    pub fn new(ctx: &GpuContext) -> ElmMethod {
        let mut entries = lookup_entries().to_vec();
        entries.push(uniform_entry(PARAMS_BINDING, wgpu::ShaderStages::FRAGMENT));
        ElmMethod {
            elm: ExtendedLightMap::new(ctx),
            camera: CameraGroup::new(ctx, SHADER, &entries),
            uniforms: uniform_buffer::<ShadowUniforms>(&ctx.device, "ElmMethod::uniforms"),
            params: uniform_buffer::<ExtendedLightMapParams>(&ctx.device, "ElmMethod::params"),
            made: None,
            view_proj: Mat4::IDENTITY,
        }
    }
}

impl MethodState for ElmMethod {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, _, rec) = p;
        let ctx = inputs.ctx;
        let params = elm_params(inputs);
        let made = Made {
            revision: inputs.revision,
            bits: params.bits,
            pattern: params.pattern,
            size: params.size,
        };
        if self.made != Some(made) {
            self.elm.record(ctx, rec, &params, inputs.surfaces);
            self.view_proj = params.view_proj;
            self.made = Some(made);
        }
        let map = require(self.elm.targets(), "the extended light map was not made")?;
        let uniforms = ShadowUniforms::new(inputs.light_view, map.size);
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        let own = ExtendedLightMapParams::new(&params);
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&own));
        let entries = [
            buffer_entry(0, &self.uniforms),
            view_entry(1, &map.map.view),
            buffer_entry(PARAMS_BINDING, &self.params),
        ];
        self.camera.bind(&ctx.device, map.generation, &entries);
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, _shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        let t = self.elm.targets().filter(|_| self.made.is_some())?;
        Some(LightMaps::single(
            t.size,
            self.view_proj,
            &t.map,
            CHANNELS,
            t.generation,
        ))
    }

    fn invalidate(&mut self) {
        self.made = None;
    }
}
