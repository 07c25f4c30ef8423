//! The render core as the lab holds it: a [`Session`] on eframe's own wgpu device. Every pixel
//! the lab shows comes from here, through the same calls `dbuffer render` makes.

use crate::geometry::light_view::LightView;
use crate::geometry::SceneGeometry;
use crate::render::session::Session;
use crate::render::{Frame, FrameRequest, GpuContext, RenderError};
use crate::scene::{Camera, DiskLight, Mesh, Scene};

pub struct Core {
    pub ctx: GpuContext,
    session: Session,
}

impl Core {
    /// Wrap eframe's device (or the test harness's) and start a session on `scene`.
    pub fn new(ctx: GpuContext, scene: Scene) -> Core {
        let session = Session::new(&ctx, scene);
        Core { ctx, session }
    }

    /// Look at another scene.
    pub fn replace_scene(&mut self, scene: Scene) {
        self.session = Session::new(&self.ctx, scene);
    }

    pub fn scene(&self) -> &Scene {
        self.session.scene()
    }

    pub fn geometry(&self) -> &SceneGeometry {
        self.session.geometry()
    }

    pub fn geometry_builds(&self) -> u64 {
        self.session.geometry_builds()
    }

    pub fn set_light(&mut self, light: DiskLight) {
        self.session.set_light(light);
    }

    pub fn set_object_mesh(&mut self, index: usize, mesh: Mesh) {
        self.session.set_object_mesh(&self.ctx, index, mesh);
    }

    pub fn set_camera(&mut self, camera: Camera) {
        self.session.set_camera(camera);
    }

    /// The D-buffer's view from the light centre (maps world points to texels).
    pub fn light_view(&self) -> &LightView {
        self.session.light_view()
    }

    /// CPU milliseconds of the last geometry build.
    pub fn geometry_ms(&self) -> f64 {
        self.session.geometry_ms()
    }

    pub fn frame(&mut self, request: &FrameRequest) -> Result<Frame, RenderError> {
        self.session.frame(&self.ctx, request)
    }

    /// Reference samples per pixel done and asked for, once a reference has been started.
    pub fn reference_progress(&self) -> Option<(u32, u32)> {
        self.session.reference_progress()
    }

    /// The accumulated reference V of the last size it was advanced for (row-major).
    pub fn reference_visibility(&self) -> Option<&[f32]> {
        self.session.reference_visibility()
    }

    /// Add reference samples without showing the reference (for the error view).
    pub fn advance_reference(&mut self, request: &FrameRequest) -> Result<(), RenderError> {
        self.session.advance_reference(&self.ctx, request)
    }

    /// The reference is still adding samples.
    pub fn converging(&self) -> bool {
        self.session.converging()
    }
}
