//! `vsm`: variance shadow maps (Donnelly & Lauritzen 2006), the filterable baseline engines ship
//! (Filament's VSM, with `lightBleedReduction` 0.15 by default). The centre's shadow map's
//! moments box-filtered over `(2R + 1)²` texels (`passes::moments`), then per pixel the one-sided
//! Chebyshev bound (`shaders/methods/vsm.wgsl`). Where the filter sees two occluders at
//! different depths the bound is loose: light bleeds through the farther one's shadow (the
//! `leak-test` built-in); the bleeding reduction trades it for darker, narrower edges.

use super::Cost;
use wgpu::TextureFormat as F;

use super::{
    require, AdapterNeeds, CameraGroup, FrameInputs, Knob, LightMaps, MethodSpec, MethodState,
    Prepare, Quality, Scaled, SharedMaps, SHADOW_MAP,
};
use crate::render::adapter::{FormatNeed, Usage};
use crate::render::passes::moments::Moments;
use crate::render::passes::shadow_map::{lookup_entries, ShadowUniforms};
use crate::render::{
    buffer_entry, texture_entry, uniform_buffer, view_entry, GpuContext, RenderError,
};

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

pub static VSM: MethodSpec = MethodSpec::new("vsm", SHADER, |ctx| Box::new(Vsm::new(ctx)))
    .adapter(NEEDS)
    .about(
        "variance shadow maps (Donnelly & Lauritzen 2006), filtered, with light-bleeding reduction",
    )
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

/// What the moments were made from.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Made {
    revision: u64,
    radius: u32,
    map: u64,
}

pub struct Vsm {
    moments: Moments,
    camera: CameraGroup,
    uniforms: wgpu::Buffer,
    made: Option<Made>,
}

impl Vsm {
    pub fn new(ctx: &GpuContext) -> Vsm {
        let mut entries = lookup_entries().to_vec();
        entries.push(texture_entry(
            2,
            wgpu::ShaderStages::FRAGMENT,
            wgpu::TextureViewDimension::D2,
        ));
        Vsm {
            moments: Moments::new(ctx),
            camera: CameraGroup::new(ctx, SHADER, &entries),
            uniforms: uniform_buffer::<ShadowUniforms>(&ctx.device, "Vsm::uniforms"),
            made: None,
        }
    }
}

fn vsm_knobs(f: &FrameInputs<'_>) -> [f32; 4] {
    [f.knobs.get(&BLEED), MIN_VARIANCE, 0.0, 0.0]
}

impl MethodState for Vsm {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        let ctx = inputs.ctx;
        let map = shared.shadow_map.update(inputs, rec)?;
        let made = Made {
            revision: inputs.revision,
            radius: inputs.knobs.get(&RADIUS),
            map: map.generation,
        };
        if self.made != Some(made) {
            self.moments.record(
                ctx,
                rec,
                &map.distance.view,
                map.size,
                made.radius,
                inputs.light_view.far,
            );
            self.made = Some(made);
        }
        let moments = require(
            self.moments.targets(),
            "the variance shadow map was not made",
        )?;
        let uniforms = ShadowUniforms::new(inputs.light_view, map.size, vsm_knobs(inputs));
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        let entries = [
            buffer_entry(0, &self.uniforms),
            view_entry(1, &map.distance.view),
            view_entry(2, &moments.moments.view),
        ];
        self.camera
            .bind(&ctx.device, (map.generation, moments.generation), &entries);
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        shared.shadow_map.light_maps()
    }

    fn invalidate(&mut self) {
        self.made = None;
    }
}
