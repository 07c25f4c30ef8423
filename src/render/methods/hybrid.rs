//! `hybrid`: shadow volumes reconstructed from a depth map (McCool 2000, ACM TOG 19(1)). The
//! light's hard distance map (the session's shadow map, shared with `hard`) is searched for
//! depth discontinuities (edge detection: a relative jump above `--hybrid-threshold` that neither
//! neighbour's slope predicts; `--hybrid-edges 0`: any such jump), a volume
//! boundary is rebuilt from them with marching-squares templates (`--hybrid-templates 0`: the
//! plain staircase along texel borders), and the walls are counted over the camera's pixels in
//! one stencil bit (`passes::hybrid`; CPU twin `geometry::hybrid`).
//!
//! Errors it inherits from the map and shows: its boundaries are where the map's samples say
//! (staircases or 45° cuts at texel size, thin occluders lost), and the threshold trades walls on
//! steep continuous surfaces (acne) against missed discontinuities between close surfaces (light
//! leaks). The reconstructed edges (the walls' tops) are the lab's overlay: this method's
//! [`MethodState::geometry`] holds them as silhouette edges, a frame after the walls were made.

use super::{
    require, v_texture_entries, CameraGroup, Knobs, MethodSpec, MethodState, Prepare, Scaled,
    SharedMaps, Switch,
};
use super::{AdapterNeeds, Quality};
use crate::geometry::hybrid::WallParams;
use crate::geometry::silhouette::SilhouetteEdge;
use crate::geometry::{CasterGeometry, GeometryStats, SceneGeometry, VolumeParams};
use crate::render::passes::hybrid::{Hybrid, HybridFrame, HybridUniforms};
use crate::render::passes::stencil_volumes::ScreenPass;
use crate::render::{view_entry, GpuContext, RenderError};
use wgpu::DownlevelFlags as D;

/// τ in thousandths.
pub static THRESHOLD: Scaled = Scaled::new(
    "hybrid-threshold",
    "hybrid: the relative depth jump between neighbouring texels that makes an edge, in \
     thousandths (20 = 2 %)",
    1..=500,
    20,
    1000,
);

/// Templates or the plain staircase.
pub static TEMPLATES: Switch = Switch::new(
    "hybrid-templates",
    "hybrid: 1 = marching-squares templates (straight and 45° cuts), 0 = the staircase \
     along texel borders",
    true,
);

/// The edge detector: the plain jump, or a jump neither side's slope predicts.
pub static EDGES: Switch = Switch::new(
    "hybrid-edges",
    "hybrid: 0 = every jump above the threshold is an edge, 1 = only jumps neither \
     neighbour's slope predicts (no walls on steep continuous surfaces)",
    true,
);

pub static HYBRID: MethodSpec =
    MethodSpec::new("hybrid", SHADER, |ctx| Box::new(HybridMethod::new(ctx)))
        .adapter(NEEDS)
        .about("shadow volumes rebuilt from the light's depth map (McCool 2000), one stencil bit")
        .knobs(&[&THRESHOLD.0, &TEMPLATES.0, &EDGES.0])
        .hard()
        .overlay_note("hybrid: silhouette edges = rebuilt from the depth map")
        .cost(super::SCREEN_COST)
        .sweep(&[Quality::MapSize], &[&[512], &[1024], &[2048]]);

/// What it needs of the adapter: the shadow map, the stencil volumes and its walls found by a compute pass (six
/// storage buffers in its compute stage).
const NEEDS: AdapterNeeds = AdapterNeeds {
    formats: &super::MAP_AND_SCREEN,
    downlevel: D::COMPUTE_SHADERS,
    storage_buffers_per_stage: 6,
    ..AdapterNeeds::NONE
};

const SHADER: &str = "methods/hybrid.wgsl";

/// The bias of the near cap's map lookup, relative to the distance (the hard test's order).
const LOOKUP_BIAS: f32 = 2e-3;

/// The reconstruction's parameters from the knobs; walls with nothing behind them reach `far`.
pub fn wall_params(knobs: &Knobs, far: f32) -> WallParams {
    WallParams {
        threshold: knobs.get(&THRESHOLD),
        templates: knobs.get(&TEMPLATES),
        far,
        slope_test: knobs.get(&EDGES),
    }
}

