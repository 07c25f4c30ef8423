//! A view kept alive over many frames: what a window (the lab) does to show one or two methods
//! of a scene as it changes, without a window. It holds the [`Session`], the targets each shown
//! side renders into and keeps on the GPU, the progressive ground truth and its workers, the
//! probes, and the FLIP map; the caller says what it wants to see ([`Intent`]: which methods,
//! which view, which pixel to probe, whether something is being dragged) and calls
//! [`ViewSession::advance`] once per window frame. That records a frame only where what decides
//! its pixels changed (the [`RenderKey`]), redraws only the view where only the view changed,
//! feeds the reference workers and hands their samples to the GPU, and computes the FLIP map on a
//! thread of its own, uploading it when it is ready. What comes back ([`Update`]) is what the
//! window shows around the image: errors, probe answers, pass timings, and when to look again.
//!
//! The soft truth is traced on the GPU where the adapter can (`gpu_reference::Progressive`: one
//! short dispatch of a batch of samples per pixel submitted after each advance's frame, the
//! batch's counts picked up by a later advance without waiting), else on the CPU's worker
//! threads; either can be forced
//! ([`ViewSession::set_reference_engine`]). Either way a new key (scene, light, camera, size,
//! K) drops the work on the old one and starts over.
//!
//! A frame is colour-only (`FrameRequest::colour_only`: the camera pass writes the colour alone)
//! when the final image is shown and nothing reads its other targets: no probe under the cursor
//! and no drag being measured. Its cache key leaves that out, so the cursor leaving the viewport
//! renders nothing again.

use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::thread::ThreadId;
use std::time::{Duration, Instant};

mod flip_view;

use self::flip_view::FlipState;
use super::gpu_reference;
use super::passes::probe::{ProbeRequest, ProbeResult};
use super::passes::view::{View, ViewParams};
use super::reference::{ReferenceKey, ReferenceWorker, Snapshot};
use super::session::{FrameJob, Session};
use super::truth::{self, Truth};
use super::{Frame, FrameRequest, FrameTargets, GpuContext, Method, RenderError};
use crate::scene::{Camera, Light, Mesh, Scene};

/// Everything that decides a frame's pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RenderKey {
    request: FrameRequest,
    camera: Camera,
    revision: u64,
    /// The truth's snapshot the frame shades (a truth method only).
    reference: u64,
}

/// Everything that decides how a frame is shown.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ViewKey {
    params: ViewParams,
    /// The reference snapshot (the error view) or FLIP map (the FLIP view) it shows.
    reference: u64,
}

/// A pixel probe's circumstances: the pixel, the frame serial it was probed on, the view, and
/// the reference's serial then (an inspector shows the reference's V there, which grows as it
/// converges): any of them changed, the pixel is probed again.
type Probed = (u32, u32, u64, View, u64);

/// What a side of the view shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Shown {
    pub method: Method,
    pub request: FrameRequest,
    /// The light the frame was rendered with.
    pub light: Light,
    /// Reference samples (done, total) on the GPU when the frame was shown, if any.
    pub reference: Option<(u32, u32)>,
    /// Why the view cannot be drawn as asked (e.g. no reference yet).
    pub note: Option<String>,
    /// Bumped for every new frame the side shows.
    pub serial: u64,
}

/// A pixel to probe: on which side (0 the main one, 1 the right of a split), where.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelProbe {
    pub side: usize,
    pub x: u32,
    pub y: u32,
}

/// What the viewer wants to see this frame.
#[derive(Clone, Copy, Debug)]
pub struct Intent {
    /// The main side's frame: its method, size, light-map size, V(t) and knobs (the soft
    /// truth's samples among them). `colour_only` is the session's to decide.
    pub request: FrameRequest,
    /// The method on the right of a split, if the view is split.
    pub split: Option<Method>,
    /// The view drawn of each frame.
    pub params: ViewParams,
    /// The pixel the inspector reads.
    pub probe: Option<PixelProbe>,
    /// The light or a caster is being dragged: each new frame of the main side is measured
    /// (a motion probe) and keeps every target.
    pub moving: bool,
    /// Wait for what this frame asked of the GPU and the FLIP thread (probes, a FLIP map) before
    /// returning: a scripted window then settles in a known number of frames.
    pub wait: bool,
}

