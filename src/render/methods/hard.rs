//! `hard`: a shadow map from the light centre (Williams 1978), the `|cx_o|` test alone with
//! slope-scaled bias (`shaders/methods/hard.wgsl`).

use super::shadow_mapped::ShadowMapped;
use super::MethodSpec;
use super::{Cost, Quality};

pub static HARD: MethodSpec = MethodSpec::new("hard", SHADER, |ctx| {
    Box::new(ShadowMapped::new(ctx, SHADER, (), |_| ()))
})
.adapter(super::SHADOW_MAPPED)
.about("hard shadow map from the light centre")
.hard()
.cost(Cost::counted("shadow-map taps").constant("one test of the centre's shadow map"))
.sweep(&[Quality::MapSize], &[&[512], &[1024], &[2048], &[4096]]);

const SHADER: &str = "methods/hard.wgsl";