/// What the walls were made from.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Made {
    revision: u64,
    map: u64,
    params: WallParams,
}

pub struct HybridMethod {
    screen: ScreenPass,
    hybrid: Hybrid,
    /// Bound for the generation of the screen targets.
    camera: CameraGroup,
    made: Option<Made>,
    geometry: Option<SceneGeometry>,
}

impl HybridMethod {
    pub fn new(ctx: &GpuContext) -> HybridMethod {
        let screen = ScreenPass::new(ctx);
        let hybrid = Hybrid::new(ctx, screen.pass.format);
        HybridMethod {
            screen,
            hybrid,
            camera: CameraGroup::new(ctx, SHADER, &v_texture_entries()),
            made: None,
            geometry: None,
        }
    }

    /// The walls copied back since the last frame, as the overlay's silhouette edges; `true`
    /// when they arrived.
    fn take_walls(&mut self) -> bool {
        let Some((_, walls, found)) = self.hybrid.poll_walls() else {
            return false;
        };
        let silhouettes = walls
            .iter()
            .enumerate()
            .map(|(i, w)| SilhouetteEdge {
                edge: i as u32,
                v: [w[0].truncate(), w[1].truncate()],
                umbra: true,
                penumbra: false,
                caster_side: w[5].truncate(),
            })
            .collect();
        let mut warnings = Vec::new();
        if found as usize > walls.len() {
            warnings.push(format!(
                "hybrid: {found} walls found, the first {} drawn",
                walls.len()
            ));
        }
        let stats = GeometryStats {
            umbra_edges: walls.len(),
            umbra_triangles: 2 * walls.len(),
            ..GeometryStats::default()
        };
        self.geometry = Some(SceneGeometry {
            casters: vec![CasterGeometry {
                name: "depth-map silhouette".into(),
                silhouettes,
                stats,
                warnings: warnings.clone(),
                ..CasterGeometry::default()
            }],
            stats,
            warnings,
        });
        true
    }
}

impl MethodState for HybridMethod {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        let ctx = inputs.ctx;
        let _ = self.take_walls();
        let map = shared.shadow_map.update(inputs, rec)?;
        let params = wall_params(inputs.knobs, VolumeParams::for_scene(inputs.scene).far);
        let frame = HybridFrame {
            light_view_proj: inputs.light_view.view_projection(),
            infinite_view_proj: inputs.view.infinite_view_proj,
            light: inputs.scene.light.center(),
            map_size: map.size,
            walls: params,
            top_bias: 0.5 * params.threshold,
            bottom_margin: params.threshold,
            lookup_bias: LOOKUP_BIAS,
            width: inputs.view.width,
            height: inputs.view.height,
        };
        self.hybrid.begin(
            ctx,
            &HybridUniforms::new(&frame),
            &map.distance.view,
            map.generation,
        );
        let made = Made {
            revision: inputs.revision,
            map: map.generation,
            params,
        };
        if self.made != Some(made) {
            self.hybrid
                .record_extract(ctx, rec, &map.distance.texture, inputs.revision);
            self.made = Some(made);
        }
        self.screen.begin(ctx, &inputs.view);
        let targets = require(self.screen.targets(), "the screen targets were not made")?;
        self.screen.record_prepass(rec, inputs.surfaces);
        self.hybrid.record_walls(rec, targets);
        self.hybrid.record_resolve(rec, targets);
        let entries = [view_entry(0, &targets.visibility.view)];
        self.camera.bind(&ctx.device, targets.generation, &entries);
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<super::LightMaps<'a>> {
        shared.shadow_map.light_maps()
    }

    fn geometry(&self) -> Option<&SceneGeometry> {
        self.geometry.as_ref()
    }

    fn invalidate(&mut self) {
        self.made = None;
    }

    fn poll_geometry(&mut self) -> bool {
        self.take_walls() || self.hybrid.walls_pending()
    }

    fn stencil_fill(&self, ctx: &GpuContext) -> Option<Result<f64, RenderError>> {
        Some(
            self.screen
                .measure_fill(ctx, &|pass| self.hybrid.draw_walls(pass)),
        )
    }
}
