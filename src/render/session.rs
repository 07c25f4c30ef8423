//! A scene being looked at over many frames (the lab, benchmarks, `render`): the surfaces are
//! uploaded once; each method's light-space work (geometry, D-buffer, shadow maps) runs again only
//! when the light or a caster moved (Jakobsen et al. 2004, §6.1: the D-buffer does not depend on the camera);
//! the camera pass runs every frame. Frames stay on the GPU in [`FrameTargets`]; reading one back
//! is a separate call.

use super::truth;
use std::cell::OnceCell;
use std::collections::{BTreeSet, HashMap};
use std::time::Instant;

use super::frame::{
    read_frame, read_light_map_rows, record_frame, Frame, FrameParts, FrameRequest, FrameTargets,
    LightMapsData,
};
use super::gpu_scene::GpuScene;
use super::methods::{External, FrameInputs, LightMaps, Method, MethodState, Prepare, SharedMaps};
use super::passes::camera::{Camera, ScreenView};
use super::passes::probe::ProbeRequest;
use super::passes::shadow_map::ShadowMap;
use super::passes::view::ViewParams;
use super::readback::Readback;
use super::reference::{self, ReferenceKey};
use super::timer::{groups_span_passes, PassTimer, Recorder};
use super::{GpuContext, RenderError, Texture};
use crate::geometry::light_view::{FitBoxes, LightView};
use crate::geometry::progressive::ProgressiveReference;
use crate::geometry::{PreparedCasters, SceneGeometry};
use crate::scene::{Camera as SceneCamera, Light, LightKind, Mesh, Scene};

mod truths;

/// One frame to record: into which targets, what, and (for a window) how to show it.
pub struct FrameJob<'a> {
    pub targets: &'a mut FrameTargets,
    pub request: FrameRequest,
    /// Draw the view pass into the targets' display texture.
    pub view: Option<ViewParams>,
    /// `false`: the targets already hold this frame; only the view (and probe) run.
    pub render: bool,
    /// Values to read back through the targets' probe (the inspector, the display range's fit).
    pub probes: Vec<ProbeRequest>,
}

/// The reference V on the GPU.
struct ReferenceImage {
    texture: Texture,
    key: ReferenceKey,
    done: u32,
    total: u32,
    generation: u64,
}

pub struct Session {
    scene: Scene,
    /// Built on first use: methods without volumes never need it.
    prepared: OnceCell<PreparedCasters>,
    surfaces: GpuScene,
    light_view: LightView,
    /// The meshes' boxes the light view is fitted with (made again when a mesh changes).
    fit_boxes: FitBoxes,
    /// Bumped whenever the light or a caster changed.
    revision: u64,
    /// Bumped whenever an object's mesh changes (the reference depends on every object).
    meshes: u64,
    methods: HashMap<Method, Box<dyn MethodState>>,
    /// The shader files each method's frames were made with (its state's pipelines, and the
    /// passes recorded with them), as [`super::shaders::recording`] noted them.
    files: HashMap<Method, BTreeSet<String>>,
    /// The shader files of what every method shares: the shadow map's pass, the camera's group.
    common: BTreeSet<String>,
    shared: SharedMaps,
    camera: Camera,
    timer: Option<PassTimer>,
    readback: Readback,
    reference: Option<ReferenceImage>,
    /// The exact hard shadow handed in from outside (the lab's worker), for `reference-hard`.
    reference_hard: Option<ReferenceImage>,
    /// A FLIP map of a frame against the reference's image, handed in for the view pass's FLIP
    /// view ([`Session::set_flip`]): the key of the reference it was made against.
    flip: Option<ReferenceImage>,
    /// Which engine [`Session::cast_truth`] traces the soft truth's rays with.
    truth_engine: truth::Engine,
    /// The synchronous reference ([`Session::advance_reference`]).
    progressive: Option<(ReferenceKey, ProgressiveReference)>,
    /// The targets [`Session::frame`] renders into.
    own: FrameTargets,
    /// Bytes the last submit will read back (timings, probes).
    pending_read_bytes: u64,
    /// Submits so far: each one's pass timings come back tagged with its number.
    submits: u64,
}

