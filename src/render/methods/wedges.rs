//! `wedges`: soft shadow volumes with penumbra wedges (Akenine-Möller & Assarsson 2002;
//! Assarsson & Akenine-Möller 2003), for the disk light.
//!
//! Per light or caster move: the casters' hard volumes from the disk's centre
//! (`geometry::hard_volume`, the same as `shadow-volume`'s) and one wedge per side edge of them
//! (`geometry::wedges::wedge_hull`), uploaded. Per frame: the screen prepass and the z-fail count
//! (`passes::stencil_volumes`, shared with `shadow-volume`: no second copy), the wedges' coverage
//! sum and the resolve (`passes::wedges`); the camera pass reads V at its pixel.
//!
//! The camera pass then takes at most the part of the disk in front of the receiver's own plane
//! (`V = min(V_wedges, F)`, see `geometry::wedges`): a receiver on a caster whose plane cuts the
//! disk is in no wedge, and the papers leave it lit (`--wedges-horizon 0` shows that).
//!
//! The errors the papers admit are kept, to show in `compare`: silhouettes from the centre only
//! (thick or concave casters under a large light: `fig1-large-light`, `no-umbra`) and
//! overlapping edges or casters summed, not combined (`overlap`, `fig7-concave`,
//! `fig8c-complex`, `bunny`); the sum is clamped, which hides some of it.

use super::Cost;
use super::{AdapterNeeds, STENCIL_VOLUMES};
use crate::render::adapter::{FormatNeed, Usage};
use std::time::Instant;
use wgpu::TextureFormat as F;

use glam::Vec3;

use super::shadow_volume::{build_volumes, open_meshes, OPEN};
use super::{
    require, v_texture_entries, CameraGroup, Knobs, MethodSpec, MethodState, Prepare, Switch,
};
use crate::geometry::hard_volume::{scene_volumes, OpenMeshes};
use crate::geometry::volumes::{VolumeKind, VolumeMesh, VolumeVertex};
use crate::geometry::wedges::{wedge_hull, wedge_reach};
use crate::geometry::SceneGeometry;
use crate::render::gpu_scene::VertexChunks;
use crate::render::passes::stencil_volumes::ScreenPass;
use crate::render::passes::wedges::{WedgeVertex, Wedges};
use crate::render::{
    buffer_entry, uniform_buffer, uniform_entry, view_entry, GpuContext, RenderError,
};
use crate::scene::AreaLight;

/// `--wedges-horizon`: clip the disk by the receiver's own plane.
pub static HORIZON: Switch = Switch::new(
    "wedges-horizon",
    "wedges: 1 = a receiver gets at most the part of the disk in front of its own plane \
     (V = min(V, that part)); 0 = the papers' wedges as they are (lit where a caster's own \
     face cuts the disk)",
    true,
);

pub static WEDGES: MethodSpec = MethodSpec::new("wedges", SHADER, |ctx| {
    Box::new(WedgesMethod::new(ctx))
})
.adapter(NEEDS)
.about("penumbra wedges: soft shadow volumes (Akenine-Möller & Assarsson 2002/2003)")
.knobs(&[&OPEN.0, &HORIZON.0])
.cost(Cost::counted("wedge fragments"))
.lights(super::AREA_LIGHTS)
.fixed_quality(
    "one wedge per silhouette edge, its coverage computed exactly per pixel: nothing to trade",
); // the coverage of a disk or a convex polygon

const SHADER: &str = "methods/wedges.wgsl";

/// What it needs of the adapter: the stencil volumes and the wedges' coverage summed by blending, in 32-bit floats
/// or, where they do not blend, 16-bit ones.
const NEEDS: AdapterNeeds = AdapterNeeds::formats(&[
    STENCIL_VOLUMES[0],
    STENCIL_VOLUMES[1],
    STENCIL_VOLUMES[2],
    STENCIL_VOLUMES[3],
    FormatNeed {
        usage: Usage::Blend,
        formats: &[F::Rg32Float, F::Rg16Float],
        fallback: "coverage summed in half floats: V within 1/64 of the 32-bit sum, within 1/256 at 99.5 % of pixels",
    },
]);

/// The camera pass's group 1: the screen visibility (`shared/screen_v.wgsl`), the coverage sum
/// and the options ([`WedgeOptions`]).
fn camera_entries() -> [wgpu::BindGroupLayoutEntry; 3] {
    let [v] = v_texture_entries();
    [
        v,
        crate::render::texture_entry(
            1,
            wgpu::ShaderStages::FRAGMENT,
            wgpu::TextureViewDimension::D2,
        ),
        uniform_entry(2, wgpu::ShaderStages::FRAGMENT),
    ]
}

/// `wedge_options` of `shaders/methods/wedges.wgsl`: x = 1 clips by the receiver's plane.
type WedgeOptions = [f32; 4];

fn wedge_options(knobs: &Knobs) -> WedgeOptions {
    [f32::from(knobs.get(&HORIZON)), 0.0, 0.0, 0.0]
}

