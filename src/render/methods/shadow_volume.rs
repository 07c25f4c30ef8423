//! `shadow-volume`: stencil shadow volumes from the light centre (Crow 1977; counted in the
//! stencil buffer as Heidmann 1991 did, by z-fail with both caps — Carmack's reverse, made robust
//! by Everitt and Kilgard 2002 — so the camera may stand inside a volume).
//!
//! Per light or caster move: each caster's faces classed against the centre, its volume from
//! the silhouette edges (`geometry::hard_volume`: the adjacency and silhouette rule of the
//! geometry core, no second copy), uploaded. Per frame (the volumes depend on the camera's
//! pixels): the screen prepass, the z-fail count and the resolve
//! (`passes::stencil_volumes`), then the camera pass reads V at its pixel
//! (`shaders/methods/shadow_volume.wgsl`).
//!
//! Closed casters are exact up to rasterisation. An open mesh breaks Crow's assumption (every
//! ray through the solid crosses as many faces toward the light as away from it): with
//! `--sv-open 0` it gets Crow's one-sided volumes (only faces whose front faces the light cast,
//! so a sheet turned away from the light casts nothing and a hole facing the light leaks), with
//! `--sv-open 1` (the default) the two-sided count, exact for any triangle soup at about twice
//! the fill.

pub use super::screen_volumes::OPEN;
use super::screen_volumes::{Counted, OnVolumes, ScreenVolumes};
use super::{require, v_texture_entries, AdapterNeeds, CameraGroup, MethodSpec, STENCIL_VOLUMES};
use crate::render::passes::stencil_volumes::ScreenPass;
use crate::render::{view_entry, RenderError};

pub static SHADOW_VOLUME: MethodSpec = MethodSpec::new("shadow-volume", SHADER, |ctx| {
    Box::new(ScreenVolumes::new(
        ScreenPass::new(ctx),
        ShadowVolume {
            camera: CameraGroup::new(ctx, SHADER, &v_texture_entries()),
        },
    ))
})
.adapter(NEEDS)
.about("stencil shadow volumes from the light centre (Crow 1977), z-fail with caps")
.knobs(&[&OPEN.0])
.hard()
.overlay_note("shadow-volume: from the light centre; umbra volume = Crow's")
.cost(super::SCREEN_COST)
.fixed_quality("the exact hard shadow from the light's centre: nothing to trade");

/// What it needs of the adapter: the stencil volumes.
const NEEDS: AdapterNeeds = AdapterNeeds::formats(&STENCIL_VOLUMES);

const SHADER: &str = "methods/shadow_volume.wgsl";

/// Its part of the screen-space volumes: the camera reads the visibility the resolve wrote.
pub struct ShadowVolume {
    /// Bound for the generation of the screen targets.
    camera: CameraGroup,
}

impl OnVolumes for ShadowVolume {
    const LABEL: &'static str = "ShadowVolume::volumes";

    fn record(&mut self, c: Counted<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Counted(inputs, rec, screen, generation) = c;
        screen.record_resolve(rec);
        let targets = require(screen.targets(), "the screen targets were not made")?;
        let entries = [view_entry(0, &targets.visibility.view)];
        self.camera.bind(&inputs.ctx.device, generation, &entries);
        Ok(&self.camera)
    }
}
