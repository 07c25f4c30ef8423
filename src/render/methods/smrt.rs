//! `smrt`: shadow-map ray tracing, the soft shadows Unreal Engine 5 draws for a local light from
//! its virtual shadow map, here on the centre's shadow map (`shaders/methods/smrt.wgsl`, a port
//! of UE's `TraceLocalLight`, `SMRTRayCast` and `VirtualShadowMapScreenRayCast`). Per pixel: the
//! receiver pushed out along its normal (`r.Shadow.Virtual.NormalBias`), a screen ray through
//! the camera's depth toward the light's centre that says where the shadow-map rays start (a
//! depth prepass, [`ScreenPass`]; `r.Shadow.Virtual.ScreenRayLength`), then `smrt-rays` rays
//! toward points of the light, each clipped to the angle `smrt-max-angle` seen from the light
//! and to three quarters of the way there, its start dithered over a texel in the receiver's
//! plane and biased by the plane's slope, marched in `smrt-steps` steps through the one depth
//! layer the map holds with UE's gap extrapolation (`smrt-extrapolate-slope`), and the adaptive
//! ray count (a 2×2 quad of pixels votes where UE's wave does). UE's defaults for local lights
//! throughout. docs/method/README.md#smrt says what differs from UE and where it errs.

use super::{
    AdapterNeeds, CameraGroup, Cost, FrameInputs, Knob, LightMaps, MethodSpec, MethodState,
    Prepare, Quality, Scaled, SharedMaps, Switch,
};
use crate::render::passes::shadow_map::{lookup_entries, ShadowUniforms, PARAMS_BINDING};
use crate::render::passes::stencil_volumes::ScreenPass;
use crate::render::{
    buffer_entry, texture_entry, uniform_buffer, uniform_entry, view_entry, GpuContext, RenderError,
};

/// `r.Shadow.Virtual.SMRT.RayCountLocal`.
pub static RAYS: Knob = Knob::int(
    "smrt-rays",
    "smrt: rays per pixel toward points of the light (UE's RayCountLocal, 7)",
    1..=64,
    7,
);

/// `r.Shadow.Virtual.SMRT.SamplesPerRayLocal`.
pub static STEPS: Knob = Knob::int(
    "smrt-steps",
    "smrt: shadow-map samples per ray (UE's SamplesPerRayLocal, 8)",
    1..=32,
    8,
);

/// `r.Shadow.Virtual.SMRT.AdaptiveRayCount`.
pub static ADAPTIVE: Switch = Switch::new(
    "smrt-adaptive",
    "smrt: adaptive ray count (a 2x2 quad stops after one ray where all of it missed, after two where all of it was hit)",
    true,
);

/// `r.Shadow.Virtual.SMRT.MaxRayAngleFromLight`, in milliradians: the angle a ray may span seen
/// from the light, which caps the penumbra's width.
pub static MAX_ANGLE: Scaled = Scaled::new(
    "smrt-max-angle",
    "smrt: largest angle a ray may span seen from the light, in 1/1000 rad (UE's MaxRayAngleFromLight, 30; caps the penumbra)",
    1..=1570,
    30,
    1000,
);

/// `r.Shadow.Virtual.SMRT.ExtrapolateMaxSlopeLocal`, in thousandths.
pub static EXTRAPOLATE_SLOPE: Scaled = Scaled::new(
    "smrt-extrapolate-slope",
    "smrt: past a depth gap, extrapolate the last surface passed at most this slope, in 1/1000 of the ray's depth change (UE's ExtrapolateMaxSlopeLocal, 50; 0: held)",
    0..=1000,
    50,
    1000,
);

/// `r.Shadow.Virtual.SMRT.TexelDitherScaleLocal` times the light's own VSM texel dither scale
/// (1 by default).
pub const TEXEL_DITHER: f32 = 2.0;
/// `r.Shadow.Virtual.SMRT.MaxSlopeBiasLocal`.
pub const MAX_SLOPE_BIAS: f32 = 50.0;
/// `r.Shadow.Virtual.ScreenRayLength`.
pub const SCREEN_RAY_LENGTH: f32 = 0.015;
/// `r.Shadow.Virtual.NormalBias` (0.5), over the 1000 UE divides it by.
pub const NORMAL_BIAS: f32 = 0.5 / 1000.0;