/// The wedges of every side edge of `volumes`' hard volumes, as GPU vertices, and the overlay's
/// view of them (each wedge cut at about the distance from its edge to the light).
pub fn build_wedges(
    light: &AreaLight,
    sides: &[[Vec3; 2]],
    reach: f32,
) -> (Vec<WedgeVertex>, VolumeMesh) {
    let mut vertices = Vec::new();
    let mut overlay = VolumeMesh::default();
    let pad = |v: Vec3| [v.x, v.y, v.z];
    for &[e0, e1] in sides {
        for [a, b, c] in wedge_hull(light, e0, e1, reach) {
            for p in [a, b, c] {
                vertices.push(WedgeVertex {
                    position: pad(p),
                    _pad0: 0.0,
                    e0: pad(e0),
                    _pad1: 0.0,
                    e1: pad(e1),
                    _pad2: 0.0,
                });
            }
        }
        // The overlay: the wedge down to about as far below the edge as the light is above it.
        let short = 1.2 * (0.5 * (e0 + e1) - light.center).length();
        for t in wedge_hull(light, e0, e1, short) {
            let base = overlay.vertices.len() as u32;
            for p in t {
                overlay.vertices.push(VolumeVertex {
                    position: p,
                    kind: VolumeKind::PenumbraQuad,
                    edge: [e0, e1],
                    extrusion: light.center,
                });
            }
            overlay.indices.extend([base, base + 1, base + 2]);
        }
    }
    (vertices, overlay)
}

pub struct WedgesMethod {
    screen: ScreenPass,
    wedges: Wedges,
    /// Bound for the generation of the screen targets.
    camera: CameraGroup,
    volumes: VertexChunks,
    wedge_vertices: VertexChunks,
    built_for: Option<(u64, OpenMeshes)>,
    geometry: Option<SceneGeometry>,
    builds: u64,
    geometry_ms: f64,
    options: wgpu::Buffer,
}

impl WedgesMethod {
    pub fn new(ctx: &GpuContext) -> WedgesMethod {
        let screen = ScreenPass::new(ctx);
        let wedges = Wedges::new(ctx, &screen);
        WedgesMethod {
            screen,
            wedges,
            camera: CameraGroup::new(ctx, SHADER, &camera_entries()),
            volumes: VertexChunks::empty(),
            wedge_vertices: VertexChunks::empty(),
            built_for: None,
            geometry: None,
            builds: 0,
            geometry_ms: 0.0,
            options: uniform_buffer::<WedgeOptions>(&ctx.device, "Wedges::options"),
        }
    }
}

impl MethodState for WedgesMethod {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, _, rec) = p;
        let light = *inputs.area(WEDGES.name)?;
        let ctx = inputs.ctx;
        let open = open_meshes(inputs.knobs);
        if self.built_for != Some((inputs.revision, open)) {
            let t = Instant::now();
            // The hard part: shadow-volume's volumes from the centre, as they are.
            let mut built = build_volumes(inputs, light.center, open, self.screen.pass.push());
            // The wedges: each silhouette edge once (Crow's one-sided sides; see
            // geometry::wedges::wedge_edges), whatever `open` closes the stencil count with.
            let volumes = scene_volumes(inputs.prepared(), light.center, OpenMeshes::OneSided);
            let reach = wedge_reach(inputs.scene);
            let mut vertices = Vec::new();
            for ((_, _, volume), caster) in volumes.iter().zip(&mut built.geometry.casters) {
                let (v, overlay) = build_wedges(&light, &volume.sides, reach);
                vertices.extend(v);
                // Wedges beside the hard volume's sides in the overlay's penumbra volume.
                let base = caster.volumes.vertices.len() as u32;
                caster.volumes.vertices.extend(overlay.vertices);
                caster
                    .volumes
                    .indices
                    .extend(overlay.indices.iter().map(|i| i + base));
                caster.stats.penumbra_edges = volume.sides.len();
                caster.stats.penumbra_triangles = overlay.indices.len() / 3;
            }
            built.geometry.stats.penumbra_edges = built
                .geometry
                .casters
                .iter()
                .map(|c| c.stats.penumbra_edges)
                .sum();
            built.geometry.stats.penumbra_triangles = vertices.len() / 3;
            self.volumes = VertexChunks::new(&ctx.device, "Wedges::volumes", &built.vertices);
            self.wedge_vertices = VertexChunks::new(&ctx.device, "Wedges::wedges", &vertices);
            self.geometry = Some(built.geometry);
            self.geometry_ms = t.elapsed().as_secs_f64() * 1e3;
            self.builds += 1;
            self.built_for = Some((inputs.revision, open));
        }
        ctx.queue.write_buffer(
            &self.options,
            0,
            bytemuck::bytes_of(&wedge_options(inputs.knobs)),
        );
        let generation = self.screen.begin(ctx, &inputs.view).generation;
        self.screen.record_prepass(rec, inputs.surfaces);
        self.screen.record_zfail(rec, &self.volumes);
        self.wedges
            .record(ctx, rec, &self.screen, &light, &self.wedge_vertices);
        let missing = "the wedges' targets were not made";
        let targets = require(self.screen.targets(), missing)?;
        let sum = require(self.wedges.sum(), missing)?;
        self.camera.bind(
            &ctx.device,
            generation,
            &[
                view_entry(0, &targets.visibility.view),
                view_entry(1, &sum.view),
                buffer_entry(2, &self.options),
            ],
        );
        Ok(&self.camera)
    }

    fn geometry(&self) -> Option<&SceneGeometry> {
        self.geometry.as_ref()
    }

    fn geometry_builds(&self) -> (u64, f64) {
        (self.builds, self.geometry_ms)
    }

    fn stencil_fill(&self, ctx: &GpuContext) -> Option<Result<f64, RenderError>> {
        Some(
            self.screen
                .measure_fill(ctx, &|pass| self.volumes.draw(pass)),
        )
    }
}
