//! `raytraced`: what engines with ray tracing ship for area lights — a few shadow rays per pixel
//! toward points of the light, traced against the scene's geometry, then a denoiser in the
//! manner of NVIDIA's SIGMA (`passes::raytraced`, `shaders/passes/raytraced.wgsl`): temporal
//! accumulation with reprojection and history rejection, and a spatial filter whose footprint
//! follows the penumbra's size estimated from the rays' hit distances. The rays run through the
//! scene's BVH in WGSL (`passes::trace`); the light's points come from a low-discrepancy sequence
//! scrambled per pixel that runs on from frame to frame, so a still view converges to the
//! visible fraction of the light. The camera pass reads V at its pixel
//! (`shaders/methods/raytraced.wgsl`).
//!
//! A temporal method: its image depends on the frames before it. A still `render` shows the
//! frame after [`FRAMES`] frames of history and `compare` scores both its first frame and that
//! one; the sequence is fixed by the frame's index since the history began, so two runs of the
//! same frames give the same images. docs/method/raytraced.md says what it gets wrong.

use glam::Mat4;

use super::{
    require, AdapterNeeds, CameraGroup, Cost, Knob, MethodSpec, MethodState, Prepare, Quality,
    Switch,
};
use crate::geometry::bvh::Bvh;
use crate::render::adapter::FormatNeed;
use crate::render::passes::raytraced::{RtPasses, RtSettings, RtTargets, RtUniforms};
use crate::render::passes::stencil_volumes::ScreenPass;
use crate::render::passes::trace::{Path, TraceScene};
use crate::render::{
    buffer_entry, storage_entry, uniform_buffer, uniform_entry, GpuContext, RenderError,
};

/// Shadow rays per pixel and frame.
pub static RAYS: Knob = Knob::int(
    "rt-rays",
    "raytraced: shadow rays per pixel each frame, toward points of the light",
    1..=64,
    1,
);

/// The temporal accumulation.
pub static TEMPORAL: Switch = Switch::new(
    "rt-temporal",
    "raytraced: accumulate the rays of earlier frames, reprojected (0: this frame's rays alone)",
    true,
);

/// Frames the running mean spans at most.
pub static HISTORY: Knob = Knob::int(
    "rt-history",
    "raytraced: frames the temporal running mean spans at most",
    2..=64,
    32,
);

/// The spatial filter's largest radius.
pub static RADIUS: Knob = Knob::int(
    "rt-radius",
    "raytraced: the spatial filter's largest radius in pixels (it follows the penumbra's width below that; 0: off)",
    0..=32,
    8,
);

/// The denoiser as a whole.
pub static DENOISE: Switch = Switch::new(
    "rt-denoise",
    "raytraced: denoise (0: the raw rays of the frame)",
    true,
);

/// Frames of history before the frame a still view is shown and scored with: a user standing
/// still for a quarter of a second at 60 frames a second.
pub static FRAMES: Knob = Knob::int(
    "rt-frames",
    "raytraced: frames of history before the one render shows and compare scores (15: a quarter second at 60 fps; 0: the first frame)",
    0..=256,
    15,
);

pub static RAYTRACED: MethodSpec =
    MethodSpec::new("raytraced", SHADER, |ctx| Box::new(Raytraced::new(ctx)))
        .adapter(NEEDS)
        .about("shadow rays traced on the GPU, denoised over time and space (as SIGMA does)")
        .knobs(&[&RAYS, &TEMPORAL.0, &HISTORY, &RADIUS, &DENOISE.0, &FRAMES])
        .history(&FRAMES)
        .bench("raytraced 1 ray", &[(&RAYS, 1)])
        .cost(
            Cost::counted("BVH nodes visited by the frame's rays").paths(&[
                "raw rays (the denoiser off)",
                "denoised, no spatial filter (no penumbra near)",
                "denoised, spatially filtered",
            ]),
        )
        .sweep(&[Quality::Knob(&RAYS)], &[&[1], &[2], &[4], &[8], &[16]]);

const SHADER: &str = "methods/raytraced.wgsl";

/// The screen prepass's positions and depth, compute shaders, and the passes' storage buffers.
const NEEDS: AdapterNeeds = AdapterNeeds {
    formats: &SCREEN,
    downlevel: wgpu::DownlevelFlags::COMPUTE_SHADERS,
    storage_buffers_per_stage: crate::render::passes::raytraced::STORAGE_BUFFERS,
    ..AdapterNeeds::NONE
};

/// The screen prepass's position target and its depth (`passes::stencil_volumes`).
const SCREEN: [FormatNeed; 2] = [super::STENCIL_VOLUMES[0], super::STENCIL_VOLUMES[3]];

/// `RaytracedParams` of `shaders/methods/raytraced.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RaytracedParams {
    /// 1: the denoised V; 0: the frame's raw rays.
    pub denoise: u32,
    /// The image's width in pixels.
    pub width: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// The scene's BVH on the GPU and the mesh revision it was built for.