impl Session {
    pub fn new(ctx: &GpuContext, scene: Scene) -> Session {
        let surfaces = GpuScene::new(ctx, &scene);
        let fit_boxes = FitBoxes::new(&scene);
        let light_view = LightView::fit_with(&scene, &fit_boxes);
        let ((shadow_map, camera), common) =
            super::shaders::recording(|| (ShadowMap::new(ctx), Camera::new(ctx)));
        Session {
            shared: SharedMaps { shadow_map },
            camera,
            common,
            files: HashMap::new(),
            timer: PassTimer::new(ctx),
            readback: Readback::default(),
            scene,
            prepared: OnceCell::new(),
            surfaces,
            light_view,
            fit_boxes,
            revision: 1,
            meshes: 0,
            methods: HashMap::new(),
            reference: None,
            reference_hard: None,
            flip: None,
            truth_engine: truth::Engine::Cpu,
            progressive: None,
            own: FrameTargets::new(),
            pending_read_bytes: 0,
            submits: 0,
        }
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene's surfaces on the GPU.
    pub fn surfaces(&self) -> &GpuScene {
        &self.surfaces
    }

    /// The casters, welded with their adjacency (what the overlays draw faces from).
    pub fn prepared(&self) -> &PreparedCasters {
        self.prepared
            .get_or_init(|| PreparedCasters::new(&self.scene))
    }

    /// The light centre's view the D-buffer and the shadow maps are drawn in.
    pub fn light_view(&self) -> &LightView {
        &self.light_view
    }

    /// Bumped whenever the light or a caster moved.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Move the light (or change it, disk or line); light-space work is redone on the next
    /// frame if it changed.
    pub fn set_light(&mut self, light: impl Into<Light>) {
        let light = light.into();
        if light != self.scene.light {
            self.scene.light = light;
            self.moved();
        }
    }

    /// Move the camera: only the camera pass (and the reference) depend on it.
    pub fn set_camera(&mut self, camera: SceneCamera) {
        self.scene.camera = camera;
    }

    /// Replace object `index`'s world-space mesh (it moved): the surfaces are uploaded again,
    /// and a caster's adjacency is prepared again.
    pub fn set_object_mesh(&mut self, ctx: &GpuContext, index: usize, mesh: Mesh) {
        let Some(object) = self.scene.objects.get_mut(index) else {
            return;
        };
        if object.mesh == mesh {
            return;
        }
        object.mesh = mesh;
        if object.casts_shadow {
            self.prepared = OnceCell::new();
        }
        self.surfaces = GpuScene::new(ctx, &self.scene);
        self.fit_boxes = FitBoxes::new(&self.scene);
        self.meshes += 1;
        self.moved();
    }

    /// Redo every method's geometry and light-space work on the next frame even if nothing
    /// moved (to measure frame coherence).
    pub fn invalidate_geometry(&mut self) {
        self.moved();
    }

    /// Redo the light-space passes (not the geometry) on the next frame: to time them.
    pub fn invalidate_light_maps(&mut self) {
        self.shared.shadow_map.invalidate();
        for m in self.methods.values_mut() {
            m.invalidate();
        }
    }

    /// Let go of what `method` holds on the GPU and the CPU (its targets, maps, geometry;
    /// for the reference also the V handed in), and of the camera targets [`Session::frame`]
    /// renders into, now (the device is polled, so a CPU adapter's host memory is freed before
    /// this returns): made again if it draws again. A run through every method (`compare`)
    /// holds one method's screen-sized textures at a time, not all, and none while it works
    /// on the frame it read.
    pub fn release(&mut self, ctx: &GpuContext, method: Method) -> Result<(), RenderError> {
        self.methods.remove(&method);
        if truth::is_soft(method) {
            self.reference = None;
            self.progressive = None;
        }
        self.own = FrameTargets::new();
        super::readback::map_now(&ctx.device)
    }

    /// The shader files `changed` have a new text and the pipelines made from them were let go
    /// of ([`GpuContext::forget_shaders`]): the states of the methods whose frames used one of
    /// them are dropped (made again on their next frame, from the pipelines cached now; the
    /// others keep theirs, a temporal method its history), and so are the session's own
    /// targets; where what every method shares (the shadow map's pass, the camera's group) used
    /// one, that is made again and every state dropped. The scene, its surfaces and the truths
    /// handed in stay.
    pub fn shaders_changed(&mut self, ctx: &GpuContext, changed: &BTreeSet<String>) {
        if self.common.is_disjoint(changed) {
            let files = &self.files;
            self.methods
                .retain(|m, _| files.get(m).is_none_or(|f| f.is_disjoint(changed)));
        } else {
            let ((shadow_map, camera), common) =
                super::shaders::recording(|| (ShadowMap::new(ctx), Camera::new(ctx)));
            self.shared = SharedMaps { shadow_map };
            self.camera = camera;
            self.common = common;
            self.methods.clear();
        }
        let methods = &self.methods;
        self.files.retain(|m, _| methods.contains_key(m));
        self.own = FrameTargets::new();
    }

    /// Forget `method`'s frames before (a temporal method's history): its next frame is a
    /// first one.
    pub fn reset_history(&mut self, method: Method) {
        if let Some(m) = self.methods.get_mut(&method) {
            m.reset_history();
        }
    }

    /// A still view of a temporal method (its spec's `history` knob): its history begun afresh
    /// and filled with the frames of `request` the knob states, drawn without reading back, so
    /// the next frame is the one a user standing still sees. Nothing for any other method.
    pub fn fill_history(
        &mut self,
        ctx: &GpuContext,
        request: &FrameRequest,
    ) -> Result<(), RenderError> {
        let Some(frames) = request.method.spec().history else {
            return Ok(());
        };
        self.reset_history(request.method);
        for _ in 0..request.knobs.get(frames) {
            self.draw(ctx, request)?;
        }
        Ok(())
    }

    /// Whether more frames of a still view would still change `method`'s image (a temporal
    /// method's history is filling): a window keeps drawing while it is.
    pub fn settling(&self, method: Method) -> bool {
        self.methods.get(&method).is_some_and(|m| m.settling())
    }

    fn moved(&mut self) {
        self.revision += 1;
        self.light_view = LightView::fit_with(&self.scene, &self.fit_boxes);
    }

    /// The geometry stage's output `method` last built its light pass from.
    pub fn geometry(&self, method: Method) -> Option<&SceneGeometry> {
        self.methods.get(&method).and_then(|m| m.geometry())
    }

    /// `method`'s geometry stage on the GPU, where its last build ran there.
    pub fn gpu_geometry(
        &self,
        method: Method,
    ) -> Option<&crate::render::passes::geometry_gpu::GpuGeometry> {
        self.methods.get(&method).and_then(|m| m.gpu_geometry())
    }

    /// How many times `method` has run the geometry stage, and its last CPU milliseconds.
    pub fn geometry_builds(&self, method: Method) -> (u64, f64) {
        self.methods
            .get(&method)
            .map_or((0, 0.0), |m| m.geometry_builds())
    }

    /// The shadow volumes' fill (mean volume fragments per pixel) of `method`'s last frame, for
    /// a method that counts volumes over the screen (an untimed pass of its own, one wait).
    pub fn stencil_fill(
        &self,
        ctx: &GpuContext,
        method: Method,
    ) -> Option<Result<f64, RenderError>> {
        self.methods.get(&method)?.stencil_fill(ctx)
    }

    /// Let every method pick up what the GPU handed back for its overlays since the last frame
    /// (never waits); `true` while something is on its way or has just arrived.
    pub fn poll_geometry(&mut self, ctx: &GpuContext) -> bool {
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        let mut busy = false;
        for m in self.methods.values_mut() {
            busy |= m.poll_geometry();
        }
        busy
    }

    /// `method`'s light-space maps as they stand.
    /// Make sure the light-space maps a frame of `request` is written with (those of
    /// [`dbuffer_of`] its method) exist, as [`Session::frame`] with `read_dbuffer` does, without
    /// reading them back. Returns the method whose maps they are.
    pub fn prepare_maps(
        &mut self,
        ctx: &GpuContext,
        request: &FrameRequest,
    ) -> Result<Method, RenderError> {
        let d = dbuffer_of(request.method, self.scene.light.kind());
        if !self.methods.contains_key(&d) || d != request.method {
            self.prepare_only(ctx, d, request)?;
        }
        Ok(d)
    }

    /// Rows `rows` of `method`'s light-space maps, read back (see [`read_light_map_rows`]).
    pub fn read_map_rows(
        &mut self,
        ctx: &GpuContext,
        method: Method,
        rows: std::ops::Range<u32>,
    ) -> Result<LightMapsData, RenderError> {
        let Some(maps) = self
            .methods
            .get(&method)
            .and_then(|m| m.light_maps(&self.shared))
        else {
            return Err(RenderError::Readback(format!(
                "{method} has no light-space maps"
            )));
        };
        read_light_map_rows(ctx, &mut self.readback, &maps, rows)
    }

    pub fn light_maps(&self, method: Method) -> Option<LightMaps<'_>> {
        self.methods
            .get(&method)
            .and_then(|m| m.light_maps(&self.shared))
    }

