//! `msm`: moment shadow maps (Peters & Klein, I3D 2015), filtered: the centre's shadow map as
//! four quantization-optimized moments a texel in a summed-area table (`passes::moment_sat`), a
//! `(2R + 1)²` box of it per pixel, and Hamburger 4MSM at the receiver's depth
//! (`shaders/methods/msm.wgsl`; the arithmetic's CPU twin: `geometry::moments`). Where the box
//! holds at most two depths the moments determine them and the test is exact; with more it is a
//! bound, and light leaks — less than the variance shadow map's (`leak-test`).

use super::shadow_mapped::{moment_bias, ShadowMapped, MOMENT_TABLE_NEEDS};
use super::Cost;
use super::{FrameInputs, Knob, MethodSpec, Quality, Scaled};
use crate::render::passes::moment_sat::MomentSat;

/// The filter's half-width R in shadow-map texels.
pub static RADIUS: Knob = Knob::int(
    "msm-radius",
    "msm: moments averaged over (2R+1)² shadow-map texels",
    0..=32,
    3,
);

/// The moment bias α ([`moment_bias`]).
pub static BIAS: Scaled = moment_bias(
    "msm-bias",
    "msm: moment bias in 1/1,000,000 (Peters & Klein's 30 for 16 bits a moment): larger leaks more, smaller breaks up",
);

pub static MSM: MethodSpec = MethodSpec::new("msm", SHADER, |ctx| {
    Box::new(ShadowMapped::new(
        ctx,
        SHADER,
        MomentSat::new(ctx),
        MsmParams::new,
    ))
})
.adapter(MOMENT_TABLE_NEEDS)
.about("moment shadow maps (Peters & Klein 2015), four moments, filtered")
.knobs(&[&RADIUS, &BIAS.0])
.hard()
.cost(Cost::counted("summed-area table reads").constant("two boxes of four corners"))
.sweep(&[Quality::Knob(&RADIUS)], &[&[1], &[3], &[6], &[12]]);

const SHADER: &str = "methods/msm.wgsl";

/// `MsmParams` of `shaders/methods/msm.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MsmParams {
    /// The box's half-width R in texels.
    pub radius: u32,
    /// The moment bias α.
    pub bias: f32,
    pub _pad0: u32,
    pub _pad1: u32,
}

impl MsmParams {
    pub fn new(f: &FrameInputs<'_>) -> MsmParams {
        MsmParams {
            radius: f.knobs.get(&RADIUS),
            bias: f.knobs.get(&BIAS),
            ..MsmParams::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::moments::DEFAULT_MOMENT_BIAS;
    use crate::render::Knobs;

    /// Peters & Klein (I3D 2015) give α = 3·10⁻⁵ for moments quantized to 16 bits each (64 bits
    /// a texel), as the table's fixed point holds them (`msm-soft` reads the same table and
    /// holds its bias to the same). The knob and the CPU twin say so (they said 6·10⁻⁵, twice
    /// the paper's, which leaks more).
    #[test]
    fn the_moment_bias_is_the_papers_for_16_bit_moments() {
        let k = Knobs::default();
        for (name, bias) in [
            ("msm", k.get(&BIAS)),
            ("geometry::moments", DEFAULT_MOMENT_BIAS),
        ] {
            assert!((bias - 3e-5).abs() < 1e-9, "{name}: {bias}");
        }
    }
}
