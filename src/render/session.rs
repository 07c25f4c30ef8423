//! A scene being looked at over many frames (the lab, benchmarks): the geometry stage runs again
//! only when the light or a caster changed; the passes run every frame (seed 000 §6.1).

use super::frame::{Frame, FrameRenderer, FrameRequest};
use super::gpu_scene::GpuScene;
use super::{GpuContext, RenderError};
use crate::geometry::light_view::LightView;
use crate::geometry::{PreparedCasters, SceneGeometry, VolumeParams};
use crate::scene::{DiskLight, Mesh, Scene};

pub struct Session {
    scene: Scene,
    prepared: PreparedCasters,
    geometry: SceneGeometry,
    gpu: GpuScene,
    view: LightView,
    renderer: FrameRenderer,
    /// The light or a caster moved since the geometry was built.
    dirty: bool,
    geometry_builds: u64,
}

impl Session {
    pub fn new(ctx: &GpuContext, scene: Scene) -> Session {
        let prepared = PreparedCasters::new(&scene);
        let geometry = prepared.build(&scene.light, &VolumeParams::for_scene(&scene));
        let gpu = GpuScene::new(&ctx.device, &scene, &geometry);
        let view = LightView::fit(&scene);
        Session {
            renderer: FrameRenderer::new(ctx),
            scene,
            prepared,
            geometry,
            gpu,
            view,
            dirty: false,
            geometry_builds: 1,
        }
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    pub fn geometry(&self) -> &SceneGeometry {
        &self.geometry
    }

    /// How many times the geometry stage has run.
    pub fn geometry_builds(&self) -> u64 {
        self.geometry_builds
    }

    /// Move the light; the geometry is rebuilt on the next frame if it changed.
    pub fn set_light(&mut self, light: DiskLight) {
        if light != self.scene.light {
            self.scene.light = light;
            self.dirty = true;
        }
    }

    /// Replace object `index`'s world-space mesh (it moved); a caster's adjacency is prepared
    /// again, and the surfaces are uploaded again.
    pub fn set_object_mesh(&mut self, ctx: &GpuContext, index: usize, mesh: Mesh) {
        let Some(object) = self.scene.objects.get_mut(index) else {
            return;
        };
        if object.mesh == mesh {
            return;
        }
        object.mesh = mesh;
        self.prepared = PreparedCasters::new(&self.scene);
        self.gpu = GpuScene::new(&ctx.device, &self.scene, &self.geometry);
        self.dirty = true;
    }

    /// Render a frame, running the geometry stage first only if something moved.
    pub fn frame(
        &mut self,
        ctx: &GpuContext,
        request: &FrameRequest,
    ) -> Result<Frame, RenderError> {
        if self.dirty {
            self.geometry = self
                .prepared
                .build(&self.scene.light, &VolumeParams::for_scene(&self.scene));
            self.gpu.set_volumes(&ctx.device, &self.geometry);
            self.view = LightView::fit(&self.scene);
            self.geometry_builds += 1;
            self.dirty = false;
        }
        self.renderer
            .render(ctx, &self.scene, &self.gpu, &self.view, request)
    }
}