pub static SMRT: MethodSpec = MethodSpec::new("smrt", SHADER, |ctx| Box::new(Smrt::new(ctx)))
    .adapter(NEEDS)
    .about("shadow-map ray tracing (Unreal Engine 5's virtual shadow map soft shadows)")
    .knobs(&[
        &RAYS,
        &STEPS,
        &ADAPTIVE.0,
        &MAX_ANGLE.0,
        &EXTRAPOLATE_SLOPE.0,
    ])
    .lights(super::AREA_LIGHTS)
    .bench("smrt 7x8", &[(&RAYS, 7), (&STEPS, 8)])
    .cost(
        Cost::counted("screen-ray and ray-march samples (depth and shadow-map reads)").paths(&[
            "not marched: off the map, or dark",
            "adaptive: its quad's first rays all missed (lit after one ray)",
            "adaptive: its quad's first two rays all hit (umbra after two)",
            "every ray traced",
        ]),
    )
    // Unreal's default is 7 rays of 8 samples (r.Shadow.Virtual.SMRT.RayCountLocal, SamplesPerRayLocal).
    .sweep(
        &[Quality::Knob(&RAYS), Quality::Knob(&STEPS)],
        &[&[2, 4], &[4, 8], &[7, 8], &[16, 16], &[32, 32]],
    );

const SHADER: &str = "methods/smrt.wgsl";

/// The shadow map and the camera's depth prepass (its positions, as the stencil methods make
/// them).
const NEEDS: AdapterNeeds = AdapterNeeds::formats(&super::MAP_AND_SCREEN);

/// `SmrtParams` of `shaders/methods/smrt.wgsl`: UE's settings for local lights, the camera's
/// field of view and the ray counts.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SmrtParams {
    pub extrapolate_slope: f32,
    pub cot_max_angle: f32,
    pub texel_dither: f32,
    pub max_slope_bias: f32,
    pub screen_ray: f32,
    pub normal_bias: f32,
    pub tan_half_fov: [f32; 2],
    /// Rays per pixel.
    pub rays: u32,
    /// Shadow-map samples per ray.
    pub steps: u32,
    /// 1 for the adaptive ray count, 0 for every ray.
    pub adaptive: u32,
    pub _pad0: u32,
}

const _: () = assert!(std::mem::size_of::<SmrtParams>() == 48);

impl SmrtParams {
    pub fn new(f: &FrameInputs<'_>) -> SmrtParams {
        let angle = f.knobs.get(&MAX_ANGLE);
        let tan_y = (f.scene.camera.fov_y_deg.to_radians() * 0.5).tan();
        let aspect = f.view.width as f32 / f.view.height.max(1) as f32;
        SmrtParams {
            extrapolate_slope: f.knobs.get(&EXTRAPOLATE_SLOPE),
            cot_max_angle: 1.0 / angle.tan().max(1e-6),
            texel_dither: TEXEL_DITHER,
            max_slope_bias: MAX_SLOPE_BIAS,
            screen_ray: SCREEN_RAY_LENGTH,
            normal_bias: NORMAL_BIAS,
            tan_half_fov: [tan_y * aspect, tan_y],
            rays: f.knobs.get(&RAYS),
            steps: f.knobs.get(&STEPS),
            adaptive: u32::from(f.knobs.get(&ADAPTIVE)),
            _pad0: 0,
        }
    }
}

/// What the camera group was bound to.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bound {
    map: u64,
    screen: u64,
}

pub struct Smrt {
    screen: ScreenPass,
    camera: CameraGroup,
    uniforms: wgpu::Buffer,
    params: wgpu::Buffer,
}

impl Smrt {
    pub fn new(ctx: &GpuContext) -> Smrt {
        let mut entries = lookup_entries().to_vec();
        entries.push(uniform_entry(PARAMS_BINDING, wgpu::ShaderStages::FRAGMENT));
        entries.push(texture_entry(
            3,
            wgpu::ShaderStages::FRAGMENT,
            wgpu::TextureViewDimension::D2,
        ));
        Smrt {
            screen: ScreenPass::new(ctx),
            camera: CameraGroup::new(ctx, SHADER, &entries),
            uniforms: uniform_buffer::<ShadowUniforms>(&ctx.device, "Smrt::uniforms"),
            params: uniform_buffer::<SmrtParams>(&ctx.device, "Smrt::params"),
        }
    }
}

impl MethodState for Smrt {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        let ctx = inputs.ctx;
        let map = shared.shadow_map.update(inputs, rec)?;
        let uniforms = ShadowUniforms::new(inputs.light_view, map.size);
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        ctx.queue.write_buffer(
            &self.params,
            0,
            bytemuck::bytes_of(&SmrtParams::new(inputs)),
        );
        let targets = self.screen.begin(ctx, &inputs.view);
        let bound = Bound {
            map: map.generation,
            screen: targets.generation,
        };
        let entries = [
            buffer_entry(0, &self.uniforms),
            view_entry(1, &map.distance.view),
            buffer_entry(PARAMS_BINDING, &self.params),
            view_entry(3, &targets.position.view),
        ];
        self.camera.bind(&ctx.device, bound, &entries);
        self.screen.record_prepass(rec, inputs.surfaces);
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        shared.shadow_map.light_maps()
    }
}
