//! A frame without a window, as `dbuffer render`, `compare` and the tests make it: a
//! [`Session`] on a headless device, the reference computed when the method is the reference,
//! one frame rendered and read back with the D-buffer and its timings.

use std::time::Instant;

use super::frame::{Frame, FrameRequest};
use super::session::{dbuffer_of, Session};
use super::truth;
use super::{GpuContext, Method, RenderError};
use crate::geometry::GeometryStats;
use crate::scene::Scene;

/// A GPU context kept across renders (its pipelines are built once).
pub struct Offline {
    pub ctx: GpuContext,
    /// Called with (samples done, samples total) while the reference accumulates.
    pub progress: Option<Box<dyn FnMut(usize, usize)>>,
    /// Which engine traces the soft truth's rays in the sessions made here
    /// ([`Offline::session`]).
    pub reference: truth::Engine,
}

/// What one offline frame cost and built.
#[derive(Clone, Debug, Default)]
pub struct FrameReport {
    /// CPU milliseconds per stage, in order.
    pub cpu_ms: Vec<(String, f64)>,
    /// Counts of the geometry stage behind the D-buffer read back with the frame.
    pub geometry: GeometryStats,
    /// What the geometry stage warned about.
    pub warnings: Vec<String>,
    /// Reference shadow rays per pixel hit (K) and the pixels hit, for the reference.
    pub reference_rays: Option<(u32, usize)>,
    /// The casters' penumbrae reach beyond what the D-buffer's frustum can hold.
    pub clipped: bool,
}

impl Offline {
    pub fn new() -> Result<Offline, RenderError> {
        Ok(Offline {
            ctx: GpuContext::headless()?,
            progress: None,
            reference: truth::Engine::Cpu,
        })
    }

    /// A session on `scene` for several frames.
    pub fn session(&self, scene: Scene) -> Session {
        let mut session = Session::new(&self.ctx, scene);
        session.set_truth_engine(self.reference);
        session
    }

    /// Render `scene` as `request` says and read it back, the D-buffer included
    /// (`output::RenderOutputs::from_frame` turns it into a render's files).
    pub fn render(
        &mut self,
        scene: &Scene,
        request: &FrameRequest,
    ) -> Result<(Frame, FrameReport), RenderError> {
        let t = Instant::now();
        let mut session = self.session(scene.clone());
        let setup_ms = t.elapsed().as_secs_f64() * 1e3;
        let (frame, mut report) = self.render_in(&mut session, request)?;
        report.cpu_ms.insert(0, ("session_setup".into(), setup_ms));
        report.clipped = session.light_view().clipped;
        Ok((frame, report))
    }

    /// Render `request` in `session` and read it back, the D-buffer included; for the reference
    /// its rays are cast first.
    pub fn render_in(
        &mut self,
        session: &mut Session,
        request: &FrameRequest,
    ) -> Result<(Frame, FrameReport), RenderError> {
        let mut noop = |_: usize, _: usize| {};
        let progress: &mut dyn FnMut(usize, usize) = match self.progress.as_mut() {
            Some(p) => p.as_mut(),
            None => &mut noop,
        };
        let request = FrameRequest {
            read_dbuffer: true,
            ..*request
        };
        render_in(&self.ctx, session, &request, progress)
    }
}

/// Render `request` in `session` and read it back (the method's light-space maps if
/// `request.read_dbuffer`); for the reference its rays are cast first (on this thread),
/// `progress` told (samples done, total).
pub fn render_in(
    ctx: &GpuContext,
    session: &mut Session,
    request: &FrameRequest,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Frame, FrameReport), RenderError> {
    render_in_history(ctx, session, request, progress, true)
}

/// [`render_in`], a temporal method's history begun afresh and filled first where `fresh` (a
/// still view), or carried on from the session's frames before (the next frame of an animation).
pub fn render_in_history(
    ctx: &GpuContext,
    session: &mut Session,
    request: &FrameRequest,
    progress: &mut dyn FnMut(usize, usize),
    fresh: bool,
) -> Result<(Frame, FrameReport), RenderError> {
    request.validate(ctx)?;
    let mut report = FrameReport::default();
    if let Some(cast) = session.cast_truth(ctx, request, progress)? {
        report.cpu_ms.push((request.method.name().into(), cast.ms));
        report.cpu_ms.push(("reference_rays".into(), cast.rays_ms));
        report.reference_rays = Some((cast.samples, cast.hit_pixels));
    }
    // A temporal method is shown as a still view is: after the frames of history its knob
    // states, drawn first from a history begun afresh.
    if fresh {
        session.fill_history(ctx, request)?;
    }
    let t = Instant::now();
    let frame = session.frame(ctx, request)?;
    report
        .cpu_ms
        .push(("frame_and_readback".into(), t.elapsed().as_secs_f64() * 1e3));
    let dbuffer = dbuffer_of(request.method, session.scene().light.kind());
    let (_, geometry_ms) = session.geometry_builds(dbuffer);
    report
        .cpu_ms
        .insert(0, ("geometry_volumes".into(), geometry_ms));
    if let Some(g) = session.geometry(dbuffer) {
        report.geometry = g.stats;
        report.warnings = g.warnings.clone();
    } else if let Some(gpu) = session.gpu_geometry(dbuffer) {
        // The GPU stage's counts, read back here (a render reads its frame back anyway).
        let g = gpu.stats(ctx, session.prepared())?;
        report.geometry = g.stats;
        report.warnings = g.warnings;
    }
    report.clipped = session.light_view().clipped;
    Ok((frame, report))
}

/// Draw one small frame of `method` on `scene` on a device of its own, on a thread of its own,
/// and wait at most `limit` for it: what the lab does before it switches to a user's method (or
/// a new version of one), so a shader that loses its device, or never ends, loses that device
/// and not the lab's, and the lab keeps drawing the method it had. A trial that does not end in
/// time is left behind (its thread blocked on its own device).
pub fn trial(method: Method, scene: &Scene, limit: std::time::Duration) -> Result<(), String> {
    const SIDE: u32 = 64;
    let (tx, rx) = std::sync::mpsc::channel();
    let scene = scene.clone();
    let spawned = std::thread::Builder::new()
        .name("method-trial".into())
        .spawn(move || {
            let result = (|| {
                let ctx = GpuContext::headless()?;
                let mut session = Session::new(&ctx, scene);
                let request = FrameRequest {
                    width: SIDE,
                    height: SIDE,
                    dbuffer_size: 256,
                    method,
                    ..FrameRequest::default()
                };
                session.frame(&ctx, &request)?;
                ctx.check_lost_after_poll()
            })();
            let _ = tx.send(result.map_err(|e| e.to_string()));
        });
    if let Err(e) = spawned {
        return Err(format!("cannot start a trial of {}: {e}", method.name()));
    }
    let name = method.user_path().unwrap_or(method.name());
    match rx.recv_timeout(limit) {
        Ok(Ok(())) => Ok(()),
        Ok(Err(e)) => Err(format!("{name}: a {SIDE}² trial frame failed: {e}")),
        Err(_) => Err(format!(
            "{name}: a {SIDE}² trial frame did not finish within {} s on a device of its own: a \
             shader that does not end, such as a loop whose exit is never taken?",
            limit.as_secs_f64()
        )),
    }
}