/// One window frame's submit, for the window's statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Submitted {
    /// New frames recorded (views and probes alone not counted).
    pub renders: usize,
    /// CPU milliseconds of recording and submitting.
    pub wall_ms: f64,
    /// CPU milliseconds of the main method's geometry stage, when this submit rebuilt it.
    pub rebuilt: Option<f64>,
    /// Bytes the submit reads back.
    pub bytes: u64,
}

/// When the caller should call [`ViewSession::advance`] again although nothing it knows of
/// changed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Repaint {
    /// Now: something arrived that the next frame shows.
    pub now: bool,
    /// After this long: a worker or the GPU is still working.
    pub after: Option<Duration>,
}

impl Repaint {
    fn after(&mut self, d: Duration) {
        self.after = Some(self.after.map_or(d, |a| a.min(d)));
    }
}

/// What one [`ViewSession::advance`] did and what arrived.
#[derive(Debug, Default)]
pub struct Update {
    /// What went wrong, one line each (the view shows what it could).
    pub errors: Vec<String>,
    /// The submit's figures (zero renders when only nothing changed); `None` when it failed.
    pub submitted: Option<Submitted>,
    /// Pass timings that came back, of the methods shown now.
    pub timings: Option<Vec<(String, f64)>>,
    /// The methods shown are not those of the last advance: timings kept from before are
    /// another method's.
    pub methods_changed: bool,
    /// Probe answers that arrived, per side.
    pub probes: [Vec<ProbeResult>; 2],
    pub repaint: Repaint,
    /// This advance's work ran inside a graphics-debugger capture
    /// ([`ViewSession::capture_next_frame`]).
    pub captured: bool,
}

/// One side of the view: its targets on the GPU and what decided them.
#[derive(Default)]
struct Side {
    targets: FrameTargets,
    shown: Option<Shown>,
    key: Option<RenderKey>,
    view: Option<ViewKey>,
    /// The frame and view the last fit probe was for.
    fitted: Option<(RenderKey, View, [bool; 4])>,
    /// The pixel probed last.
    probed: Option<Probed>,
    /// The serial of the frame whose range count (the NaN / range view's) came back last.
    range_counted: Option<u64>,
}

impl Side {
    fn clear(&mut self) {
        self.shown = None;
        self.key = None;
        self.view = None;
    }
}

/// A scene shown over many frames, one or two methods side by side: see the module's text.
pub struct ViewSession {
    pub ctx: GpuContext,
    pub session: Session,
    /// The soft truth's rays, cast progressively off the caller's thread (the CPU engine).
    pub worker: ReferenceWorker,
    /// The soft truth's rays traced progressively on the GPU (the GPU engine), a batch of
    /// samples submitted per advance and picked up when done.
    pub gpu_worker: gpu_reference::Progressive,
    /// The engine asked for (`None`: the GPU where the adapter can trace, else the CPU).
    engine: Option<truth::Engine>,
    /// Why the GPU engine failed on this device, if it did: the CPU traces from then on.
    gpu_failed: Option<String>,
    /// The hard truth's rays, cast off the caller's thread like the soft truth's.
    pub hard_worker: ReferenceWorker,
    sides: [Side; 2],
    /// Bumped whenever a soft truth snapshot is handed to the GPU.
    reference_serial: u64,
    /// Bumped whenever a hard truth is handed to the GPU.
    hard_serial: u64,
    flip: FlipState,
    serial: u64,
    /// The methods of the last advance, and the first submit after they changed: pass timings
    /// of earlier submits are another method's.
    methods: [Option<Method>; 2],
    timed_from: u64,
    /// The next advance's work goes inside a graphics-debugger capture.
    capture_next: bool,
}

