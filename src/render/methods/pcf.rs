//! `pcf`: percentage-closer filtering (Reeves et al. 1987) of the centre's shadow map, a
//! (2R + 1)² block of hard tests, each against the receiver's plane
//! (`shaders/methods/pcf.wgsl`).

use super::on_shadow_map::{Flavor, OnShadowMap};
use super::{Bench, Knob, MethodSpec};

/// The kernel radius R in shadow-map texels.
pub static RADIUS: Knob = Knob::int(
    "pcf-radius",
    "pcf: kernel radius in shadow-map texels ((2R+1)² taps)",
    0..=8,
    2,
);

pub static PCF: MethodSpec = MethodSpec {
    name: "pcf",
    description: "percentage-closer filtering of the shadow map",
    shader: SHADER,
    knobs: &[&RADIUS],
    cpu_side: false,
    hard: true,
    lights: None,
    adapter: super::needs::SHADOW_MAPPED,
    bench: Bench::DEFAULTS,
    overlay_note: None,
    line_samples: None,
    new: |ctx| Box::new(OnShadowMap::new(ctx, &FLAVOR)),
};

const SHADER: &str = "methods/pcf.wgsl";

static FLAVOR: Flavor = Flavor {
    shader: SHADER,
    knobs: |f| [f.knobs.get(&RADIUS) as f32, 0.0, 0.0, 0.0],
    extra: None,
};
