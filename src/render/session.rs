//! A scene being looked at over many frames (the lab, benchmarks): the geometry stage runs again
//! only when the light or a caster changed, or the method wants volumes built differently; the
//! passes run every frame (seed 000 §6.1). The ray-cast reference accumulates over frames.

use std::time::Instant;

use super::frame::{Frame, FrameRenderer, FrameRequest, Method};
use super::gpu_scene::GpuScene;
use super::reference::{self, ReferenceKey};
use super::{GpuContext, RenderError};
use crate::geometry::light_view::LightView;
use crate::geometry::progressive::ProgressiveReference;
use crate::geometry::{PreparedCasters, SceneGeometry, VolumeParams};
use crate::scene::{Camera, DiskLight, Mesh, Scene};

pub struct Session {
    scene: Scene,
    prepared: PreparedCasters,
    geometry: SceneGeometry,
    gpu: GpuScene,
    view: LightView,
    renderer: FrameRenderer,
    /// The light or a caster moved since the geometry was built.
    dirty: bool,
    /// Whether the current volumes were built from the light centre only (`dbuffer-center`).
    center_silhouettes: bool,
    geometry_builds: u64,
    /// CPU milliseconds of the last geometry build.
    geometry_ms: f64,
    /// Bumped whenever an object's mesh changes (the reference depends on it).
    meshes: u64,
    reference: Option<(ReferenceKey, ProgressiveReference)>,
}

impl Session {
    pub fn new(ctx: &GpuContext, scene: Scene) -> Session {
        let prepared = PreparedCasters::new(&scene);
        let t = Instant::now();
        let geometry = prepared.build(&scene.light, &VolumeParams::for_scene(&scene));
        let geometry_ms = t.elapsed().as_secs_f64() * 1e3;
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
            center_silhouettes: false,
            geometry_builds: 1,
            geometry_ms,
            meshes: 0,
            reference: None,
        }
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The geometry of the last frame (or of construction).
    pub fn geometry(&self) -> &SceneGeometry {
        &self.geometry
    }

    /// The D-buffer's view from the light centre.
    pub fn light_view(&self) -> &LightView {
        &self.view
    }

    /// How many times the geometry stage has run.
    pub fn geometry_builds(&self) -> u64 {
        self.geometry_builds
    }

    /// CPU milliseconds of the last geometry build (classes, silhouettes, volumes).
    pub fn geometry_ms(&self) -> f64 {
        self.geometry_ms
    }

    /// Move the light; the geometry is rebuilt on the next frame if it changed.
    pub fn set_light(&mut self, light: DiskLight) {
        if light != self.scene.light {
            self.scene.light = light;
            self.dirty = true;
        }
    }

    /// Move the camera (only the reference depends on it beyond the frame itself).
    pub fn set_camera(&mut self, camera: Camera) {
        self.scene.camera = camera;
    }

    /// Rebuild the geometry on the next frame even if nothing moved (to measure frame coherence).
    pub fn invalidate_geometry(&mut self) {
        self.dirty = true;
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
        self.meshes += 1;
        self.dirty = true;
    }

    /// Run the geometry stage if something moved or `method` builds volumes differently.
    fn update_geometry(&mut self, ctx: &GpuContext, method: Method) {
        // Methods without volumes keep whichever volumes there are.
        let center = match method {
            Method::DBuffer | Method::DBufferCenter => method.center_silhouettes(),
            _ => self.center_silhouettes,
        };
        if !self.dirty && center == self.center_silhouettes {
            return;
        }
        let params = VolumeParams {
            center_silhouettes: center,
            ..VolumeParams::for_scene(&self.scene)
        };
        let t = Instant::now();
        self.geometry = self.prepared.build(&self.scene.light, &params);
        self.geometry_ms = t.elapsed().as_secs_f64() * 1e3;
        self.gpu.set_volumes(&ctx.device, &self.geometry);
        self.view = LightView::fit(&self.scene);
        self.geometry_builds += 1;
        self.center_silhouettes = center;
        self.dirty = false;
    }

    /// Render a frame, running the geometry stage first only if something moved. With
    /// [`Method::Reference`] the reference first takes `params.reference_step` more samples.
    pub fn frame(
        &mut self,
        ctx: &GpuContext,
        request: &FrameRequest,
    ) -> Result<Frame, RenderError> {
        self.update_geometry(ctx, request.method);
        if request.method == Method::Reference {
            self.advance_reference(ctx, request)?;
            let v = self.reference.as_ref().map(|(_, r)| r.visibility());
            return self
                .renderer
                .render_with(ctx, &self.scene, &self.gpu, &self.view, request, v);
        }
        self.renderer
            .render(ctx, &self.scene, &self.gpu, &self.view, request)
    }

    /// Take `params.reference_step` more reference samples per pixel for this request's size and
    /// the current scene; starts over when the light, camera, a mesh, the size or K changed.
    pub fn advance_reference(
        &mut self,
        ctx: &GpuContext,
        request: &FrameRequest,
    ) -> Result<(), RenderError> {
        request.params.validate().map_err(RenderError::Request)?;
        let key = ReferenceKey::new(&self.scene, request, self.meshes);
        if self.reference.as_ref().is_none_or(|(k, _)| *k != key) {
            self.update_geometry(ctx, request.method);
            let positions = self.renderer.render(
                ctx,
                &self.scene,
                &self.gpu,
                &self.view,
                &reference::positions_request(request),
            )?;
            let start = reference::start(&self.scene, &positions, request.params.reference_samples);
            self.reference = Some((key, start));
        }
        if let Some((_, r)) = &mut self.reference {
            r.step(request.params.reference_step as usize);
        }
        Ok(())
    }

    /// Samples per pixel the reference holds, and how many it will hold when complete.
    pub fn reference_progress(&self) -> Option<(u32, u32)> {
        self.reference
            .as_ref()
            .map(|(_, r)| (r.samples_done() as u32, r.samples_total() as u32))
    }

    /// The reference V so far (row-major, the size of the last request that advanced it).
    pub fn reference_visibility(&self) -> Option<&[f32]> {
        self.reference.as_ref().map(|(_, r)| r.visibility())
    }

    /// Whether the reference is still converging (another frame would change it).
    pub fn converging(&self) -> bool {
        self.reference
            .as_ref()
            .is_some_and(|(_, r)| !r.is_complete())
    }
}
