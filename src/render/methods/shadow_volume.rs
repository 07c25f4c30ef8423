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

use super::{AdapterNeeds, STENCIL_VOLUMES};
use std::time::Instant;

use glam::Vec3;

use super::{
    v_texture_entries, CameraGroup, FrameInputs, Knobs, MethodSpec, MethodState, Prepare, Switch,
};
use crate::geometry::hard_volume::{scene_volumes, Caps, HardVolume, OpenMeshes};
use crate::geometry::silhouette::find_silhouettes;
use crate::geometry::volumes::{VolumeKind, VolumeMesh, VolumeParams, VolumeVertex};
use crate::geometry::{CasterGeometry, FaceClass, GeometryStats, SceneGeometry};
use crate::render::gpu_scene::VertexChunks;
use crate::render::passes::stencil_volumes::ScreenPass;
use crate::render::{view_entry, GpuContext, RenderError};

/// What open meshes get.
pub static OPEN: Switch = Switch::new(
    "sv-open",
    "shadow-volume: volumes of meshes that are not closed: 0 = Crow's one-sided (only \
     faces facing the light cast), 1 = two-sided (every face; exact for open meshes)",
    true,
);

pub static SHADOW_VOLUME: MethodSpec = MethodSpec::new("shadow-volume", SHADER, |ctx| {
    Box::new(ShadowVolume::new(ctx))
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

/// The `--sv-open` choice.
pub fn open_meshes(knobs: &Knobs) -> OpenMeshes {
    if !knobs.get(&OPEN) {
        OpenMeshes::OneSided
    } else {
        OpenMeshes::TwoSided
    }
}

/// The hard volumes of every caster, as homogeneous vertices for the GPU and as the geometry
/// stage's output for the overlays (classes, silhouettes, the sides extruded to `far`).
pub struct BuiltVolumes {
    /// Three homogeneous points per triangle (`HardVolume::triangles`).
    pub vertices: Vec<[f32; 4]>,
    pub geometry: SceneGeometry,
}

/// Build the volumes of the scene's casters from the light point `p`, finite vertices pushed
/// `push` of their distance away from it.
pub fn build_volumes(
    inputs: &FrameInputs<'_>,
    p: Vec3,
    open: OpenMeshes,
    push: f32,
) -> BuiltVolumes {
    let prepared = inputs.prepared();
    let volumes = scene_volumes(prepared, p, open);
    let far = VolumeParams::for_scene(inputs.scene).far;
    let mut vertices = Vec::new();
    let mut geometry = SceneGeometry::default();
    for (mesh, (classes, caps, volume)) in prepared.meshes.iter().zip(&volumes) {
        vertices.extend(volume.triangles(push).iter().map(|v| v.to_array()));
        let stats = GeometryStats {
            triangles: mesh.faces.len(),
            all_front: classes
                .iter()
                .filter(|c| **c == FaceClass::AllFront)
                .count(),
            none_front: classes
                .iter()
                .filter(|c| **c == FaceClass::NoneFront)
                .count(),
            umbra_edges: volume.sides.len(),
            umbra_triangles: volume.triangle_count(),
            ..GeometryStats::default()
        };
        geometry.stats += stats;
        let mut warnings = Vec::new();
        if let Some(w) = mesh.report.warning(&mesh.name) {
            warnings.push(match caps {
                Caps::Lit => format!("{w}; shadow volumes one-sided (Crow): may miss or leak"),
                _ => format!("{w}; shadow volumes two-sided (every face counted)"),
            });
        }
        geometry.warnings.extend(warnings.iter().cloned());
        geometry.casters.push(CasterGeometry {
            name: mesh.name.clone(),
            silhouettes: find_silhouettes(mesh, classes),
            classes: classes.clone(),
            volumes: overlay_mesh(volume, far),
            stats,
            warnings,
        });
    }
    BuiltVolumes { vertices, geometry }
}

/// The volume's sides as quads extruded to `far` (the lab's volume overlay draws their outline).
fn overlay_mesh(volume: &HardVolume, far: f32) -> VolumeMesh {
    let p = volume.light;
    let mut mesh = VolumeMesh::default();
    for &[e0, e1] in &volume.sides {
        let out = |e: Vec3| e + (e - p).normalize_or_zero() * far;
        let base = mesh.vertices.len() as u32;
        for position in [e0, e1, out(e1), out(e0)] {
            mesh.vertices.push(VolumeVertex {
                position,
                kind: VolumeKind::UmbraQuad,
                edge: [e0, e1],
                extrusion: p,
            });
        }
        mesh.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    mesh
}

pub struct ShadowVolume {
    screen: ScreenPass,
    /// Bound for the generation of the screen targets.
    camera: CameraGroup,
    volumes: VertexChunks,
    /// The revision and open-mesh choice the volumes were built for.
    built_for: Option<(u64, OpenMeshes)>,
    geometry: Option<SceneGeometry>,
    builds: u64,
    geometry_ms: f64,
}

impl ShadowVolume {
    pub fn new(ctx: &GpuContext) -> ShadowVolume {
        ShadowVolume {
            screen: ScreenPass::new(ctx),
            camera: CameraGroup::new(ctx, SHADER, &v_texture_entries()),
            volumes: VertexChunks::empty(),
            built_for: None,
            geometry: None,
            builds: 0,
            geometry_ms: 0.0,
        }
    }
}

impl MethodState for ShadowVolume {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, _, rec) = p;
        let ctx = inputs.ctx;
        let open = open_meshes(inputs.knobs);
        if self.built_for != Some((inputs.revision, open)) {
            let t = Instant::now();
            let built = build_volumes(
                inputs,
                inputs.scene.light.center(),
                open,
                self.screen.pass.push(),
            );
            self.volumes = VertexChunks::new(&ctx.device, "ShadowVolume::volumes", &built.vertices);
            self.geometry = Some(built.geometry);
            self.geometry_ms = t.elapsed().as_secs_f64() * 1e3;
            self.builds += 1;
            self.built_for = Some((inputs.revision, open));
        }
        let targets = self.screen.begin(ctx, &inputs.view);
        let entries = [view_entry(0, &targets.visibility.view)];
        self.camera.bind(&ctx.device, targets.generation, &entries);
        self.screen.record_prepass(rec, inputs.surfaces);
        self.screen.record_zfail(rec, &self.volumes);
        self.screen.record_resolve(rec);
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
