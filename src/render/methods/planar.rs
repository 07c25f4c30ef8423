//! `planar`: planar projected shadows (Blinn 1988, "Me and my (fake) shadow"). Every flat object
//! of the scene is a receiver plane (`geometry::planar::planar_receivers`, at most eight); the
//! casters are flattened onto each plane from the light's centre by one matrix and drawn over
//! that receiver's pixels, a stencil keeping each pixel from being darkened twice
//! (`passes::planar`, after the screen prepass of `passes::stencil_volumes`).
//!
//! Its limits are the method and are not hidden: only planar receivers get shadows (no shadow on
//! the casters themselves or on any curved object), a caster poking through a receiver casts a
//! false shadow on it from below, and a receiver's plane is infinite for the projection (the
//! stencil alone keeps the shadow on the receiver's own pixels). `--planar-opacity` below 100
//! darkens instead of blacking out, which shows the stencil at work: where projected triangles
//! overlap the pixel is still darkened once.

use super::{AdapterNeeds, STENCIL_VOLUMES};
use crate::render::adapter::{FormatNeed, Usage};
use std::sync::Arc;
use wgpu::TextureFormat as F;

use super::{
    require, v_texture_entries, CameraGroup, FrameInputs, MethodSpec, MethodState, Prepare, Scaled,
};
use crate::geometry::planar::{planar_receivers, PlanarReceiver};
use crate::render::gpu_scene::VertexChunks;
use crate::render::passes::planar::{Planar, PlanarUniforms, ReceiverDraws};
use crate::render::passes::stencil_volumes::ScreenPass;
use crate::render::{view_entry, GpuContext, RenderError};

/// How much light a projected shadow takes, in percent.
pub static OPACITY: Scaled = Scaled::new(
    "planar-opacity",
    "planar: the light a projected shadow takes, percent (100: all); below 100 shows that \
     the stencil darkens each pixel once where projected triangles overlap",
    0..=100,
    100,
    100,
);

pub static PLANAR: MethodSpec =
    MethodSpec::new("planar", SHADER, |ctx| Box::new(PlanarShadows::new(ctx)))
        .adapter(NEEDS)
        .about("planar projected shadows (Blinn 1988) onto the flat receivers, stencilled")
        .knobs(&[&OPACITY.0])
        .hard()
        .overlay_note("planar: shadows on flat objects only, no volumes")
        .cost(super::SCREEN_COST)
        .fixed_quality("projected hard shadows, exact on their planes: nothing to trade");

/// What it needs of the adapter: the stencil volumes and a half-float shade it blends.
const NEEDS: AdapterNeeds = AdapterNeeds::formats(&[
    STENCIL_VOLUMES[0],
    STENCIL_VOLUMES[1],
    STENCIL_VOLUMES[2],
    STENCIL_VOLUMES[3],
    FormatNeed::new(Usage::Blend, &[F::R16Float]),
]);

const SHADER: &str = "methods/planar.wgsl";

pub struct PlanarShadows {
    screen: ScreenPass,
    planar: Planar,
    /// Bound for the generation of the screen targets.
    camera: CameraGroup,
    receivers: Vec<PlanarReceiver>,
    draws: Vec<ReceiverDraws>,
    warnings: Vec<String>,
    built_for: Option<u64>,
}

impl PlanarShadows {
    pub fn new(ctx: &GpuContext) -> PlanarShadows {
        let screen = ScreenPass::new(ctx);
        let planar = Planar::new(ctx, screen.pass.format);
        PlanarShadows {
            screen,
            planar,
            camera: CameraGroup::new(ctx, SHADER, &v_texture_entries()),
            receivers: Vec::new(),
            draws: Vec::new(),
            warnings: Vec::new(),
            built_for: None,
        }
    }

    /// The receiver planes found for the last light (the lab's notes, tests).
    pub fn receivers(&self) -> &[PlanarReceiver] {
        &self.receivers
    }

    fn build(&mut self, inputs: &FrameInputs<'_>) {
        let scene = inputs.scene;
        let device = &inputs.ctx.device;
        let (receivers, warnings) = planar_receivers(scene, scene.light.center());
        let triangles = |i: usize| -> Vec<[f32; 4]> {
            scene.objects[i]
                .mesh
                .triangle_corners()
                .flatten()
                .map(|p| p.extend(1.0).to_array())
                .collect()
        };
        let casters: Vec<(usize, Arc<VertexChunks>)> = scene
            .objects
            .iter()
            .enumerate()
            .filter(|(_, o)| o.casts_shadow)
            .map(|(i, _)| {
                (
                    i,
                    Arc::new(VertexChunks::new(device, "Planar::caster", &triangles(i))),
                )
            })
            .collect();
        self.draws = receivers
            .iter()
            .map(|r| ReceiverDraws {
                surface: VertexChunks::new(device, "Planar::receiver", &triangles(r.object)),
                // Never onto its own plane.
                casters: casters
                    .iter()
                    .filter(|(i, _)| *i != r.object)
                    .map(|(_, c)| c.clone())
                    .collect(),
            })
            .collect();
        self.receivers = receivers;
        self.warnings = warnings;
        self.built_for = Some(inputs.revision);
    }
}

impl MethodState for PlanarShadows {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, _, rec) = p;
        let ctx = inputs.ctx;
        if self.built_for != Some(inputs.revision) {
            self.build(inputs);
        }
        self.screen.begin(ctx, &inputs.view);
        let targets = require(self.screen.targets(), "the screen targets were not made")?;
        self.screen.record_prepass(rec, inputs.surfaces);
        let shadow_v = 1.0 - inputs.knobs.get(&OPACITY);
        let uniforms = PlanarUniforms::new(
            inputs.view.infinite_view_proj,
            inputs.view.eye,
            inputs.scene.light.center(),
            &self.receivers,
            shadow_v,
        );
        self.planar
            .record(ctx, rec, targets, &uniforms, &self.draws);
        let shade = require(self.planar.shade(), "the planar shadows were not drawn")?;
        self.camera.bind(
            &ctx.device,
            targets.generation,
            &[view_entry(0, &shade.view)],
        );
        Ok(&self.camera)
    }
}
