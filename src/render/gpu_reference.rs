//! The ray-cast reference traced on the GPU (`compare --reference gpu`): the CPU reference's
//! points under the pixels (`reference::pixel_points`, primary rays through the CPU's BVH), its
//! light samples in its progressive order (`geometry::progressive::progressive_order`) and its
//! conventions (`geometry::oracle`: which points get rays, the segment's `SELF_EPS`, the tolerant
//! triangle test), with the shadow rays traced by `passes::trace` against the same BVH
//! flattened into a storage buffer, a batch of samples per dispatch. Only the shadow rays move
//! to the GPU, so the two references differ only where a ray grazes an edge within rounding
//! (`tests/gpu/trace.rs` measures how often).
//!
//! Two ways to run it: all at once ([`compute`], for `compare` and `render`), or progressively
//! for the lab ([`Progressive`]): the points are found on a thread of their own, then each call
//! of [`Progressive::advance`] (once per window frame) picks up the batch of samples that
//! finished on the GPU, if it has, and [`Progressive::submit_next`] submits the next, never
//! waiting for the GPU.

use std::sync::mpsc::{self, Receiver, Sender, TryRecvError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::Vec3;

use super::adapter::{Capabilities, Verdict};
use super::methods::AdapterNeeds;
use super::passes::trace::{max_points, GpuBvh, PendingCounts, RayCounts, ReferenceRays};
use super::reference::{self, Computed, ReferenceKey, Snapshot};
use super::{GpuContext, RenderError};
use crate::geometry::bvh::FlatBvh;
use crate::geometry::oracle::Oracle;
use crate::geometry::progressive::progressive_order;
use crate::scene::Scene;

/// What the GPU reference needs of the adapter: compute shaders, and the tracer's storage
/// buffers in the compute stage.
pub const NEEDS: AdapterNeeds = AdapterNeeds {
    downlevel: wgpu::DownlevelFlags::COMPUTE_SHADERS,
    storage_buffers_per_stage: super::passes::trace::STORAGE_BUFFERS,
    ..AdapterNeeds::NONE
};

/// Shadow rays per dispatch, about: a batch of samples per pixel is as many as keeps one
/// dispatch near this (at least one sample), so no dispatch runs long on any device.
const RAYS_PER_DISPATCH: u64 = 1 << 22;

/// Why the GPU reference cannot run on `caps`, if it cannot.
pub fn refuses_on(caps: &Capabilities) -> Option<String> {
    match NEEDS.check(caps) {
        Verdict::Cannot(missing) => Some(format!(
            "the GPU reference cannot run on {}: it needs {}",
            caps.adapter,
            missing.join(", ")
        )),
        _ => None,
    }
}

/// What the GPU's shadow rays cost, summed over every ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cost {
    /// Shadow rays traced.
    pub rays: u64,
    /// BVH boxes tested.
    pub box_tests: u64,
    /// Triangles tested.
    pub triangle_tests: u64,
}

/// The whole reference of a `width`×`height` view of `scene` at `samples` per pixel, its shadow
/// rays traced on the GPU; `progress` hears (samples done, total) after each batch. V per pixel
/// is `visible / K` exactly as the CPU reference computes it.
pub fn compute(
    ctx: &GpuContext,
    scene: &Scene,
    width: u32,
    height: u32,
    samples: u32,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Computed, Cost), RenderError> {
    let piece = max_points(ctx);
    compute_in_pieces(ctx, scene, (width, height), samples, piece, progress)
}