struct SceneBvh {
    gpu: TraceScene,
    meshes: u64,
}

pub struct Raytraced {
    screen: ScreenPass,
    passes: RtPasses,
    targets: Option<RtTargets>,
    bvh: Option<SceneBvh>,
    camera: CameraGroup,
    params: wgpu::Buffer,
    /// Frames drawn since the history began (the sequence's position).
    frame: u32,
    /// The previous frame's camera, where its history may be reprojected.
    prev: Option<Mat4>,
    /// The light-or-caster revision of the previous frame.
    revision: u64,
    /// Frames in the history and the most it spans, for [`MethodState::settling`].
    settle: (u32, u32),
    generations: u64,
}

impl Raytraced {
    pub fn new(ctx: &GpuContext) -> Raytraced {
        Raytraced {
            screen: ScreenPass::new(ctx),
            passes: RtPasses::new(ctx),
            targets: None,
            bvh: None,
            camera: CameraGroup::new(ctx, SHADER, &camera_entries()),
            params: uniform_buffer::<RaytracedParams>(&ctx.device, "Raytraced::params"),
            frame: 0,
            prev: None,
            revision: 0,
            settle: (0, 0),
            generations: 0,
        }
    }
}

/// Group 1 of `methods/raytraced.wgsl`: the frame's rays, the denoised V and the parameters.
fn camera_entries() -> [wgpu::BindGroupLayoutEntry; 3] {
    use wgpu::ShaderStages as S;
    [
        storage_entry(0, S::FRAGMENT, true),
        storage_entry(1, S::FRAGMENT, true),
        uniform_entry(2, S::FRAGMENT),
    ]
}

impl MethodState for Raytraced {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, _, rec) = p;
        let ctx = inputs.ctx;
        let view = inputs.view;
        if self.bvh.as_ref().is_none_or(|b| b.meshes != inputs.meshes) {
            // Through the BVH in WGSL on every adapter: it counts the nodes a ray visits (the
            // cost view) and finds a hit's distance (the penumbra's estimate).
            let bvh = Bvh::build(inputs.scene.all_triangles());
            self.bvh = Some(SceneBvh {
                gpu: TraceScene::new(ctx, &bvh, Path::WgslBvh)?,
                meshes: inputs.meshes,
            });
        }
        let bvh = require(self.bvh.as_ref(), "the scene's BVH")?;
        if self
            .targets
            .as_ref()
            .is_none_or(|t| (t.width, t.height) != (view.width, view.height))
        {
            self.generations += 1;
            self.targets = Some(RtTargets::new(
                ctx,
                view.width,
                view.height,
                self.generations,
            )?);
            self.prev = None;
        }
        let targets = require(self.targets.as_ref(), "the raytraced buffers")?;
        self.screen.begin(ctx, &view);
        self.screen.record_prepass(rec, inputs.surfaces);
        let screen = require(self.screen.targets(), "the screen prepass's targets")?;
        let positions = (&screen.position.view, screen.generation);
        let knobs = inputs.knobs;
        let denoise = knobs.get(&DENOISE);
        let history = if knobs.get(&TEMPORAL) {
            knobs.get(&HISTORY)
        } else {
            1
        };
        if self.prev.is_none() {
            self.frame = 0;
        }
        let settings = RtSettings {
            frame: self.frame,
            rays: knobs.get(&RAYS),
            history,
            radius: knobs.get(&RADIUS) as f32,
            denoise,
            motion: self.prev.is_some() && inputs.revision != self.revision,
        };
        let uniforms = RtUniforms::new(
            &inputs.scene.light,
            &view,
            inputs.scene.camera.fov_y_deg,
            self.prev,
            &bvh.gpu,
            &settings,
        );
        self.passes.record(
            ctx,
            rec,
            &uniforms,
            (&bvh.gpu, bvh.meshes),
            positions,
            targets,
            (self.frame % 2) as usize,
            denoise,
        );
        let params = RaytracedParams {
            denoise: u32::from(denoise),
            width: view.width,
            ..RaytracedParams::default()
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        self.camera.bind(
            &ctx.device,
            targets.generation,
            &[
                buffer_entry(0, &targets.raw),
                buffer_entry(1, &targets.denoised),
                buffer_entry(2, &self.params),
            ],
        );
        // The history is written only by the denoiser's passes.
        let accumulated = if denoise && self.prev.is_some() {
            self.settle.0 + 1
        } else {
            1
        };
        self.settle = (accumulated.min(history), if denoise { history } else { 1 });
        self.prev = denoise.then_some(view.view_proj);
        self.revision = inputs.revision;
        self.frame = self.frame.wrapping_add(1);
        Ok(&self.camera)
    }

    fn reset_history(&mut self) {
        self.prev = None;
        self.frame = 0;
        self.settle = (0, 0);
    }

    fn settling(&self) -> bool {
        self.settle.0 < self.settle.1
    }
}
