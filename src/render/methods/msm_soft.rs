//! `msm-soft`: moment soft shadow mapping (Peters, Münstermann, Wetzstein & Klein, I3D 2016;
//! JCGT 2017), sized by the disk as `pcss` is, on `msm`'s summed-area table of four moments: the
//! blocker search is one box of the table, whose moments give the share of it in front of the
//! receiver and that share's mean depth; the penumbra that depth predicts sizes a second box,
//! whose moments give V (`shaders/methods/msm_soft.wgsl`). No per-tap loop. Under a rectangle
//! or polygon it is sized by the disk of the same area, as `pcss` is.

use super::shadow_mapped::{lowest_caster, moment_bias, ShadowMapped, MOMENT_TABLE_NEEDS};
use super::Cost;
use super::{FrameInputs, MethodSpec, Quality, Scaled};
use crate::render::passes::moment_sat::MomentSat;

/// The moment bias α ([`moment_bias`]), on `msm`'s table.
pub static BIAS: Scaled = moment_bias(
    "msm-soft-bias",
    "msm-soft: moment bias in 1/1,000,000 (Peters & Klein's 30 for 16 bits a moment)",
);

/// The least share of the search box in front of the receiver that counts as a blocker.
pub static LEAST_BLOCKER: Scaled = Scaled::new(
    "msm-soft-blockers",
    "msm-soft: least share of the blocker search in front of the receiver, in 1/1000, below which the point is lit",
    0..=500,
    5,
    1000,
);

pub static MSM_SOFT: MethodSpec = MethodSpec::new("msm-soft", SHADER, |ctx| {
    Box::new(ShadowMapped::new(
        ctx,
        SHADER,
        MomentSat::new(ctx),
        MsmSoftParams::new,
    ))
})
.adapter(MOMENT_TABLE_NEEDS)
.about("moment soft shadow mapping (Peters et al. 2016): blocker search and filter from moments")
.knobs(&[&BIAS.0, &LEAST_BLOCKER.0])
.lights(super::AREA_LIGHTS)
.cost(Cost::counted("summed-area table reads"))
.sweep(&[Quality::MapSize], &[&[512], &[1024], &[2048]]);

const SHADER: &str = "methods/msm_soft.wgsl";

/// `MsmSoftParams` of `shaders/methods/msm_soft.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MsmSoftParams {
    /// The lowest caster's height above the light's plane ([`lowest_caster`]).
    pub lowest_caster: f32,
    /// The moment bias α.
    pub bias: f32,
    /// The least blocker share of the search box.
    pub least_blocker: f32,
    pub _pad0: u32,
}

impl MsmSoftParams {
    pub fn new(f: &FrameInputs<'_>) -> MsmSoftParams {
        MsmSoftParams {
            lowest_caster: lowest_caster(f.scene),
            bias: f.knobs.get(&BIAS),
            least_blocker: f.knobs.get(&LEAST_BLOCKER),
            _pad0: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Knobs;

    /// The table is `msm`'s, quantized the same: Peters & Klein's α = 3·10⁻⁵ for 16 bits a
    /// moment.
    #[test]
    fn the_moment_bias_is_the_papers_for_16_bit_moments() {
        let bias = Knobs::default().get(&BIAS);
        assert!((bias - 3e-5).abs() < 1e-9, "{bias}");
    }
}
