//! `hard`: a shadow map from the light centre (Williams 1978), the `|cx_o|` test alone with
//! slope-scaled bias (`shaders/methods/hard.wgsl`).

use super::on_shadow_map::{Flavor, OnShadowMap};
use super::{Bench, MethodSpec};

pub static HARD: MethodSpec = MethodSpec {
    name: "hard",
    description: "hard shadow map from the light centre",
    shader: SHADER,
    knobs: &[],
    cpu_side: false,
    hard: true,
    lights: None,
    adapter: super::needs::SHADOW_MAPPED,
    bench: Bench::DEFAULTS,
    overlay_note: None,
    line_samples: None,
    new: |ctx| Box::new(OnShadowMap::new(ctx, &FLAVOR)),
};

const SHADER: &str = "methods/hard.wgsl";

static FLAVOR: Flavor = Flavor {
    shader: SHADER,
    knobs: |_| [0.0; 4],
    extra: None,
};
