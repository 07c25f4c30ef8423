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

use super::Cost;
use super::{AdapterNeeds, Quality, SHADOW_MAP};
use glam::{Mat4, Vec3};
use wgpu::DownlevelFlags as D;

use super::{require, CameraGroup, Knob, MethodSpec, MethodState, Prepare};
use crate::render::passes::sample_maps::{lights_at, SampleMaps};
use crate::render::passes::shadow_map::{BIAS_CONSTANT, BIAS_SLOPE};
use crate::render::passes::ssm::{Ssm, SsmSample, MAX_SSM_SAMPLES};
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

pub static LINEAR_SSM: MethodSpec =
    MethodSpec::new("linear-ssm", SHADER, |ctx| Box::new(LinearSsm::new(ctx)))
        .adapter(NEEDS)
        .about("soft shadow maps for a linear light (Heidrich et al. 2000)")
        .knobs(&[&SAMPLES])
        .lights(&[LightKind::Line]) // Heidrich et al.'s maps along a segment
        .bench("linear-ssm 2", &[(&SAMPLES, 2)])
        .line_samples(|line, knobs| sample_points(line, knobs.get(&SAMPLES)))
        .cost(Cost::counted("sample maps read"))
        .sweep(&[Quality::Knob(&SAMPLES)], &[&[2], &[4], &[8], &[16]]);

/// What it needs of the adapter: the sample maps and the skins found by compute passes (six storage buffers in
/// the size-extract pipeline's compute stage).
const NEEDS: AdapterNeeds = AdapterNeeds {
    formats: &SHADOW_MAP,
    downlevel: D::COMPUTE_SHADERS,
    storage_buffers_per_stage: 6,
    ..AdapterNeeds::NONE
};

const SHADER: &str = "methods/linear_ssm.wgsl";

const NOT_MADE: &str = "the linear-ssm maps were not made";

/// The `n` samples: `a + k/(n − 1) · (b − a)`, `k = 0 … n − 1` (both ends, evenly spaced).
pub fn sample_points(line: &LineLight, n: u32) -> Vec<Vec3> {
    let n = n.clamp(2, MAX_SSM_SAMPLES);
    (0..n).map(|k| line.at(k as f32 / (n - 1) as f32)).collect()
}

pub struct LinearSsm {
    /// Bound for the generations of the maps and the channels ([`Bound`]).
    camera: CameraGroup,
    maps: SampleMaps,
    ssm: Ssm,
    /// What the maps and channels hold.
    made_for: Option<Made>,
}

/// What the maps and channels were made for.
#[derive(Clone, Copy, PartialEq)]
struct Made {
    revision: u64,
    map_size: u32,
    samples: u32,
}

/// What the camera bind group binds: the maps' and the channels' generations.
#[derive(PartialEq)]
struct Bound {
    maps: u64,
    channels: u64,
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
            camera: CameraGroup::new(ctx, SHADER, &entries),
            maps: SampleMaps::new(ctx),
            ssm: Ssm::new(ctx),
            made_for: None,
        }
    }

    /// The skins and channels (tests read them back).
    pub fn ssm(&self) -> &Ssm {
        &self.ssm
    }
}

impl MethodState for LinearSsm {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, _, rec) = p;
        let Some(line) = inputs.scene.light.as_line() else {
            return Err(RenderError::Request(format!(
                "method '{}' needs a line light, and this scene's light is a disk",
                LINEAR_SSM.name
            )));
        };
        let n = inputs.knobs.get(&SAMPLES).clamp(2, MAX_SSM_SAMPLES);
        let key = Made {
            revision: inputs.revision,
            map_size: inputs.map_size,
            samples: n,
        };
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
            let maps = require(self.maps.targets(), NOT_MADE)?;
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
        let maps = require(self.maps.targets(), NOT_MADE)?;
        let channels = require(self.ssm.targets(), NOT_MADE)?;
        let bound = Bound {
            maps: maps.generation,
            channels: channels.generation,
        };
        self.camera.bind(
            &inputs.ctx.device,
            bound,
            &[
                buffer_entry(0, &self.maps.uniforms),
                view_entry(1, &maps.array_view),
                view_entry(2, &channels.array_view),
            ],
        );
        Ok(&self.camera)
    }

    fn invalidate(&mut self) {
        self.made_for = None;
    }
}
