//! `hard`: a shadow map from the light centre (Williams 1978), the `|cx_o|` test alone with
//! slope-scaled bias (`shaders/methods/hard.wgsl`).

use super::on_shadow_map::{Flavor, OnShadowMap};
use super::MethodSpec;

pub static HARD: MethodSpec = MethodSpec {
    name: "hard",
    description: "hard shadow map from the light centre",
    knobs: &[],
    cpu_side: false,
    hard: true,
    needs: None,
    new: |ctx| Box::new(OnShadowMap::new(ctx, &FLAVOR)),
};

static FLAVOR: Flavor = Flavor {
    shader: "methods/hard.wgsl",
    knobs: |_| [0.0; 4],
    extra: None,
};