    /// Record every job's frame (light-space work only where stale, the camera pass, the view,
    /// the probe) into one encoder and submit it; nothing waits. Returns the bytes the submit
    /// will read back (timings and probes).
    pub fn submit(
        &mut self,
        ctx: &GpuContext,
        jobs: &mut [FrameJob<'_>],
    ) -> Result<u64, RenderError> {
        ctx.check_lost()?;
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("Session::encoder"),
            });
        let mut bytes = 0;
        let result = (|| {
            for job in jobs.iter_mut() {
                let (recorded, files) =
                    super::shaders::recording(|| self.record_job(ctx, &mut encoder, job));
                self.files
                    .entry(job.request.method)
                    .or_default()
                    .extend(files);
                bytes += recorded?;
            }
            Ok::<_, RenderError>(())
        })();
        self.submits += 1;
        if let Some(t) = self.timer.as_mut() {
            bytes += t.finish(&mut encoder, self.submits);
        }
        ctx.queue.submit([encoder.finish()]);
        for job in jobs.iter_mut() {
            if let Some(p) = job.targets.probe.as_mut() {
                p.request_map();
            }
        }
        if let Some(t) = self.timer.as_mut() {
            t.request_maps();
        }
        // Errors raised before the scope (creating pipelines) come first: they are the cause.
        let scoped = pollster::block_on(scope.pop());
        let error = ctx
            .take_uncaptured_errors()
            .into_iter()
            .next()
            .or(scoped.map(|e| e.to_string()));
        if let Some(e) = error {
            // A lost device fails every call after it: say that, not the first call it failed
            // (wgpu tells the device's loss on its next poll).
            ctx.check_lost_after_poll()?;
            return Err(RenderError::Gpu(e));
        }
        ctx.injected_fault()?;
        result?;
        self.pending_read_bytes = bytes;
        Ok(bytes)
    }

    fn record_job(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        job: &mut FrameJob<'_>,
    ) -> Result<u64, RenderError> {
        // A view, probe or readback (a job without a view) that reads the V/t or cost targets
        // never gets a colour-only frame: asked for one, or holding one, the frame is rendered
        // in full.
        let reads_targets = !job.probes.is_empty()
            || job
                .view
                .as_ref()
                .is_none_or(|v| v.view != super::passes::view::View::Final);
        if reads_targets {
            job.request.colour_only = false;
            if job
                .targets
                .rendered
                .as_ref()
                .is_some_and(|r| r.request.colour_only)
            {
                job.render = true;
            }
        }
        let request = job.request;
        request.validate(ctx)?;
        let method = request.method;
        // Before any of its pipelines is made: a light it cannot take, or a device that lacks
        // what it needs, says so.
        if let Some(why) = method.refusal(self.scene.light.kind(), Some(&ctx.caps)) {
            return Err(RenderError::Request(why));
        }
        let state = self
            .methods
            .entry(method)
            .or_insert_with(|| method.spec().state(ctx));
        let reference = self
            .reference
            .as_ref()
            .filter(|r| (r.key.width, r.key.height) == (request.width, request.height));
        let current = ReferenceKey {
            light: self.scene.light,
            camera: self.scene.camera,
            width: request.width,
            height: request.height,
            samples: request.knobs.get(&super::truth::SAMPLES),
            meshes: self.meshes,
        };
        // The reference method shades only the reference of exactly this view; reference-hard
        // the exact hard shadow of this view when one was handed in (else it casts its rays).
        let hard_key = ReferenceKey {
            samples: 1,
            ..current
        };
        let external = if truth::is_hard(method) {
            self.reference_hard.as_ref().filter(|r| r.key == hard_key)
        } else {
            reference.filter(|r| r.key == current)
        }
        .map(|r| External {
            view: &r.texture.view,
            generation: r.generation,
            rays: r.done,
        });
        let inputs = FrameInputs {
            ctx,
            scene: &self.scene,
            surfaces: &self.surfaces,
            prepared: &self.prepared,
            light_view: &self.light_view,
            revision: self.revision,
            meshes: self.meshes,
            map_size: request.dbuffer_size,
            vt: request.vt,
            knobs: &request.knobs,
            external,
            view: ScreenView::new(
                &self.scene,
                self.surfaces.bounds,
                request.width,
                request.height,
            ),
        };
        // The error view compares with the reference of exactly this view; the FLIP view shows
        // the FLIP map made against it, in the same binding.
        let flip_view = job
            .view
            .as_ref()
            .is_some_and(|v| v.view == super::passes::view::View::Flip);
        let view_reference = if flip_view {
            self.flip.as_ref().filter(|r| r.key == current)
        } else {
            reference.filter(|r| r.key == current)
        }
        .map(|r| (&r.texture.view, r.generation));
        let mut rec = Recorder::new(encoder, self.timer.as_ref())
            .with_groups(groups_span_passes(&ctx.adapter));
        // The frame's debug groups (docs/development/architecture.md): the frame, in it the
        // method's passes, the camera pass and the view; then the probes' readbacks.
        let frame = format!("frame: {method} {}×{}", request.width, request.height);
        rec.group(&frame, |rec| {
            if job.render || job.targets.rendered.is_none() {
                record_frame(
                    FrameParts {
                        inputs,
                        request: &request,
                        method: state.as_mut(),
                        shared: &mut self.shared,
                        camera: &self.camera,
                        surfaces: &self.surfaces,
                    },
                    job.targets,
                    job.view.as_ref().map(|v| (v, view_reference)),
                    rec,
                )?;
            } else if let Some(params) = &job.view {
                super::frame::record_view(
                    ctx,
                    job.targets,
                    params,
                    view_reference,
                    state.light_maps(&self.shared),
                    rec,
                );
            }
            Ok::<_, RenderError>(())
        })?;
        let mut bytes = 0;
        if !job.probes.is_empty() {
            rec.group("readbacks: probes", |rec| {
                for p in &job.probes {
                    bytes += super::passes::probe::record(
                        ctx,
                        job.targets,
                        p,
                        view_reference,
                        state.light_maps(&self.shared),
                        rec,
                    );
                }
            });
        }
        Ok(bytes)
    }

    /// The newest pass timings that have come back, without waiting (a window, a frame later).
    pub fn poll_timings(&mut self, ctx: &GpuContext) -> Option<Vec<(String, f64)>> {
        self.timer.as_mut().and_then(|t| t.poll(ctx))
    }

    /// [`Session::poll_timings`], with the number of the submit they timed (see
    /// [`Session::submits`]).
    pub fn poll_timings_tagged(&mut self, ctx: &GpuContext) -> Option<(u64, Vec<(String, f64)>)> {
        self.timer.as_mut().and_then(|t| t.poll_tagged(ctx))
    }

    /// How many submits the session has made: the next one is numbered one more.
    pub fn submits(&self) -> u64 {
        self.submits
    }

    /// Render `request` into the session's own targets and read it back (with the D-buffer if
    /// `request.read_dbuffer`), with its pass timings: what `dbuffer render` makes. One submit,
    /// one wait.
    pub fn frame(
        &mut self,
        ctx: &GpuContext,
        request: &FrameRequest,
    ) -> Result<Frame, RenderError> {
        self.frame_with(ctx, request, false)
    }

    /// [`Session::frame`] for a method drawn for the last time (`compare`, one method after
    /// another): the method's state is let go of ([`Session::release`]) as soon as the frame is
    /// submitted, so its screen-sized textures are freed when the GPU is done with them, before
    /// the frame is read back into memory, and the camera targets after it.
    pub fn frame_releasing(
        &mut self,
        ctx: &GpuContext,
        request: &FrameRequest,
    ) -> Result<Frame, RenderError> {
        let frame = self.frame_with(ctx, request, true);
        self.release(ctx, request.method)?;
        frame
    }

    /// Render `request` into the session's own targets and wait for it, reading nothing back:
    /// a warm-up (pipelines compiled, geometry and light-space maps made), its timings dropped.
    pub fn draw(&mut self, ctx: &GpuContext, request: &FrameRequest) -> Result<(), RenderError> {
        request.validate(ctx)?;
        let mut own = std::mem::take(&mut self.own);
        let submitted = self.submit(
            ctx,
            &mut [FrameJob {
                targets: &mut own,
                request: FrameRequest {
                    read_dbuffer: false,
                    ..*request
                },
                view: None,
                render: true,
                probes: Vec::new(),
            }],
        );
        self.own = own;
        submitted?;
        match self.timer.as_mut() {
            Some(t) => t.wait(ctx).map(drop),
            None => super::readback::map_now(&ctx.device),
        }
    }

    fn frame_with(
        &mut self,
        ctx: &GpuContext,
        request: &FrameRequest,
        release: bool,
    ) -> Result<Frame, RenderError> {
        let _watch = super::watchdog::watch(|| {
            let m = request.method;
            match m.user_path() {
                Some(path) => format!("a frame of {} ({path})", m.name()),
                None => format!("a frame of {}", m.name()),
            }
        });
        let mut own = std::mem::take(&mut self.own);
        let dbuffer = request
            .read_dbuffer
            .then(|| dbuffer_of(request.method, self.scene.light.kind()));
        let submitted = (|| {
            self.submit(
                ctx,
                &mut [FrameJob {
                    targets: &mut own,
                    request: *request,
                    view: None,
                    render: true,
                    probes: Vec::new(),
                }],
            )?;
            if let Some(d) = dbuffer.filter(|d| *d != request.method) {
                // The D-buffer of the paper's method, for a method that has none of its own
                // (after the frame, so the frame's timings are its own).
                let (prepared, files) =
                    super::shaders::recording(|| self.prepare_only(ctx, d, request));
                self.files.entry(d).or_default().extend(files);
                prepared?;
            }
            if release && dbuffer != Some(request.method) {
                // Nothing of the method is read: its textures go once the GPU is done.
                self.methods.remove(&request.method);
                super::readback::map_now(&ctx.device)?;
            }
            Ok::<_, RenderError>(())
        })();
        let read = submitted.and_then(|_| {
            let maps = dbuffer.and_then(|d| {
                self.methods
                    .get(&d)
                    .and_then(|m| m.light_maps(&self.shared))
            });
            read_frame(ctx, &mut self.readback, &own, maps.as_ref())
        });
        self.own = own;
        let mut frame = read?;
        if let Some(t) = self.timer.as_mut() {
            frame.gpu_ms = t.wait(ctx)?;
        }
        Ok(frame)
    }

    /// Bring `method`'s light-space products up to date for `request`, without a camera pass.
    fn prepare_only(
        &mut self,
        ctx: &GpuContext,
        method: Method,
        request: &FrameRequest,
    ) -> Result<(), RenderError> {
        let state = self
            .methods
            .entry(method)
            .or_insert_with(|| method.spec().state(ctx));
        let inputs = FrameInputs {
            ctx,
            scene: &self.scene,
            surfaces: &self.surfaces,
            prepared: &self.prepared,
            light_view: &self.light_view,
            revision: self.revision,
            meshes: self.meshes,
            map_size: request.dbuffer_size,
            vt: request.vt,
            knobs: &request.knobs,
            external: None,
            view: ScreenView::new(
                &self.scene,
                self.surfaces.bounds,
                request.width,
                request.height,
            ),
        };
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("Session::prepare_only"),
            });
        let mut rec =
            Recorder::new(&mut encoder, None).with_groups(groups_span_passes(&ctx.adapter));
        rec.group(&format!("{method}: its light-space maps alone"), |rec| {
            state.prepare(Prepare(&inputs, &mut self.shared, rec))
        })?;
        ctx.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// Read back whatever `targets` hold, with `method`'s light-space maps if given: for tests
    /// and exports of a frame a window shows. A colour-only frame is rendered in full first,
    /// into targets of its own (what `targets` show stays as it is).
    pub fn read(
        &mut self,
        ctx: &GpuContext,
        targets: &mut FrameTargets,
        maps_of: Option<Method>,
    ) -> Result<Frame, RenderError> {
        // The viewport shows a colour-only frame's colour target itself (FrameTargets::shown).
        let mut full = None;
        if let Some(request) = targets
            .rendered
            .as_ref()
            .map(|r| r.request)
            .filter(|r| r.colour_only)
        {
            let scratch = full.insert(FrameTargets::new());
            self.submit(
                ctx,
                &mut [FrameJob {
                    targets: scratch,
                    request: FrameRequest {
                        colour_only: false,
                        ..request
                    },
                    view: None,
                    render: true,
                    probes: Vec::new(),
                }],
            )?;
        }
        let maps = maps_of.and_then(|m| {
            self.methods
                .get(&m)
                .and_then(|s| s.light_maps(&self.shared))
        });
        read_frame(
            ctx,
            &mut self.readback,
            full.as_ref().unwrap_or(targets),
            maps.as_ref(),
        )
    }

    /// Bytes the last submit reads back.
    pub fn pending_read_bytes(&self) -> u64 {
        self.pending_read_bytes
    }
}

