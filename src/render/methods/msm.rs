//! `msm`: moment shadow maps (Peters & Klein, I3D 2015), filtered: the centre's shadow map as
//! four quantization-optimized moments a texel in a summed-area table (`passes::moment_sat`), a
//! `(2R + 1)²` box of it per pixel, and Hamburger 4MSM at the receiver's depth
//! (`shaders/methods/msm.wgsl`; the arithmetic's CPU twin: `geometry::moments`). Where the box
//! holds at most two depths the moments determine them and the test is exact; with more it is a
//! bound, and light leaks — less than the variance shadow map's (`leak-test`). The state here is
//! `msm-soft`'s too.

use super::Cost;
use super::{
    require, AdapterNeeds, CameraGroup, FrameInputs, Knob, LightMaps, MethodSpec, MethodState,
    Prepare, Quality, Scaled, SharedMaps, SHADOW_MAP,
};
use crate::render::passes::moment_sat::MomentSat;
use crate::render::passes::shadow_map::{lookup_entries, MapFrame, ShadowUniforms};
use crate::render::storage_entry;
use crate::render::{buffer_entry, uniform_buffer, view_entry, GpuContext, RenderError};

/// The filter's half-width R in shadow-map texels.
pub static RADIUS: Knob = Knob::int(
    "msm-radius",
    "msm: moments averaged over (2R+1)² shadow-map texels",
    0..=32,
    3,
);

/// The moment bias α, in millionths: Peters & Klein's 3·10⁻⁵ for moments quantized to 16 bits
/// each (64 bits a texel), as the table's fixed point holds them.
pub static BIAS: Scaled = Scaled::new(
    "msm-bias",
    "msm: moment bias in 1/1,000,000 (Peters & Klein's 30 for 16 bits a moment): larger leaks more, smaller breaks up",
    1..=5000,
    30,
    1_000_000,
);

pub static MSM: MethodSpec = MethodSpec::new("msm", SHADER, |ctx| {
    Box::new(MomentMapped::new(ctx, SHADER, msm_knobs))
})
.adapter(NEEDS)
.about("moment shadow maps (Peters & Klein 2015), four moments, filtered")
.knobs(&[&RADIUS, &BIAS.0])
.hard()
.cost(Cost::counted("summed-area table reads").constant("two boxes of four corners"))
.sweep(&[Quality::Knob(&RADIUS)], &[&[1], &[3], &[6], &[12]]);

const SHADER: &str = "methods/msm.wgsl";

/// The shadow map; the table built by compute and read in fragment shaders (2 storage buffers).
pub const NEEDS: AdapterNeeds = AdapterNeeds {
    formats: &SHADOW_MAP,
    downlevel: wgpu::DownlevelFlags::COMPUTE_SHADERS.union(wgpu::DownlevelFlags::FRAGMENT_STORAGE),
    storage_buffers_per_stage: 2,
    ..AdapterNeeds::NONE
};

fn msm_knobs(f: &FrameInputs<'_>) -> [f32; 4] {
    [f.knobs.get(&RADIUS) as f32, f.knobs.get(&BIAS), 0.0, 0.0]
}

/// What the table was made from.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Made {
    revision: u64,
    map: u64,
}

/// A method drawn from the moment table: `msm`'s and `msm-soft`'s state, told apart by their
/// shader and the numbers they hand it (`ShadowUniforms::knobs`).
pub struct MomentMapped {
    sat: MomentSat,
    camera: CameraGroup,
    uniforms: wgpu::Buffer,
    knobs: fn(&FrameInputs<'_>) -> [f32; 4],
    made: Option<Made>,
}

impl MomentMapped {
    pub fn new(
        ctx: &GpuContext,
        shader: &'static str,
        knobs: fn(&FrameInputs<'_>) -> [f32; 4],
    ) -> MomentMapped {
        let mut entries = lookup_entries().to_vec();
        entries.push(storage_entry(2, wgpu::ShaderStages::FRAGMENT, true));
        entries.push(storage_entry(3, wgpu::ShaderStages::FRAGMENT, true));
        MomentMapped {
            sat: MomentSat::new(ctx),
            camera: CameraGroup::new(ctx, shader, &entries),
            uniforms: uniform_buffer::<ShadowUniforms>(&ctx.device, "MomentMapped::uniforms"),
            knobs,
            made: None,
        }
    }
}

impl MethodState for MomentMapped {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        let ctx = inputs.ctx;
        let map = shared.shadow_map.update(inputs, rec)?;
        let made = Made {
            revision: inputs.revision,
            map: map.generation,
        };
        if self.made != Some(made) {
            let frame = MapFrame::new(inputs.light_view, &inputs.scene.light);
            self.sat
                .record(ctx, rec, &map.distance.view, map.size, &frame);
            self.made = Some(made);
        }
        let table = require(self.sat.table(), "the moment table was not made")?;
        let uniforms = ShadowUniforms::new(inputs.light_view, map.size, (self.knobs)(inputs));
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        let entries = [
            buffer_entry(0, &self.uniforms),
            view_entry(1, &map.distance.view),
            buffer_entry(2, &table.buffer),
            buffer_entry(3, &table.range),
        ];
        self.camera
            .bind(&ctx.device, (map.generation, table.generation), &entries);
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        shared.shadow_map.light_maps()
    }

    fn invalidate(&mut self) {
        self.made = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::moments::DEFAULT_MOMENT_BIAS;
    use crate::render::Knobs;

    /// Peters & Klein (I3D 2015) give α = 3·10⁻⁵ for moments quantized to 16 bits each (64 bits
    /// a texel), as the table's fixed point holds them; `msm-soft` reads the same table. Both
    /// knobs and the CPU twin say so (they said 6·10⁻⁵, twice the paper's, which leaks more).
    #[test]
    fn the_moment_bias_is_the_papers_for_16_bit_moments() {
        let k = Knobs::default();
        for (name, bias) in [
            ("msm", k.get(&BIAS)),
            ("msm-soft", k.get(&super::super::msm_soft::BIAS)),
            ("geometry::moments", DEFAULT_MOMENT_BIAS),
        ] {
            assert!((bias - 3e-5).abs() < 1e-9, "{name}: {bias}");
        }
    }
}
