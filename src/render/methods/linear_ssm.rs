//! `linear-ssm`: soft shadow maps for linear lights (Heidrich, Brabec & Seidel 2000).
//!
//! N samples on the segment, its two ends included (`--ssm-samples`, the paper's 2 by default):
//! each is a point light with a distance map (the `sampled` maps pass, at these points) and a
//! visibility channel per neighbouring pair, built from the skins of the neighbour's map
//! ([`crate::render::passes::ssm`]). The camera pass (`shaders/methods/linear_ssm.wgsl`) adds
//! the channels of every sample that sees the point. Each pair of neighbours is a linear light of
//! its own, `1/(N − 1)` of the whole (Heidrich et al. 2000, §3.3); the two channels of an inner sample are the
//! paper's "two point lights merged, their visibility channels summed".
//!
//! What the paper admits, and what shows here: a point seen by no sample is in umbra even where
//! it sees part of the light between them (`line-fig6-gap`), points seen by both ends of a pair
//! are taken as fully lit (`line-bar`), overlapping penumbrae are undersampled with two samples
//! (`line-fig8-overlap`), and the transition is linear in the image where the truth is rational
//! (`line-fig3-tilted`).

use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::{
    Bench, CameraBindings, FrameInputs, Knob, MethodPipeline, MethodSpec, MethodState, SharedMaps,
};
use crate::geometry::VtVariant;
use crate::render::passes::sample_maps::{lights_at, SampleMaps};
use crate::render::passes::shadow_map::{BIAS_CONSTANT, BIAS_SLOPE};
use crate::render::passes::ssm::{Ssm, SsmSample, MAX_SSM_SAMPLES};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, texture_entry, uniform_entry, view_entry, GpuContext, RenderError,
};
use crate::scene::{LightKind, LineLight};

/// N, the samples on the segment.
pub static SAMPLES: Knob = Knob::int(
    "ssm-samples",
    "linear-ssm: light samples on the segment, its ends included (the paper's 2)",
    2..=MAX_SSM_SAMPLES,
    2,
);

pub static LINEAR_SSM: MethodSpec = MethodSpec {
    name: "linear-ssm",
    description: "soft shadow maps for a linear light (Heidrich et al. 2000)",
    shader: SHADER,
    knobs: &[&SAMPLES],
    cpu_side: false,
    hard: false,
    lights: Some(LightKind::Line), // Heidrich et al.'s maps along a segment
    adapter: super::needs::LINEAR_SSM,
    bench: Bench {
        label: Some("linear-ssm 2"),
        knobs: &[(&SAMPLES, 2)],
    },
    overlay_note: None,
    line_samples: Some(|line, knobs| sample_points(line, knobs.get(&SAMPLES))),
    new: |ctx| Box::new(LinearSsm::new(ctx)),
};

const SHADER: &str = "methods/linear_ssm.wgsl";

/// The `n` samples: `a + k/(n − 1) · (b − a)`, `k = 0 … n − 1` (both ends, evenly spaced).
pub fn sample_points(line: &LineLight, n: u32) -> Vec<Vec3> {
    let n = n.clamp(2, MAX_SSM_SAMPLES);
    (0..n).map(|k| line.at(k as f32 / (n - 1) as f32)).collect()
}

pub struct LinearSsm {
    pipeline: Arc<MethodPipeline>,
    maps: SampleMaps,
    ssm: Ssm,
    /// The revision, size and sample count the maps and channels hold.
    made_for: Option<(u64, u32, u32)>,
    /// The bind group and the generations (maps, channels) it binds.
    bind_group: Option<(wgpu::BindGroup, u64, u64)>,
}

impl LinearSsm {
    pub fn new(ctx: &GpuContext) -> LinearSsm {
        let array = || wgpu::TextureViewDimension::D2Array;
        let entries = [
            uniform_entry(0, wgpu::ShaderStages::FRAGMENT),
            texture_entry(1, wgpu::ShaderStages::FRAGMENT, array()),
            texture_entry(2, wgpu::ShaderStages::FRAGMENT, array()),
        ];
        LinearSsm {
            pipeline: MethodPipeline::get(ctx, SHADER, &entries),
            maps: SampleMaps::new(ctx),
            ssm: Ssm::new(ctx),
            made_for: None,
            bind_group: None,
        }
    }

    /// The skins and channels (tests read them back).
    pub fn ssm(&self) -> &Ssm {
        &self.ssm
    }
}

impl MethodState for LinearSsm {
    fn prepare(
        &mut self,
        inputs: &FrameInputs<'_>,
        _shared: &mut SharedMaps,
        rec: &mut Recorder<'_>,
    ) -> Result<(), RenderError> {
        let Some(line) = inputs.scene.light.as_line() else {
            return Err(RenderError::Request(format!(
                "method '{}' needs a line light, and this scene's light is a disk",
                LINEAR_SSM.name
            )));
        };
        let n = inputs.knobs.get(&SAMPLES).clamp(2, MAX_SSM_SAMPLES);
        let key = (inputs.revision, inputs.map_size, n);
        if self.made_for != Some(key) {
            let view = inputs.light_view;
            let points = sample_points(line, n);
            let lights = lights_at(
                inputs.scene.light.center(),
                &points,
                view,
                inputs.map_size,
                (BIAS_CONSTANT, BIAS_SLOPE),
            );
            self.maps.record(inputs.ctx, rec, inputs.surfaces, &lights);
            let Some(maps) = self.maps.targets() else {
                return Err(RenderError::Gpu("the linear-ssm maps were not made".into()));
            };
            let samples: Vec<SsmSample> = lights.lights[..n as usize]
                .iter()
                .enumerate()
                .map(|(k, l)| {
                    SsmSample::new(
                        Mat4::from_cols_array_2d(&l.view_proj),
                        Vec3::from(l.point),
                        k as u32,
                        n,
                        inputs.map_size,
                        view.far,
                    )
                })
                .collect();
            self.ssm.record(
                inputs.ctx,
                rec,
                (&maps.texture, &maps.array_view, maps.generation),
                &samples,
            )?;
            self.made_for = Some(key);
        }
        let (Some(maps), Some(channels)) = (self.maps.targets(), self.ssm.targets()) else {
            return Err(RenderError::Gpu("the linear-ssm maps were not made".into()));
        };
        if self
            .bind_group
            .as_ref()
            .is_none_or(|(_, m, c)| (*m, *c) != (maps.generation, channels.generation))
        {
            let group = inputs
                .ctx
                .device
                .create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("LinearSsm::bind_group"),
                    layout: &self.pipeline.layout,
                    entries: &[
                        buffer_entry(0, &self.maps.uniforms),
                        view_entry(1, &maps.array_view),
                        view_entry(2, &channels.array_view),
                    ],
                });
            self.bind_group = Some((group, maps.generation, channels.generation));
        }
        Ok(())
    }

    fn camera(&self, device: &wgpu::Device, vt: VtVariant) -> Option<CameraBindings<'_>> {
        self.bind_group.as_ref().map(|(g, _, _)| CameraBindings {
            pipeline: self.pipeline.pipeline(device, vt),
            bind_group: g,
        })
    }

    fn invalidate(&mut self) {
        self.made_for = None;
    }
}
