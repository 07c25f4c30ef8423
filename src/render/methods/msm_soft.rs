//! `msm-soft`: moment soft shadow mapping (Peters, Münstermann, Wetzstein & Klein, I3D 2016;
//! JCGT 2017), sized by the disk as `pcss` is, on `msm`'s summed-area table of four moments: the
//! blocker search is one box of the table, whose moments give the share of it in front of the
//! receiver and that share's mean depth; the penumbra that depth predicts sizes a second box,
//! whose moments give V (`shaders/methods/msm_soft.wgsl`). No per-tap loop. Under a rectangle
//! or polygon it is sized by the disk of the same area, as `pcss` is.

use super::msm::{MomentMapped, NEEDS};
use super::Cost;
use super::{FrameInputs, MethodSpec, Quality, Scaled};

/// The moment bias α, in millionths: `msm`'s, on the same table.
pub static BIAS: Scaled = Scaled::new(
    "msm-soft-bias",
    "msm-soft: moment bias in 1/1,000,000 (Peters & Klein's 30 for 16 bits a moment)",
    1..=5000,
    30,
    1_000_000,
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
    Box::new(MomentMapped::new(ctx, SHADER, msm_soft_knobs))
})
.adapter(NEEDS)
.about("moment soft shadow mapping (Peters et al. 2016): blocker search and filter from moments")
.knobs(&[&BIAS.0, &LEAST_BLOCKER.0])
.lights(super::AREA_LIGHTS)
.cost(Cost::counted("summed-area table reads"))
.sweep(&[Quality::MapSize], &[&[512], &[1024], &[2048]]);

const SHADER: &str = "methods/msm_soft.wgsl";

fn msm_soft_knobs(f: &FrameInputs<'_>) -> [f32; 4] {
    [
        super::pcss::lowest_caster(f.scene),
        f.knobs.get(&BIAS),
        f.knobs.get(&LEAST_BLOCKER),
        0.0,
    ]
}
