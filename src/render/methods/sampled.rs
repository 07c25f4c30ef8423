//! `sampled`: N shadow maps from N stratified points on the light (the disk, or a line light's
//! segment), averaged (light-source sampling, Heckbert & Herf 1997): the brute-force area light (maps from `passes::sample_maps`, camera pass
//! `shaders/methods/sampled.wgsl`).

use super::Cost;
use glam::Vec3;

use super::{require, CameraGroup, Knob, Knobs, MethodSpec, MethodState, Prepare, Quality};
use crate::render::passes::sample_maps::{sample_lights, SampleMaps, MAX_LIGHTS};
use crate::render::passes::shadow_map::{BIAS_CONSTANT, BIAS_SLOPE};
use crate::render::{
    buffer_entry, texture_entry, uniform_entry, view_entry, GpuContext, RenderError,
};
use crate::scene::LineLight;

/// How many point lights.
pub static LIGHTS: Knob = Knob::int(
    "lights",
    "sampled: shadow maps from this many stratified points on the light (disk or segment)",
    1..=MAX_LIGHTS,
    16,
);

pub static SAMPLED: MethodSpec =
    MethodSpec::new("sampled", SHADER, |ctx| Box::new(Sampled::new(ctx)))
        .adapter(super::SHADOW_MAPPED)
        .about("N shadow maps from points on the light, averaged")
        .knobs(&[&LIGHTS])
        .bench("sampled 16", &[(&LIGHTS, 16)])
        .line_samples(stratum_centres)
        .cost(Cost::counted("sample maps read"))
        .sweep(
            &[Quality::Knob(&LIGHTS)],
            &[&[4], &[8], &[16], &[32], &[64]],
        );

const SHADER: &str = "methods/sampled.wgsl";

/// The points on a line light the lab draws for this method: the centres of its `n` strata.
fn stratum_centres(line: &LineLight, knobs: &Knobs) -> Vec<Vec3> {
    let n = knobs.get(&LIGHTS).max(1);
    (0..n)
        .map(|i| line.at((i as f32 + 0.5) / n as f32))
        .collect()
}

pub struct Sampled {
    /// Bound for the maps' generation.
    camera: CameraGroup,
    maps: SampleMaps,
    /// What the maps hold.
    made_for: Option<Made>,
}

/// What the maps were made for.
#[derive(Clone, Copy, PartialEq)]
struct Made {
    revision: u64,
    map_size: u32,
    lights: u32,
}

impl Sampled {
    pub fn new(ctx: &GpuContext) -> Sampled {
        let entries = [
            uniform_entry(0, wgpu::ShaderStages::FRAGMENT),
            texture_entry(
                1,
                wgpu::ShaderStages::FRAGMENT,
                wgpu::TextureViewDimension::D2Array,
            ),
        ];
        Sampled {
            camera: CameraGroup::new(ctx, SHADER, &entries),
            maps: SampleMaps::new(ctx),
            made_for: None,
        }
    }
}

impl MethodState for Sampled {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, _, rec) = p;
        let n = inputs.knobs.get(&LIGHTS);
        let key = Made {
            revision: inputs.revision,
            map_size: inputs.map_size,
            lights: n,
        };
        if self.made_for != Some(key) {
            let lights = sample_lights(
                &inputs.scene.light,
                inputs.light_view,
                n,
                inputs.map_size,
                (BIAS_CONSTANT, BIAS_SLOPE),
            );
            self.maps.record(inputs.ctx, rec, inputs.surfaces, &lights);
            self.made_for = Some(key);
        }
        let t = require(self.maps.targets(), "the sampled maps were not made")?;
        self.camera.bind(
            &inputs.ctx.device,
            t.generation,
            &[
                buffer_entry(0, &self.maps.uniforms),
                view_entry(1, &t.array_view),
            ],
        );
        Ok(&self.camera)
    }

    fn invalidate(&mut self) {
        self.made_for = None;
    }
}
