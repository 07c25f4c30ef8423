//! The skeleton the screen-space volume methods share (`shadow-volume`, `wedges`): the casters'
//! hard volumes from the light's centre (`geometry::hard_volume`), built again when the light, a
//! caster or `--sv-open` changed, and per frame the screen prepass and the volumes' z-fail count
//! (`passes::stencil_volumes`). A method adds what it builds beside the volumes and its own passes
//! after the count ([`OnVolumes`]); [`ScreenVolumes`] is its [`MethodState`].

use std::time::Instant;

use glam::Vec3;

use super::{CameraGroup, FrameInputs, Knobs, MethodState, Prepare, Switch};
use crate::geometry::hard_volume::{scene_volumes, Caps, HardVolume, OpenMeshes};
use crate::geometry::silhouette::find_silhouettes;
use crate::geometry::volumes::{VolumeKind, VolumeMesh, VolumeParams, VolumeVertex};
use crate::geometry::{CasterGeometry, FaceClass, GeometryStats, SceneGeometry};
use crate::render::gpu_scene::VertexChunks;
use crate::render::passes::stencil_volumes::ScreenPass;
use crate::render::timer::Recorder;
use crate::render::{GpuContext, RenderError};

/// What open meshes get.
pub static OPEN: Switch = Switch::new(
    "sv-open",
    "shadow-volume: volumes of meshes that are not closed: 0 = Crow's one-sided (only \
     faces facing the light cast), 1 = two-sided (every face; exact for open meshes)",
    true,
);

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

/// What a screen-space volume method adds to the skeleton.
pub trait OnVolumes: Send {
    /// The label of the volumes' vertex buffer.
    const LABEL: &'static str;

    /// What it builds beside the hard volumes when they are built again, into `built` (the
    /// wedges add theirs to the overlay); nothing by default.
    fn build(
        &mut self,
        _inputs: &FrameInputs<'_>,
        _built: &mut BuiltVolumes,
    ) -> Result<(), RenderError> {
        Ok(())
    }

    /// After the prepass and the z-fail count: its own passes, and its camera group bound for
    /// the screen targets.
    fn record(&mut self, c: Counted<'_, '_>) -> Result<&CameraGroup, RenderError>;
}

/// What [`OnVolumes::record`] works with: the frame's inputs, its encoder, the screen pass the
/// volumes were counted in, and the generation of its targets (a method takes them apart with
/// `let Counted(inputs, rec, screen, generation) = c;`).
pub struct Counted<'a, 'r>(
    pub &'a FrameInputs<'a>,
    pub &'a mut Recorder<'r>,
    pub &'a ScreenPass,
    pub u64,
);

/// What the volumes were built for.
#[derive(Clone, Copy, PartialEq, Eq)]
struct BuiltFor {
    revision: u64,
    open: OpenMeshes,
}

/// A screen-space volume method's state: the screen pass, the volumes and the method's own part.
pub struct ScreenVolumes<M> {
    screen: ScreenPass,
    volumes: VertexChunks,
    built_for: Option<BuiltFor>,
    geometry: Option<SceneGeometry>,
    builds: u64,
    geometry_ms: f64,
    method: M,
}

impl<M: OnVolumes> ScreenVolumes<M> {
    /// The state of `method`, which draws with `screen`.
    pub fn new(screen: ScreenPass, method: M) -> ScreenVolumes<M> {
        ScreenVolumes {
            screen,
            volumes: VertexChunks::empty(),
            built_for: None,
            geometry: None,
            builds: 0,
            geometry_ms: 0.0,
            method,
        }
    }
}

impl<M: OnVolumes> MethodState for ScreenVolumes<M> {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, _, rec) = p;
        let ctx = inputs.ctx;
        let built_for = BuiltFor {
            revision: inputs.revision,
            open: open_meshes(inputs.knobs),
        };
        if self.built_for != Some(built_for) {
            let t = Instant::now();
            let mut built = build_volumes(
                inputs,
                inputs.scene.light.center(),
                built_for.open,
                self.screen.pass.push(),
            );
            self.method.build(inputs, &mut built)?;
            self.volumes = VertexChunks::new(&ctx.device, M::LABEL, &built.vertices);
            self.geometry = Some(built.geometry);
            self.geometry_ms = t.elapsed().as_secs_f64() * 1e3;
            self.builds += 1;
            self.built_for = Some(built_for);
        }
        let generation = self.screen.begin(ctx, &inputs.view).generation;
        self.screen.record_prepass(rec, inputs.surfaces);
        self.screen.record_zfail(rec, &self.volumes);
        let counted = Counted(inputs, rec, &self.screen, generation);
        self.method.record(counted)
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
