//! `sampled`: N shadow maps from N stratified points on the light (the disk, or a line light's
//! segment), averaged (light-source sampling, Heckbert & Herf 1997): the brute-force area light (maps from `passes::sample_maps`, camera pass
//! `shaders/methods/sampled.wgsl`).

use std::sync::Arc;

use glam::Vec3;

use super::{
    Bench, CameraBindings, FrameInputs, Knob, Knobs, MethodPipeline, MethodSpec, MethodState,
    SharedMaps,
};
use crate::geometry::VtVariant;
use crate::render::passes::sample_maps::{sample_lights, SampleMaps, MAX_LIGHTS};
use crate::render::passes::shadow_map::{BIAS_CONSTANT, BIAS_SLOPE};
use crate::render::timer::Recorder;
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

pub static SAMPLED: MethodSpec = MethodSpec {
    name: "sampled",
    description: "N shadow maps from points on the light, averaged",
    shader: SHADER,
    knobs: &[&LIGHTS],
    cpu_side: false,
    hard: false,
    lights: None,
    adapter: super::needs::SAMPLED,
    bench: Bench {
        label: Some("sampled 16"),
        knobs: &[(&LIGHTS, 16)],
    },
    overlay_note: None,
    line_samples: Some(stratum_centres),
    new: |ctx| Box::new(Sampled::new(ctx)),
};

const SHADER: &str = "methods/sampled.wgsl";

/// The points on a line light the lab draws for this method: the centres of its `n` strata.
fn stratum_centres(line: &LineLight, knobs: &Knobs) -> Vec<Vec3> {
    let n = knobs.get(&LIGHTS).max(1);
    (0..n)
        .map(|i| line.at((i as f32 + 0.5) / n as f32))
        .collect()
}

pub struct Sampled {
    pipeline: Arc<MethodPipeline>,
    maps: SampleMaps,
    /// The revision, size and light count the maps hold.
    made_for: Option<(u64, u32, u32)>,
    /// The bind group and the maps' generation it binds.
    bind_group: Option<(wgpu::BindGroup, u64)>,
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
            pipeline: MethodPipeline::get(ctx, SHADER, &entries),
            maps: SampleMaps::new(ctx),
            made_for: None,
            bind_group: None,
        }
    }
}

impl MethodState for Sampled {
    fn prepare(
        &mut self,
        inputs: &FrameInputs<'_>,
        _shared: &mut SharedMaps,
        rec: &mut Recorder<'_>,
    ) -> Result<(), RenderError> {
        let n = inputs.knobs.get(&LIGHTS);
        let key = (inputs.revision, inputs.map_size, n);
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
        let Some(t) = self.maps.targets() else {
            return Err(RenderError::Gpu("the sampled maps were not made".into()));
        };
        if self
            .bind_group
            .as_ref()
            .is_none_or(|(_, g)| *g != t.generation)
        {
            let group = inputs
                .ctx
                .device
                .create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("Sampled::bind_group"),
                    layout: &self.pipeline.layout,
                    entries: &[
                        buffer_entry(0, &self.maps.uniforms),
                        view_entry(1, &t.array_view),
                    ],
                });
            self.bind_group = Some((group, t.generation));
        }
        Ok(())
    }

    fn camera(&self, device: &wgpu::Device, vt: VtVariant) -> Option<CameraBindings<'_>> {
        self.bind_group.as_ref().map(|(g, _)| CameraBindings {
            pipeline: self.pipeline.pipeline(device, vt),
            bind_group: g,
        })
    }

    fn invalidate(&mut self) {
        self.made_for = None;
    }
}