impl ViewSession {
    /// Capture the next advance's GPU work (every pass of the frame, under the debug groups
    /// the timer names) in the attached graphics debugger: RenderDoc when the lab runs under
    /// it; without one, nothing is captured.
    pub fn capture_next_frame(&mut self) {
        self.capture_next = true;
    }

    /// A view of `scene` on `ctx`'s device.
    pub fn new(ctx: GpuContext, scene: Scene) -> ViewSession {
        let session = Session::new(&ctx, scene);
        ViewSession {
            ctx,
            session,
            worker: ReferenceWorker::new(),
            gpu_worker: gpu_reference::Progressive::new(),
            engine: None,
            gpu_failed: None,
            hard_worker: ReferenceWorker::hard(),
            sides: Default::default(),
            reference_serial: 0,
            hard_serial: 0,
            flip: FlipState::default(),
            serial: 0,
            methods: [None; 2],
            timed_from: 0,
            capture_next: false,
        }
    }

    /// Look at another scene.
    pub fn replace_scene(&mut self, scene: Scene) {
        self.session = Session::new(&self.ctx, scene);
        for side in &mut self.sides {
            side.targets.rendered = None;
        }
    }

    pub fn scene(&self) -> &Scene {
        self.session.scene()
    }

    /// Draw every side again although nothing the request holds changed (a user's method's knob
    /// values, which live in its method).
    pub fn redraw(&mut self) {
        for side in &mut self.sides {
            side.key = None;
        }
    }

    /// The shader files `changed` (named as [`super::shaders`] names them, a user's method as
    /// `file:PATH`) have a new text: the pipelines made from them are let go of (those of other
    /// files are kept), the methods' states and the view's and probes' passes are made again
    /// from what is cached now ([`Session::shaders_changed`]; the scene and the truths handed
    /// in stay), and every side draws again. How many pipelines' objects were
    /// let go of.
    pub fn shaders_changed(&mut self, changed: &std::collections::BTreeSet<String>) -> usize {
        let forgotten = self.ctx.forget_shaders(changed);
        self.session.shaders_changed(&self.ctx, changed);
        for side in &mut self.sides {
            side.targets.rendered = None;
            side.targets.view = None;
            side.targets.probe = None;
            side.clear();
            side.fitted = None;
            side.probed = None;
        }
        self.flip.targets = FrameTargets::new();
        self.flip.made = None;
        forgotten
    }

    /// Look from `camera`.
    pub fn set_camera(&mut self, camera: Camera) {
        self.session.set_camera(camera);
    }

    /// Move or change the light.
    pub fn set_light(&mut self, light: impl Into<Light>) {
        self.session.set_light(light);
    }

    /// Object `index` moved: its world-space mesh is `mesh`.
    pub fn set_object_mesh(&mut self, index: usize, mesh: Mesh) {
        self.session.set_object_mesh(&self.ctx, index, mesh);
    }

    /// Trace the soft truth with `engine` (`None`: on the GPU where the adapter can, else on
    /// the CPU's threads). The one no longer used is stopped; the other starts over.
    pub fn set_reference_engine(&mut self, engine: Option<truth::Engine>) {
        if engine != self.engine {
            self.engine = engine;
            self.gpu_failed = None;
        }
    }

    /// The engine that traces the soft truth now: the one asked for where it can run here, the
    /// CPU where the GPU cannot (the adapter refuses, or the GPU's tracing failed). Asked for
    /// none, the GPU — except on an adapter that is itself the CPU (lavapipe), whose traced rays
    /// are several times slower than the CPU's own (docs/results/performance.md).
    pub fn reference_engine(&self) -> truth::Engine {
        let gpu_can =
            self.gpu_failed.is_none() && gpu_reference::refuses_on(&self.ctx.caps).is_none();
        let auto = if self.ctx.adapter.device_type == wgpu::DeviceType::Cpu {
            truth::Engine::Cpu
        } else {
            truth::Engine::Gpu
        };
        match self.engine.unwrap_or(auto) {
            truth::Engine::Gpu if gpu_can => truth::Engine::Gpu,
            _ => truth::Engine::Cpu,
        }
    }

