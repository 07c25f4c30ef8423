//! `smrt`: shadow-map ray tracing, the soft shadows of Unreal Engine 5's virtual shadow maps, on
//! the centre's shadow map (`shaders/methods/smrt.wgsl`). Per pixel `smrt-rays` rays toward
//! points of the light (a Fibonacci lattice over the light's area, rotated per pixel by
//! interleaved gradient noise: fixed by the pixel, so two renders agree), each marched in
//! `smrt-steps` steps through the one depth layer the map holds, with UE5's gap extrapolation
//! and adaptive ray count (two rays toward opposite halves of the light first; if they agree,
//! no more). UE5's defaults for local
//! lights: 7 rays (`r.Shadow.Virtual.SMRT.RayCountLocal`), 8 samples a ray
//! (`SamplesPerRayLocal`). docs/method/README.md#smrt says where it errs.

use super::Cost;
use super::on_shadow_map::{Flavor, OnShadowMap};
use super::{FrameInputs, Knob, MethodSpec, Scaled, Switch, Quality};

pub static RAYS: Knob = Knob::int(
    "smrt-rays",
    "smrt: rays per pixel toward points of the light",
    1..=64,
    7,
);

pub static STEPS: Knob = Knob::int(
    "smrt-steps",
    "smrt: shadow-map samples per ray",
    1..=32,
    8,
);

pub static EXTRAPOLATE: Switch = Switch::new(
    "smrt-extrapolate",
    "smrt: where a ray jumps behind a nearer surface, compare it with the last surface it passed, extrapolated (off: held)",
    true,
);

pub static ADAPTIVE: Switch = Switch::new(
    "smrt-adaptive",
    "smrt: adaptive ray count (two rays toward opposite halves of the light first; if they agree, no more)",
    true,
);

/// The share of the way from the point to the light a ray is marched: beyond it nothing
/// occludes, so it caps the penumbra's width.
pub static RAY_LENGTH: Scaled = Scaled::new(
    "smrt-ray-length",
    "smrt: share of the way to the light each ray is marched, in 1/100 (caps the penumbra)",
    1..=100,
    100,
    100,
);

pub static SMRT: MethodSpec = MethodSpec::new("smrt", SHADER, |ctx| {
    Box::new(OnShadowMap::new(ctx, &FLAVOR))
})
.adapter(super::SHADOW_MAPPED)
.about("shadow-map ray tracing (Unreal Engine 5's virtual shadow map soft shadows)")
.knobs(&[&RAYS, &STEPS, &EXTRAPOLATE.0, &ADAPTIVE.0, &RAY_LENGTH.0])
.lights(super::AREA_LIGHTS)
.bench("smrt 7x8", &[(&RAYS, 7), (&STEPS, 8)])
.cost(Cost::counted("ray-march steps (shadow-map reads)").paths(&["not marched: off the map, or dark", "adaptive: its two first rays agreed", "every ray traced"]))
// Unreal's default is 7 rays of 8 samples (r.Shadow.Virtual.SMRT.RayCountLocal, SamplesPerRayLocal).
.sweep(
    &[Quality::Knob(&RAYS), Quality::Knob(&STEPS)],
    &[&[2, 4], &[4, 8], &[7, 8], &[16, 16], &[32, 32]],
);

const SHADER: &str = "methods/smrt.wgsl";

static FLAVOR: Flavor = Flavor {
    shader: SHADER,
    knobs: smrt_knobs,
    extra: None,
};

/// The shader's flags (`FLAG_EXTRAPOLATE`, `FLAG_ADAPTIVE` of smrt.wgsl).
const FLAG_EXTRAPOLATE: u32 = 1;
const FLAG_ADAPTIVE: u32 = 2;

fn smrt_knobs(f: &FrameInputs<'_>) -> [f32; 4] {
    let k = f.knobs;
    let flags = if k.get(&EXTRAPOLATE) { FLAG_EXTRAPOLATE } else { 0 }
        | if k.get(&ADAPTIVE) { FLAG_ADAPTIVE } else { 0 };
    [
        k.get(&RAYS) as f32,
        k.get(&STEPS) as f32,
        flags as f32,
        k.get(&RAY_LENGTH),
    ]
}