/// [`compute`] with the image traced in pieces of at most `piece` pixels (at least 1), each its
/// own buffers and dispatches: [`compute`] takes the most one storage binding of the device
/// holds; a test, fewer, to see that the pieces make the same image.
pub fn compute_in_pieces(
    ctx: &GpuContext,
    scene: &Scene,
    (width, height): (u32, u32),
    samples: u32,
    piece: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Computed, Cost), RenderError> {
    if let Some(why) = refuses_on(&ctx.caps) {
        return Err(RenderError::Request(why));
    }
    let oracle = Oracle::from_scene(scene, samples as usize);
    let points = reference::pixel_points(scene, oracle.bvh(), width, height);
    let hit_pixels = points.iter().filter(|p| p.is_some()).count();
    let traced: Vec<Option<Vec3>> = points
        .iter()
        .map(|p| p.filter(|&x| oracle.casts_from(x)))
        .collect();
    let order = progressive_order(oracle.sample_points());
    let t = Instant::now();
    let bvh = GpuBvh::new(ctx, &oracle.bvh().flatten())?;
    // An image larger than one storage binding holds is traced in pieces, side by side.
    let mut pieces = traced
        .chunks(piece.clamp(1, max_points(ctx)))
        .map(|points| ReferenceRays::new(ctx, &bvh, points, &order))
        .collect::<Result<Vec<_>, _>>()?;
    let total = pieces.first().map_or(0, ReferenceRays::samples_total);
    let lit = traced.iter().filter(|p| p.is_some()).count().max(1) as u64;
    let batch = (RAYS_PER_DISPATCH / lit).clamp(1, u64::from(total.max(1))) as u32;
    let mut done = 0;
    while done < total {
        for piece in &mut pieces {
            piece.step(ctx, batch);
        }
        super::readback::map_now(&ctx.device)?;
        done = pieces.first().map_or(total, ReferenceRays::samples_done);
        progress(done as usize, total as usize);
    }
    let mut counts = Vec::with_capacity(traced.len());
    for piece in &pieces {
        counts.extend(piece.read(ctx)?);
    }
    let rays_ms = t.elapsed().as_secs_f64() * 1e3;
    let k = total.max(1) as f32;
    let visibility = counts
        .iter()
        .zip(&traced)
        .map(|(c, p)| if p.is_some() { c.count as f32 / k } else { 0.0 })
        .collect();
    let mut cost = Cost::default();
    for (c, p) in counts.iter().zip(&traced) {
        if p.is_some() {
            cost.rays += u64::from(total);
            cost.box_tests += u64::from(c.box_tests);
            cost.triangle_tests += u64::from(c.triangle_tests);
        }
    }
    Ok((
        Computed {
            visibility,
            rays_ms,
            hit_pixels,
        },
        cost,
    ))
}

/// What a progressive GPU reference needs from the CPU before its first batch: the points
/// that cast rays (`None`: no rays, V = 0), the light's samples in the progressive order and
/// the BVH flattened for the GPU.
struct Prepared {
    key: ReferenceKey,
    traced: Vec<Option<Vec3>>,
    order: Vec<Vec3>,
    flat: FlatBvh,
}

impl Prepared {
    fn of(scene: &Scene, key: ReferenceKey) -> Prepared {
        let oracle = Oracle::from_scene(scene, key.samples as usize);
        let traced = reference::pixel_points(scene, oracle.bvh(), key.width, key.height)
            .into_iter()
            .map(|p| p.filter(|&x| oracle.casts_from(x)))
            .collect();
        Prepared {
            key,
            traced,
            order: progressive_order(oracle.sample_points()),
            flat: oracle.bvh().flatten(),
        }
    }
}

/// Prepares references ([`Prepared`]) on a thread of its own, at a lower priority than the
/// window: the primary rays of a large view take longer than a window frame. Only the newest
/// key asked for is prepared (a drag asks for one a frame).
struct Preparer {
    tx: Option<Sender<Box<(Scene, ReferenceKey)>>>,
    rx: Receiver<Prepared>,
    thread: Option<JoinHandle<()>>,
}

impl Preparer {
    fn new() -> Preparer {
        let (tx, jobs) = mpsc::channel::<Box<(Scene, ReferenceKey)>>();
        let (done, rx) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("dbuffer-reference-gpu".into())
            .spawn(move || {
                reference::lower_priority();
                while let Ok(mut job) = jobs.recv() {
                    while let Ok(newer) = jobs.try_recv() {
                        job = newer;
                    }
                    let (scene, key) = *job;
                    if done.send(Prepared::of(&scene, key)).is_err() {
                        return;
                    }
                }
            })
            .ok();
        Preparer {
            tx: Some(tx),
            rx,
            thread,
        }
    }
}

