//! `pcf`: percentage-closer filtering (Reeves et al. 1987) of the centre's shadow map, a
//! (2R + 1)² block of hard tests, each against the receiver's plane
//! (`shaders/methods/pcf.wgsl`).

use super::on_shadow_map::{Flavor, OnShadowMap};
use super::Cost;
use super::{Knob, MethodSpec, Quality};

/// The kernel radius R in shadow-map texels.
pub static RADIUS: Knob = Knob::int(
    "pcf-radius",
    "pcf: kernel radius in shadow-map texels ((2R+1)² taps)",
    0..=8,
    2,
);

pub static PCF: MethodSpec = MethodSpec::new("pcf", SHADER, |ctx| {
    Box::new(OnShadowMap::new(ctx, &FLAVOR))
})
.adapter(super::SHADOW_MAPPED)
.about("percentage-closer filtering of the shadow map")
.knobs(&[&RADIUS])
.hard()
.cost(Cost::counted("shadow-map taps").constant("(2R + 1)² taps, R its radius"))
.sweep(&[Quality::Knob(&RADIUS)], &[&[1], &[2], &[4], &[8]]);

const SHADER: &str = "methods/pcf.wgsl";

static FLAVOR: Flavor = Flavor {
    shader: SHADER,
    knobs: |f| [f.knobs.get(&RADIUS) as f32, 0.0, 0.0, 0.0],
    extra: None,
};