    /// (key, samples per pixel done, total) of the soft truth being traced, by either engine.
    pub fn tracing_progress(&self) -> Option<(ReferenceKey, u32, u32)> {
        match self.reference_engine() {
            truth::Engine::Cpu => self.worker.progress(),
            truth::Engine::Gpu => self.gpu_worker.progress(),
        }
    }

    /// Whether the soft truth's engine is still adding samples.
    pub fn reference_busy(&self) -> bool {
        match self.reference_engine() {
            truth::Engine::Cpu => self.worker.busy(),
            truth::Engine::Gpu => self.gpu_worker.busy(),
        }
    }

    /// How much news the soft truth's engine has had (snapshots handed over): what
    /// [`ViewSession::wait_for_reference`] waits to see grow.
    pub fn reference_news(&self) -> u64 {
        match self.reference_engine() {
            truth::Engine::Cpu => self.worker.news(),
            truth::Engine::Gpu => self.gpu_worker.news(),
        }
    }

    /// Wait at most `timeout` for the soft truth's engine to have something new for the next
    /// advance (the CPU's worker: news after `seen`; the GPU: its batch done). For tests and
    /// measurements; the lab never waits (its frames ask for a repaint while it works).
    pub fn wait_for_reference(&mut self, seen: u64, timeout: Duration) {
        match self.reference_engine() {
            truth::Engine::Cpu => {
                self.worker.wait_for_news(seen, timeout);
            }
            truth::Engine::Gpu => self.gpu_worker.wait(&self.ctx, timeout),
        }
    }

    /// What side `side` shows (0 the main one, 1 the right of a split).
    pub fn shown(&self, side: usize) -> Option<&Shown> {
        self.sides.get(side)?.shown.as_ref()
    }

