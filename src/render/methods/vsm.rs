//! `vsm`: variance shadow maps (Donnelly & Lauritzen 2006), the filterable baseline engines ship
//! (Filament's VSM, with `lightBleedReduction` 0.15 by default). The centre's shadow map's
//! moments box-filtered over `(2R + 1)²` texels (`passes::moments`), then per pixel the one-sided
//! Chebyshev bound (`shaders/methods/vsm.wgsl`). Where the filter sees two occluders at
//! different depths the bound is loose: light bleeds through the farther one's shadow (the
//! `leak-test` built-in); the bleeding reduction trades it for darker, narrower edges.

use super::Cost;
use wgpu::TextureFormat as F;

use super::shadow_mapped::{Bound, MapProducts, ShadowMapped};
use super::{require, AdapterNeeds, FrameInputs, Knob, MethodSpec, Quality, Scaled, SHADOW_MAP};
use crate::render::adapter::{FormatNeed, Usage};
use crate::render::passes::moments::Moments;
use crate::render::passes::shadow_map::ShadowMapTargets;
use crate::render::timer::Recorder;
use crate::render::{texture_entry, view_entry, RenderError};

/// The filter radius R in shadow-map texels.
pub static RADIUS: Knob = Knob::int(
    "vsm-radius",
    "vsm: moments box-filtered over (2R+1)² shadow-map texels",
    0..=32,
    3,
);

/// The light-bleeding reduction: the Chebyshev bound's share below it is cut off.
pub static BLEED: Scaled = Scaled::new(
    "vsm-bleed",
    "vsm: light-bleeding reduction in 1/100 (Filament's default 15): bounds below it read 0, the rest rescaled",
    0..=95,
    15,
    100,
);

pub static VSM: MethodSpec = MethodSpec::new("vsm", SHADER, |ctx| {
    Box::new(ShadowMapped::new(
        ctx,
        SHADER,
        Moments::new(ctx),
        VsmParams::new,
    ))
})
.adapter(NEEDS)
.about("variance shadow maps (Donnelly & Lauritzen 2006), filtered, with light-bleeding reduction")
.knobs(&[&RADIUS, &BLEED.0])
.hard()
.cost(Cost::counted("moment texels").constant("one filtered moment texel"))
.sweep(&[Quality::Knob(&RADIUS)], &[&[1], &[3], &[6], &[12]]);

const SHADER: &str = "methods/vsm.wgsl";

/// The shadow map, and the moments it renders to.
const NEEDS: AdapterNeeds = AdapterNeeds::formats(&[
    SHADOW_MAP[0],
    SHADOW_MAP[1],
    FormatNeed::new(Usage::Render, &[F::Rg32Float]),
]);

/// The least variance, relative to the receiver's squared distance: keeps the bound finite on a
/// flat receiver (its own moments have no spread) without visible softening.
pub const MIN_VARIANCE: f32 = 1e-6;

/// `VsmParams` of `shaders/methods/vsm.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VsmParams {
    /// The light-bleeding reduction (0..1).
    pub bleed: f32,
    /// The least variance, relative to `|cx|²` ([`MIN_VARIANCE`]).
    pub min_variance: f32,
    pub _pad0: u32,
    pub _pad1: u32,
}

impl VsmParams {
    pub fn new(f: &FrameInputs<'_>) -> VsmParams {
        VsmParams {
            bleed: f.knobs.get(&BLEED),
            min_variance: MIN_VARIANCE,
            ..VsmParams::default()
        }
    }
}

/// The moments, made for a filter radius, bound at 3.
impl MapProducts for Moments {
    type Key = u32;

    fn layout(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        vec![texture_entry(
            3,
            wgpu::ShaderStages::FRAGMENT,
            wgpu::TextureViewDimension::D2,
        )]
    }

    fn key(&self, inputs: &FrameInputs<'_>) -> u32 {
        inputs.knobs.get(&RADIUS)
    }

    fn record(
        &mut self,
        inputs: &FrameInputs<'_>,
        rec: &mut Recorder<'_>,
        map: &ShadowMapTargets,
        radius: u32,
    ) {
        Moments::record(
            self,
            inputs.ctx,
            rec,
            &map.distance.view,
            map.size,
            radius,
            inputs.light_view.far,
        );
    }

    fn entries(&mut self, _: &FrameInputs<'_>) -> Result<Bound<'_>, RenderError> {
        let moments = require(self.targets(), "the variance shadow map was not made")?;
        Ok(Bound {
            generations: vec![moments.generation],
            entries: vec![view_entry(3, &moments.moments.view)],
        })
    }
}