impl Drop for Preparer {
    fn drop(&mut self) {
        // The thread ends when its channel closes, after the job it is on.
        self.tx = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// A batch of samples submitted and its counts on their way back.
struct InFlight {
    reads: Vec<PendingCounts>,
    /// Each piece's counts, as they arrive.
    arrived: Vec<Option<Vec<RayCounts>>>,
    /// Samples per pixel the counts hold.
    done: u32,
    submitted: Instant,
}

/// A reference being traced: its buffers on the GPU and the batch under way.
struct Run {
    key: ReferenceKey,
    /// Which pixels cast rays.
    lit: Vec<bool>,
    /// Kept alive with the traces that read it.
    _bvh: GpuBvh,
    pieces: Vec<ReferenceRays>,
    /// Samples per pixel of the next batch.
    batch: u32,
    /// The most samples per pixel a batch takes (about [`RAYS_PER_DISPATCH`] rays).
    max_batch: u32,
    in_flight: Option<InFlight>,
    /// Samples per pixel of the last snapshot handed over.
    shown: u32,
    total: u32,
}

/// About this long per batch on the GPU: long batches would hold up the window's frames
/// queued behind them, short ones cost a readback each.
const BATCH_MS: f64 = 60.0;

/// Rays of the first batch, before there is a time to aim by.
const FIRST_RAYS: u64 = 1 << 18;

impl Run {
    /// `limit`: at most this many rays a batch (at least one sample per pixel).
    fn new(ctx: &GpuContext, p: Prepared, limit: u64) -> Result<Run, RenderError> {
        let bvh = GpuBvh::new(ctx, &p.flat)?;
        let pieces = p
            .traced
            .chunks(max_points(ctx))
            .map(|points| ReferenceRays::new(ctx, &bvh, points, &p.order))
            .collect::<Result<Vec<_>, _>>()?;
        let lit: Vec<bool> = p.traced.iter().map(Option::is_some).collect();
        let rays = lit.iter().filter(|l| **l).count().max(1) as u64;
        let total = pieces.first().map_or(0, ReferenceRays::samples_total);
        let per_batch = |r: u64| (r / rays).clamp(1, u64::from(total.max(1))) as u32;
        Ok(Run {
            key: p.key,
            lit,
            _bvh: bvh,
            batch: per_batch(FIRST_RAYS.min(limit)),
            max_batch: per_batch(RAYS_PER_DISPATCH.min(limit)),
            pieces,
            in_flight: None,
            shown: 0,
            total,
        })
    }

    fn complete(&self) -> bool {
        self.shown >= self.total
    }

    /// Submit the next batch and ask for its counts back.
    fn submit(&mut self, ctx: &GpuContext) {
        for piece in &mut self.pieces {
            piece.step(ctx, self.batch);
        }
        let done = self
            .pieces
            .first()
            .map_or(self.total, ReferenceRays::samples_done);
        let reads: Vec<PendingCounts> = self.pieces.iter().map(|p| p.start_read(ctx)).collect();
        self.in_flight = Some(InFlight {
            arrived: reads.iter().map(|_| None).collect(),
            reads,
            done,
            submitted: Instant::now(),
        });
    }

    /// The batch's snapshot, once every piece's counts have arrived (checks, never waits).
    fn poll(&mut self, ctx: &GpuContext) -> Result<Option<Snapshot>, RenderError> {
        let Some(f) = self.in_flight.as_mut() else {
            return Ok(None);
        };
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        for (read, slot) in f.reads.iter().zip(&mut f.arrived) {
            if slot.is_none() {
                *slot = read.take().transpose()?;
            }
        }
        if f.arrived.iter().any(Option::is_none) {
            return Ok(None);
        }
        let ms = f.submitted.elapsed().as_secs_f64() * 1e3;
        let done = f.done;
        let n = done.max(1) as f32;
        let visibility = f
            .arrived
            .iter()
            .flatten()
            .flatten()
            .zip(&self.lit)
            .map(|(c, &lit)| if lit { c.count as f32 / n } else { 0.0 })
            .collect();
        self.in_flight = None;
        self.shown = done;
        // Aim for BATCH_MS a batch, growing at most fourfold at a time.
        let aim = (f64::from(self.batch) * BATCH_MS / ms.max(1.0)).round() as u32;
        self.batch = aim.clamp(1, self.batch.saturating_mul(4).min(self.max_batch));
        Ok(Some(Snapshot {
            key: self.key,
            visibility,
            done,
            total: self.total,
        }))
    }
}

/// The lab's reference traced on the GPU progressively, driven from the window's thread: see
/// the module's text. What it hands over ([`Snapshot`]s) is what the CPU's worker hands over,
/// V = visible / samples so far, with the same samples in the same order.
pub struct Progressive {
    preparer: Preparer,
    wanted: Option<ReferenceKey>,
    run: Option<Run>,
    /// Points prepared that the next advance takes.
    ready: Option<Prepared>,
    /// The most rays a batch takes ([`Progressive::limit_batch`]).
    batch_rays: u64,
    /// Snapshots handed over: what [`Progressive::news`] counts.
    news: u64,
}

impl Default for Progressive {
    fn default() -> Self {
        Self::new()
    }
}

impl Progressive {
    pub fn new() -> Progressive {
        Progressive {
            preparer: Preparer::new(),
            wanted: None,
            run: None,
            ready: None,
            batch_rays: RAYS_PER_DISPATCH,
            news: 0,
        }
    }

    /// Work toward the reference `key` of `scene`; a no-op if that is the one being traced (or
    /// finished). Any other is dropped, its batch in flight with it.
    pub fn want(&mut self, scene: &Scene, key: ReferenceKey) {
        if self.wanted == Some(key) {
            return;
        }
        self.wanted = Some(key);
        self.run = None;
        self.ready = None;
        if let Some(tx) = self.preparer.tx.as_ref() {
            let _ = tx.send(Box::new((scene.clone(), key)));
        }
    }

    /// At most `rays` rays a batch from the next reference on (at least one sample per pixel):
    /// a test sees a small image converge over many batches.
    pub fn limit_batch(&mut self, rays: u64) {
        self.batch_rays = rays.max(1);
    }

    /// Stop: nothing shown needs the reference (or the CPU traces it now).
    pub fn pause(&mut self) {
        self.wanted = None;
        self.run = None;
        self.ready = None;
    }

    /// Pick up what arrived (the points prepared, a batch's counts); returns the newest
    /// snapshot, if a batch finished. Never waits for the GPU. [`Progressive::submit_next`]
    /// then submits the next batch.
    pub fn advance(&mut self, ctx: &GpuContext) -> Result<Option<Snapshot>, RenderError> {
        let Some(wanted) = self.wanted else {
            return Ok(None);
        };
        if self.run.is_none() {
            let mut newest = self.ready.take();
            loop {
                match self.preparer.rx.try_recv() {
                    Ok(p) => newest = Some(p),
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => {
                        self.wanted = None;
                        return Err(RenderError::Request(
                            "the GPU reference's preparing thread ended".into(),
                        ));
                    }
                }
            }
            // One prepared for a key the view has moved past is dropped.
            match newest.filter(|p| p.key == wanted) {
                Some(p) => match Run::new(ctx, p, self.batch_rays) {
                    Ok(run) => self.run = Some(run),
                    Err(e) => {
                        self.wanted = None;
                        return Err(e);
                    }
                },
                None => return Ok(None),
            }
        }
        let Some(run) = self.run.as_mut() else {
            return Ok(None);
        };
        let snapshot = run.poll(ctx).inspect_err(|_| self.wanted = None)?;
        if snapshot.is_some() {
            self.news += 1;
        }
        Ok(snapshot)
    }

    /// Submit the next batch of samples, unless one is in flight or none is left: after the
    /// window's frame is submitted, so that frame does not wait behind the batch on the queue.
    pub fn submit_next(&mut self, ctx: &GpuContext) {
        if let Some(run) = self.run.as_mut() {
            if run.in_flight.is_none() && !run.complete() {
                run.submit(ctx);
            }
        }
    }

    /// Whether samples are still to come (the points being found, or batches to trace).
    pub fn busy(&self) -> bool {
        self.wanted.is_some() && self.run.as_ref().is_none_or(|r| !r.complete())
    }

    /// (key, samples per pixel handed over, total) of the reference being traced.
    pub fn progress(&self) -> Option<(ReferenceKey, u32, u32)> {
        let key = self.wanted?;
        Some(match self.run.as_ref() {
            Some(r) => (key, r.shown, r.total),
            None => (key, 0, key.samples),
        })
    }

    /// Snapshots handed over so far.
    pub fn news(&self) -> u64 {
        self.news
    }

    /// Wait at most `timeout` for the batch in flight to finish on the GPU (or for the points
    /// to be prepared): for tests and measurements, which advance again once there is something
    /// new; the lab never waits.
    pub fn wait(&mut self, ctx: &GpuContext, timeout: Duration) {
        if self.wanted.is_none() {
            return;
        }
        match self.run.as_ref() {
            Some(r) if r.in_flight.is_some() => {
                let _ = ctx.device.poll(wgpu::PollType::Wait {
                    submission_index: None,
                    timeout: Some(timeout),
                });
            }
            Some(_) => {}
            None => {
                // Kept for the next advance, which makes its buffers.
                if let Ok(p) = self.preparer.rx.recv_timeout(timeout) {
                    self.ready = Some(p);
                }
            }
        }
    }
}