/// Which method's D-buffer `dbuffer.exr` holds for a frame of `method` under a `light` light:
/// its own if it is a D-buffer method, else the paper's; under a line light (which the D-buffer
/// refuses), the hard shadow map from the midpoint (its `|cx_o|` channel alone).
pub fn dbuffer_of(method: Method, light: LightKind) -> Method {
    if light == LightKind::Line {
        Method::HARD
    } else if method == Method::DBUFFER_CENTER {
        method
    } else {
        Method::DBUFFER
    }
}

/// Write V for `key` into `slot`'s texture (made again when the size changed), holding `done` of
/// `total` samples per pixel.
fn upload(
    slot: &mut Option<ReferenceImage>,
    ctx: &GpuContext,
    key: ReferenceKey,
    visibility: &[f32],
    (done, total): (u32, u32),
) -> Result<(), RenderError> {
    let (w, h) = (key.width, key.height);
    if visibility.len() != w as usize * h as usize {
        return Err(RenderError::Request(format!(
            "the reference needs V for each of the {w}×{h} pixels, found {}",
            visibility.len()
        )));
    }
    if slot
        .as_ref()
        .is_none_or(|r| (r.key.width, r.key.height) != (w, h))
    {
        *slot = Some(ReferenceImage {
            texture: Texture::new(
                &ctx.device,
                "Session::reference",
                (w, h),
                wgpu::TextureFormat::R32Float,
                wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            ),
            key,
            done,
            total,
            generation: super::passes::next_generation(),
        });
    }
    let Some(r) = slot.as_mut() else {
        return Ok(());
    };
    ctx.queue.write_texture(
        r.texture.texture.as_image_copy(),
        bytemuck::cast_slice(visibility),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(w * 4),
            rows_per_image: Some(h),
        },
        r.texture.texture.size(),
    );
    r.key = key;
    r.done = done;
    r.total = total;
    Ok(())
}
