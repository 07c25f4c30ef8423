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
use wgpu::TextureFormat as F;

use glam::Vec3;

use super::screen_volumes::{BuiltVolumes, Counted, OnVolumes, ScreenVolumes, OPEN};
use super::{require, v_texture_entries, CameraGroup, FrameInputs, Knobs, MethodSpec, Switch};
use crate::geometry::hard_volume::{scene_volumes, OpenMeshes};
use crate::geometry::volumes::{VolumeKind, VolumeMesh, VolumeVertex};
use crate::geometry::wedges::{wedge_hull, wedge_reach};
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
    let screen = ScreenPass::new(ctx);
    let method = WedgesMethod::new(ctx, &screen);
    Box::new(ScreenVolumes::new(screen, method))
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
/// and the parameters ([`WedgesParams`]).
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

/// `WedgesParams` of `shaders/methods/wedges.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WedgesParams {
    /// 1: V at most the part of the light in front of the receiver's plane ([`HORIZON`]).
    pub horizon: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

impl WedgesParams {
    fn new(knobs: &Knobs) -> WedgesParams {
        WedgesParams {
            horizon: u32::from(knobs.get(&HORIZON)),
            ..WedgesParams::default()
        }
    }
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

/// Its part of the screen-space volumes: the wedges beside the hard volumes, their coverage
/// sum and the resolve.
pub struct WedgesMethod {
    wedges: Wedges,
    /// Bound for the generation of the screen targets.
    camera: CameraGroup,
    wedge_vertices: VertexChunks,
    options: wgpu::Buffer,
}

impl WedgesMethod {
    pub fn new(ctx: &GpuContext, screen: &ScreenPass) -> WedgesMethod {
        WedgesMethod {
            wedges: Wedges::new(ctx, screen),
            camera: CameraGroup::new(ctx, SHADER, &camera_entries()),
            wedge_vertices: VertexChunks::empty(),
            options: uniform_buffer::<WedgesParams>(&ctx.device, "Wedges::params"),
        }
    }
}

impl OnVolumes for WedgesMethod {
    const LABEL: &'static str = "Wedges::volumes";

    fn build(
        &mut self,
        inputs: &FrameInputs<'_>,
        built: &mut BuiltVolumes,
    ) -> Result<(), RenderError> {
        let light = *inputs.area(WEDGES.name)?;
        // The hard part is shadow-volume's volumes from the centre, as they are. The wedges: each
        // silhouette edge once (Crow's one-sided sides; see geometry::wedges::wedge_edges),
        // whatever `open` closes the stencil count with.
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
        self.wedge_vertices = VertexChunks::new(&inputs.ctx.device, "Wedges::wedges", &vertices);
        Ok(())
    }

    fn record(&mut self, c: Counted<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Counted(inputs, rec, screen, generation) = c;
        let light = *inputs.area(WEDGES.name)?;
        let ctx = inputs.ctx;
        ctx.queue.write_buffer(
            &self.options,
            0,
            bytemuck::bytes_of(&WedgesParams::new(inputs.knobs)),
        );
        self.wedges
            .record(ctx, rec, WEDGES.name, screen, &light, &self.wedge_vertices);
        let missing = "the wedges' targets were not made";
        let targets = require(screen.targets(), missing)?;
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
}