    /// The texture side `side`'s view was drawn into, once there is one.
    pub fn display(&self, side: usize) -> Option<super::frame::ShownTexture<'_>> {
        self.sides.get(side)?.targets.shown()
    }

    /// Whether a probe's answers are still on their way.
    pub fn probes_pending(&self) -> bool {
        self.sides
            .iter()
            .any(|s| s.targets.probe.as_ref().is_some_and(|p| p.pending()))
    }

    /// Whether a FLIP map is being computed.
    pub fn flip_pending(&self) -> bool {
        self.flip.job.is_some()
    }

    /// How many FLIP maps have been handed to the GPU.
    pub fn flips_made(&self) -> u64 {
        self.flip.serial
    }

    /// The thread the last FLIP map was computed on.
    pub fn flip_thread(&self) -> Option<ThreadId> {
        self.flip.thread
    }

    /// Read side `side`'s frame back whole, with `maps_of`'s light-space maps: for tests and
    /// exports, never per frame.
    pub fn read(&mut self, side: usize, maps_of: Option<Method>) -> Result<Frame, RenderError> {
        let Some(s) = self.sides.get_mut(side) else {
            return Err(RenderError::Request(format!("no view {side}")));
        };
        self.session.read(&self.ctx, &mut s.targets, maps_of)
    }

    /// Show what `intent` asks: feed the truths' workers, record what changed (frames, views,
    /// probes) in one submit, start or pick up the FLIP map, and collect what came back.
    /// `motion` tags a new frame of the main side while something is dragged (given the scene
    /// and the frame's size), the tag its motion probe's answer carries.
    pub fn advance(
        &mut self,
        intent: &Intent,
        motion: &mut dyn FnMut(&Scene, u32, u32) -> u64,
    ) -> Update {
        let mut update = Update::default();
        let params = intent.params;
        let methods = [Some(intent.request.method), intent.split];
        if methods != self.methods {
            self.methods = methods;
            self.timed_from = self.session.submits() + 1;
            update.methods_changed = true;
        }
        let base = FrameRequest {
            colour_only: params.view == View::Final && !intent.moving && intent.probe.is_none(),
            ..intent.request
        };
        let soft = self.feed_soft_truth(&base, &methods, params.view, &mut update);
        let hard = self.feed_hard_truth(&base, &methods, &mut update);
        if std::mem::take(&mut self.capture_next) {
            // A full frame (not only its colour), redrawn even where nothing changed.
            let full = FrameRequest {
                colour_only: false,
                ..base
            };
            for side in &mut self.sides {
                side.clear();
            }
            let device = self.ctx.device.clone();
            super::context::capture(&device, || {
                self.record(intent, full, methods, soft, hard, motion, &mut update)
            });
            update.captured = true;
        } else {
            self.record(intent, base, methods, soft, hard, motion, &mut update);
        }
        // The GPU engine's next batch goes after this frame's work on the queue.
        self.gpu_worker.submit_next(&self.ctx);
        if let (View::Flip, Some(serial)) = (params.view, soft) {
            self.want_flip(serial, &mut update);
        }
        self.take_flip(intent.wait, &mut update);
        if let Some((tag, timings)) = self.session.poll_timings_tagged(&self.ctx) {
            update.timings = (tag >= self.timed_from).then_some(timings);
        }
        // Overlay data some methods get back from the GPU a frame later (hybrid's walls): look
        // again shortly, without spinning.
        if self.session.poll_geometry(&self.ctx) {
            update.repaint.after(Duration::from_millis(15));
        }
        // A temporal method's history is still filling: the next frame differs.
        if methods.iter().flatten().any(|m| self.session.settling(*m)) {
            update.repaint.now = true;
        }
        let ctx = &self.ctx;
        for (side, out) in self.sides.iter_mut().zip(&mut update.probes) {
            *out = match side.targets.probe.as_mut() {
                Some(p) if intent.wait && p.pending() => p.wait(ctx),
                Some(p) => p.poll(ctx),
                None => Vec::new(),
            };
            for r in out.iter() {
                if let ProbeRequest::Range { serial, .. } = r.request {
                    side.range_counted = Some(serial);
                }
            }
        }
        if update.probes.iter().any(|p| !p.is_empty()) || self.probes_pending() {
            update.repaint.now = true;
        }
        // The light-space view of a method that keeps no such maps says so.
        for side in &mut self.sides {
            if let Some(shown) = side.shown.as_mut() {
                if params.view == View::DBuffer && self.session.light_maps(shown.method).is_none() {
                    shown.note = Some(format!("{} keeps no light-space maps", shown.method));
                }
            }
        }
        update
    }

    /// The soft truth: rays on the worker thread while something shown needs it, finished
    /// samples to the GPU. Returns its snapshot serial once the GPU holds it for this view.
    fn feed_soft_truth(
        &mut self,
        base: &FrameRequest,
        methods: &[Option<Method>; 2],
        view: View,
        update: &mut Update,
    ) -> Option<u64> {
        let request = FrameRequest {
            method: truth::SOFT,
            ..*base
        };
        let needed = methods.iter().flatten().any(|m| truth::is_soft(*m))
            || view == View::Error
            || view == View::Flip;
        let engine = self.reference_engine();
        if needed {
            let key = self.session.reference_key(&request);
            let snapshot = match engine {
                truth::Engine::Cpu => {
                    self.gpu_worker.pause();
                    self.worker.want(self.session.scene(), key);
                    self.worker.take()
                }
                truth::Engine::Gpu => {
                    self.worker.pause();
                    // Samples the CPU cast before it was stopped are not shown.
                    let _ = self.worker.take();
                    self.gpu_worker.want(self.session.scene(), key);
                    self.gpu_worker.advance(&self.ctx).unwrap_or_else(|e| {
                        // The CPU takes over (from its first sample) on the next advance.
                        update.errors.push(format!(
                            "reference on the GPU: {e}; the CPU traces it instead"
                        ));
                        self.gpu_failed = Some(e.to_string());
                        self.gpu_worker.pause();
                        update.repaint.now = true;
                        None
                    })
                }
            };
            if let Some(s) = snapshot {
                self.hand_over(s, update);
            }
            if self.reference_busy() {
                // Keep frames coming while it converges (new samples about every 90 ms on
                // the CPU's worker; on the GPU a dispatch of about 40 ms a frame).
                update.repaint.after(Duration::from_millis(match engine {
                    truth::Engine::Cpu => 30,
                    truth::Engine::Gpu => 10,
                }));
            }
        } else {
            self.worker.pause();
            self.gpu_worker.pause();
        }
        self.session
            .has_reference(&request)
            .then_some(self.reference_serial)
    }

    /// Hand the GPU a snapshot of the soft truth.
    fn hand_over(&mut self, s: Snapshot, update: &mut Update) {
        match self
            .session
            .set_reference(&self.ctx, s.key, &s.visibility, (s.done, s.total))
        {
            Ok(()) => self.reference_serial += 1,
            Err(e) => update.errors.push(format!("reference: {e}")),
        }
    }

    /// The hard truth: its rays on a worker too, V to the GPU when done; meanwhile the side
    /// keeps its last picture and says what it waits for. Returns its serial once the GPU holds
    /// it for this view.
    fn feed_hard_truth(
        &mut self,
        base: &FrameRequest,
        methods: &[Option<Method>; 2],
        update: &mut Update,
    ) -> Option<u64> {
        let request = FrameRequest {
            method: truth::HARD,
            ..*base
        };
        if methods.iter().flatten().any(|m| truth::is_hard(*m)) {
            if let Some(s) = self.hard_worker.take() {
                match self
                    .session
                    .set_reference_hard(&self.ctx, s.key, &s.visibility)
                {
                    Ok(()) => self.hard_serial += 1,
                    Err(e) => update.errors.push(format!("reference-hard: {e}")),
                }
            }
            if !self.session.has_reference_hard(&request) {
                let key = self.session.reference_hard_key(&request);
                self.hard_worker.want(self.session.scene(), key);
            }
            if self.hard_worker.busy() {
                update.repaint.after(Duration::from_millis(30));
            }
        } else {
            self.hard_worker.pause();
        }
        self.session
            .has_reference_hard(&request)
            .then_some(self.hard_serial)
    }

    /// Record each side's frame, view and probes where they changed, in one submit.
    #[allow(clippy::too_many_arguments)]
    fn record(
        &mut self,
        intent: &Intent,
        base: FrameRequest,
        methods: [Option<Method>; 2],
        soft: Option<u64>,
        hard: Option<u64>,
        motion: &mut dyn FnMut(&Scene, u32, u32) -> u64,
        update: &mut Update,
    ) {
        let params = intent.params;
        let camera = self.session.scene().camera;
        let revision = self.session.revision();
        let light = self.session.scene().light;
        let progress = self.session.reference_progress().filter(|_| soft.is_some());
        let reference_serial = soft.unwrap_or(0);
        let mut jobs: Vec<FrameJob<'_>> = Vec::new();
        for (i, (side, method)) in self.sides.iter_mut().zip(methods).enumerate() {
            let Some(method) = method else {
                side.clear();
                continue;
            };
            // A method that cannot take this light draws nothing and says why (never a
            // picture made with another light).
            if let Some(why) = method.refusal(light.kind(), Some(&self.ctx.caps)) {
                side.clear();
                update.errors.push(why);
                continue;
            }
            let request = FrameRequest { method, ..base };
            let truth = Truth::of(method);
            let waiting = match truth {
                Some(Truth::Soft) if soft.is_none() => {
                    Some("reference: waiting for its first samples")
                }
                Some(Truth::Hard) if hard.is_none() => {
                    Some("reference-hard: casting its rays (off the UI thread)…")
                }
                _ => None,
            };
            if let Some(note) = waiting {
                let shown = side.shown.get_or_insert(Shown {
                    method,
                    request,
                    light,
                    reference: None,
                    note: None,
                    serial: 0,
                });
                shown.note = Some(note.into());
                continue;
            }
            // Whether a frame is colour-only is not what it shows: the mouse leaving the
            // viewport renders nothing again, and a view or probe that needs the V/t target of
            // a colour-only frame has the render core draw it in full.
            let key = RenderKey {
                request: FrameRequest {
                    colour_only: false,
                    ..request
                },
                camera,
                revision,
                reference: match truth {
                    Some(Truth::Soft) => reference_serial,
                    Some(Truth::Hard) => hard.unwrap_or(0),
                    None => 0,
                },
            };
            let view_key = ViewKey {
                params,
                reference: match params.view {
                    View::Error => reference_serial,
                    View::Flip => self.flip.serial,
                    _ => 0,
                },
            };
            // A temporal method draws again while its history fills, the view standing still.
            let render = side.key != Some(key)
                || side.targets.rendered.is_none()
                || self.session.settling(method);
            let redraw = render || side.view != Some(view_key);
            let mut probes = Vec::new();
            let serial = if render {
                self.serial + 1
            } else {
                side.shown.as_ref().map_or(0, |s| s.serial)
            };
            if let Some(p) = intent.probe.filter(|p| p.side == i) {
                let here = Some((p.x, p.y, serial, params.view, reference_serial));
                if redraw || side.probed != here {
                    probes.push(ProbeRequest::Pixel {
                        x: p.x,
                        y: p.y,
                        params,
                    });
                    side.probed = here;
                }
            }
            if intent.moving && render && i == 0 {
                let tag = motion(self.session.scene(), request.width, request.height);
                probes.push(ProbeRequest::Motion { tag, params });
            }
            // The range view's count of the pixels it marks, for the lab's stats: once a frame,
            // asked again while the answer for the frame shown has not come back (a request
            // made while one is in flight is skipped).
            let counting = side
                .targets
                .probe
                .as_ref()
                .is_some_and(|p| p.range_pending());
            if params.view == View::Range && !counting && side.range_counted != Some(serial) {
                probes.push(ProbeRequest::Range { params, serial });
            }
            let fit_key = Some((key, params.view, params.channels));
            if params.mapping.auto
                && params.view != View::Final
                && params.view != View::Classes
                && params.view != View::Range
                && (side.fitted != fit_key
                    || view_key.reference != side.view.map_or(0, |v| v.reference))
            {
                probes.push(ProbeRequest::Fit { params });
                side.fitted = fit_key;
            }
            if !redraw && probes.is_empty() {
                continue;
            }
            if render {
                self.serial += 1;
            }
            side.key = Some(key);
            side.view = Some(view_key);
            let note = (matches!(params.view, View::Error | View::Flip) && soft.is_none())
                .then(|| "no reference of this size yet: the error view waits for it".to_string());
            side.shown = Some(Shown {
                method,
                request,
                light,
                reference: progress,
                note,
                serial: self.serial,
            });
            jobs.push(FrameJob {
                targets: &mut side.targets,
                request,
                view: Some(params),
                render,
                probes,
            });
        }
        if jobs.is_empty() {
            update.submitted = Some(Submitted::default());
            return;
        }
        let builds = self.session.geometry_builds(base.method).0;
        let t = Instant::now();
        match self.session.submit(&self.ctx, &mut jobs) {
            Ok(bytes) => {
                // As submitted: a view that needs a colour-only frame in full renders it.
                let renders = jobs.iter().filter(|j| j.render).count();
                drop(jobs);
                let wall_ms = t.elapsed().as_secs_f64() * 1e3;
                let (after, geometry_ms) = self.session.geometry_builds(base.method);
                update.submitted = Some(Submitted {
                    renders,
                    wall_ms,
                    rebuilt: (after != builds).then_some(geometry_ms),
                    bytes,
                });
            }
            Err(e) => update.errors.push(e.to_string()),
        }
    }
}
