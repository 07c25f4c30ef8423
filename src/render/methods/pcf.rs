//! `pcf`: percentage-closer filtering (Reeves et al. 1987) of the centre's shadow map, a
//! (2R + 1)² block of hard tests, each against the receiver's plane
//! (`shaders/methods/pcf.wgsl`).

use super::on_shadow_map::{Flavor, OnShadowMap};
use super::{Knob, MethodSpec};

/// The kernel radius R in shadow-map texels.
pub static RADIUS: Knob = Knob {
    name: "pcf-radius",
    help: "pcf: kernel radius in shadow-map texels ((2R+1)² taps)",
    min: 0,
    max: 8,
    default: 2,
    max_name: None,
};

pub static PCF: MethodSpec = MethodSpec {
    name: "pcf",
    description: "percentage-closer filtering of the shadow map",
    knobs: &[&RADIUS],
    cpu_side: false,
    hard: true,
    needs: None,
    new: |ctx| Box::new(OnShadowMap::new(ctx, &FLAVOR)),
};

static FLAVOR: Flavor = Flavor {
    shader: "methods/pcf.wgsl",
    knobs: |f| [f.knobs.get(&RADIUS) as f32, 0.0, 0.0, 0.0],
    extra: None,
};
