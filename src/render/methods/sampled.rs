//! `sampled`: N shadow maps from N stratified points on the light (the disk, or a line light's
//! segment), averaged (light-source sampling, Heckbert & Herf 1997): the brute-force area light (maps from `passes::sample_maps`, camera pass
//! `shaders/methods/sampled.wgsl`).

use super::{require, CameraGroup, Knob, MethodSpec, MethodState, Prepare};
use crate::render::passes::sample_maps::{sample_lights, SampleMaps, MAX_LIGHTS};
use crate::render::passes::shadow_map::{BIAS_CONSTANT, BIAS_SLOPE};
use crate::render::{
    buffer_entry, texture_entry, uniform_entry, view_entry, GpuContext, RenderError,
};

/// How many point lights.
pub static LIGHTS: Knob = Knob {
    name: "lights",
    help: "sampled: shadow maps from this many stratified points on the light (disk or segment)",
    min: 1,
    max: MAX_LIGHTS,
    default: 16,
    max_name: None,
};

pub static SAMPLED: MethodSpec = MethodSpec {
    name: "sampled",
    description: "N shadow maps from points on the light, averaged",
    knobs: &[&LIGHTS],
    cpu_side: false,
    hard: false,
    needs: None,
    new: |ctx| Box::new(Sampled::new(ctx)),
};

const SHADER: &str = "methods/sampled.wgsl";

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
