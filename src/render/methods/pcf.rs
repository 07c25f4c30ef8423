//! `pcf`: percentage-closer filtering (Reeves et al. 1987) of the centre's shadow map, a
//! (2R + 1)² block of hard tests, each against the receiver's plane
//! (`shaders/methods/pcf.wgsl`).

use super::shadow_mapped::ShadowMapped;
use super::Cost;
use super::{FrameInputs, Knob, MethodSpec, Quality};

/// The kernel radius R in shadow-map texels.
pub static RADIUS: Knob = Knob::int(
    "pcf-radius",
    "pcf: kernel radius in shadow-map texels ((2R+1)² taps)",
    0..=8,
    2,
);

pub static PCF: MethodSpec = MethodSpec::new("pcf", SHADER, |ctx| {
    Box::new(ShadowMapped::new(ctx, SHADER, (), PcfParams::new))
})
.adapter(super::SHADOW_MAPPED)
.about("percentage-closer filtering of the shadow map")
.knobs(&[&RADIUS])
.hard()
.cost(Cost::counted("shadow-map taps").constant("(2R + 1)² taps, R its radius"))
.sweep(&[Quality::Knob(&RADIUS)], &[&[1], &[2], &[4], &[8]]);

const SHADER: &str = "methods/pcf.wgsl";

/// `PcfParams` of `shaders/methods/pcf.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PcfParams {
    /// The kernel radius R in texels.
    pub radius: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

impl PcfParams {
    pub fn new(f: &FrameInputs<'_>) -> PcfParams {
        PcfParams {
            radius: f.knobs.get(&RADIUS),
            ..PcfParams::default()
        }
    }
}
