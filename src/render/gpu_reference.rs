//! The ray-cast reference traced on the GPU (`compare --reference gpu`): the CPU reference's
//! points under the pixels (`reference::pixel_points`, primary rays through the CPU's BVH), its
//! light samples in its progressive order (`geometry::progressive::progressive_order`) and its
//! conventions (`geometry::oracle`: which points get rays, the segment's `SELF_EPS`), with the
//! shadow rays traced by `passes::trace` against the same triangles, a batch of samples per
//! dispatch, by one of its two paths: hardware ray queries where the device has them, else the
//! same BVH flattened into a storage buffer and traversed in WGSL with the CPU's tolerant
//! triangle test ([`Path`]). Only the shadow rays move to the GPU, so the references differ
//! only where a ray grazes an edge within rounding (`tests/gpu/trace.rs` measures how often,
//! for both paths).
//!
//! Two ways to run it: all at once ([`compute`], for `compare` and `render`), or progressively
//! for the lab ([`Progressive`], through the WGSL BVH on every adapter): the points are found on a thread of their own, then each call
//! of [`Progressive::advance`] (once per window frame) picks up the batch of samples that
//! finished on the GPU, if it has, and [`Progressive::submit_next`] submits the next, never
//! waiting for the GPU.

use std::sync::mpsc::{self, Receiver, Sender, TryRecvError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::Vec3;

use super::adapter::{Capabilities, Verdict};
use super::methods::AdapterNeeds;
use super::passes::trace::{max_points, Path, PendingCounts, RayCounts, ReferenceRays, TraceScene};
use super::reference::{self, Computed, ReferenceKey, Snapshot};
use super::{GpuContext, RenderError};
use crate::geometry::bvh::FlatBvh;
use crate::geometry::oracle::Oracle;
use crate::geometry::progressive::progressive_order;
use crate::scene::Scene;

/// What the GPU reference needs of the adapter: compute shaders, and the tracer's storage
/// buffers in the compute stage (the BVH path's, which every adapter with these takes; ray
/// queries are used where there are any, [`Path::best`]).
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

/// How the GPU's shadow rays were traced and what they cost, summed over every ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cost {
    /// The tracer's path.
    pub path: Path,
    /// Shadow rays traced.
    pub rays: u64,
    /// BVH boxes tested (0 on [`Path::RayQuery`]: the driver does not say).
    pub box_tests: u64,
    /// Triangles tested (0 on [`Path::RayQuery`]).
    pub triangle_tests: u64,
}

/// The whole reference of a `width`×`height` view of `scene` at `samples` per pixel, its shadow
/// rays traced on the GPU by [`Path::auto`]; `progress` hears (samples done, total) after each
/// batch. V per pixel is `visible / K` exactly as the CPU reference computes it.
pub fn compute(
    ctx: &GpuContext,
    scene: &Scene,
    width: u32,
    height: u32,
    samples: u32,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Computed, Cost), RenderError> {
    let piece = max_points(ctx);
    let path = Path::auto(ctx)?;
    compute_in_pieces(ctx, scene, (width, height), samples, path, piece, progress)
}

/// [`compute`] by `path`, with the image traced in pieces of at most `piece` pixels (at least
/// 1), each its own buffers and dispatches: [`compute`] takes the most one storage binding of
/// the device holds; a test, fewer, to see that the pieces make the same image, or names the
/// path, to hold one to the other on one device.
pub fn compute_in_pieces(
    ctx: &GpuContext,
    scene: &Scene,
    (width, height): (u32, u32),
    samples: u32,
    path: Path,
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
    let trace_scene = TraceScene::new(ctx, oracle.bvh(), path)?;
    // An image larger than one storage binding holds is traced in pieces, side by side.
    let mut pieces = traced
        .chunks(piece.clamp(1, max_points(ctx)))
        .map(|points| ReferenceRays::new(ctx, &trace_scene, points, &order))
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
    let mut cost = Cost {
        path,
        rays: 0,
        box_tests: 0,
        triangle_tests: 0,
    };
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

/// What is under way on the GPU: a dispatch (a slice of pixels of a batch), or the batch's
/// counts being read back after its last.
struct InFlight {
    /// When the GPU was seen to have run everything submitted up to the dispatch.
    finished: Arc<Mutex<Option<Instant>>>,
    /// Every piece's counts asked for (a read; empty for a dispatch), and those arrived.
    reads: Vec<PendingCounts>,
    arrived: Vec<Option<Vec<RayCounts>>>,
    /// Rays the dispatch traces (about: the pixels' share of lit ones).
    rays: f64,
    /// The dispatch ends its batch: its counts are read once it has run.
    last: bool,
    submitted: Instant,
}

/// A reference being traced: its buffers on the GPU and the batch under way. A batch is
/// `batch` samples per pixel over every pixel (about [`SNAPSHOT_MS`] of work), in one dispatch
/// or in slices of pixels (one a frame) where one would run longer than [`BATCH_MS`]; its
/// counts are read back after its last slice, and V = visible / samples then.
struct Run {
    key: ReferenceKey,
    /// Which pixels cast rays.
    lit: Vec<bool>,
    /// The share of pixels that cast rays (at least one pixel's worth).
    lit_share: f64,
    /// Kept alive with the traces that read it.
    _bvh: TraceScene,
    pieces: Vec<ReferenceRays>,
    /// Rays to aim a dispatch at: adapted to take about [`BATCH_MS`].
    rays: f64,
    /// The most rays a dispatch takes.
    max_rays: f64,
    /// The batch under way: its first sample, its samples per pixel, and the next pixel (over
    /// all pieces) to trace.
    first: u32,
    batch: u32,
    next_pixel: u64,
    in_flight: Option<InFlight>,
    /// Samples per pixel of the last snapshot handed over.
    shown: u32,
    total: u32,
}

/// About this long per dispatch: a long one would hold up the window's frames queued behind
/// it (and, on a CPU's Vulkan, the window's thread that submits it), short ones cost a submit
/// each and a readback per batch.
const BATCH_MS: f64 = 40.0;

/// About this long of dispatches per batch, a snapshot each (the CPU's worker hands one over
/// every 90 ms): a batch's readback and the frame shading it cost about a dispatch's time on a
/// CPU's Vulkan at the lab's size.
const SNAPSHOT_MS: f64 = 160.0;

/// Rays of the first dispatch, before there is a time to aim by.
const FIRST_RAYS: u64 = 1 << 16;

/// The fewest pixels in a slice.
const MIN_SLICE: u64 = 256;

impl Run {
    /// `limit`: at most this many rays a dispatch.
    fn new(ctx: &GpuContext, p: Prepared, limit: u64) -> Result<Run, RenderError> {
        let bvh = TraceScene::from_flat(ctx, &p.flat)?;
        let pieces = p
            .traced
            .chunks(max_points(ctx))
            .map(|points| ReferenceRays::new(ctx, &bvh, points, &p.order))
            .collect::<Result<Vec<_>, _>>()?;
        let lit: Vec<bool> = p.traced.iter().map(Option::is_some).collect();
        let lit_pixels = lit.iter().filter(|l| **l).count().max(1);
        let total = pieces.first().map_or(0, ReferenceRays::samples_total);
        let max_rays = RAYS_PER_DISPATCH.min(limit).max(1) as f64;
        Ok(Run {
            key: p.key,
            lit_share: lit_pixels as f64 / lit.len().max(1) as f64,
            lit,
            _bvh: bvh,
            rays: (FIRST_RAYS as f64).min(max_rays),
            max_rays,
            first: 0,
            batch: 0,
            next_pixel: 0,
            pieces,
            in_flight: None,
            shown: 0,
            total,
        })
    }

    fn complete(&self) -> bool {
        self.shown >= self.total
    }

    /// Submit the next dispatch: a new batch's first slice, or the next slice of the batch
    /// under way.
    fn submit(&mut self, ctx: &GpuContext) {
        // Set before the submit: where submitting waits for the GPU, that time is the dispatch's.
        let submitted = Instant::now();
        let pixels = self.lit.len() as u64;
        let lit = (pixels as f64 * self.lit_share).max(1.0);
        if self.next_pixel == 0 {
            // Samples for about SNAPSHOT_MS of dispatches: each batch is read back and shaded.
            let left = self.total.saturating_sub(self.shown);
            self.first = self.shown;
            let rays = self.rays * SNAPSHOT_MS / BATCH_MS;
            self.batch = ((rays / lit) as u32).clamp(1, left.max(1));
        }
        // Pixels this dispatch takes: all that are left where the batch fits, else a slice.
        let want = (self.rays / (f64::from(self.batch) * self.lit_share)) as u64;
        let mut end = (self.next_pixel + want.max(MIN_SLICE)).min(pixels);
        // Within one piece (a piece holds at most one storage binding's points).
        let mut base = 0u64;
        for piece in &self.pieces {
            let n = u64::from(piece.pixels());
            if self.next_pixel < base + n {
                end = end.min(base + n);
                let local = |p: u64| (p - base) as u32;
                piece.trace(
                    ctx,
                    self.first..self.first + self.batch,
                    local(self.next_pixel)..local(end),
                );
                break;
            }
            base += n;
        }
        let rays = (end - self.next_pixel) as f64 * f64::from(self.batch) * self.lit_share;
        let last = end >= pixels;
        self.next_pixel = if last { 0 } else { end };
        self.in_flight = Some(InFlight {
            finished: when_done(ctx),
            reads: Vec::new(),
            arrived: Vec::new(),
            rays,
            last,
            submitted,
        });
    }

    /// Pick up what finished (checks, never waits): a dispatch run (the next one aimed by its
    /// time; after a batch's last, its counts asked for), or the batch's snapshot once its
    /// counts have arrived.
    fn poll(&mut self, ctx: &GpuContext) -> Result<Option<Snapshot>, RenderError> {
        let Some(f) = self.in_flight.as_mut() else {
            return Ok(None);
        };
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        if f.reads.is_empty() {
            let Some(finished) = f.finished.lock().ok().and_then(|t| *t) else {
                return Ok(None);
            };
            // Aim the next dispatch at BATCH_MS, growing at most fourfold at a time.
            let ms = finished.duration_since(f.submitted).as_secs_f64() * 1e3;
            let aim = f.rays * BATCH_MS / ms.max(0.5);
            self.rays = aim.clamp(64.0, (self.rays * 4.0).min(self.max_rays));
            if !f.last {
                self.in_flight = None;
                return Ok(None);
            }
            // The batch is done on the GPU: read its counts back now that nothing waits
            // before the copy on the queue.
            f.reads = self.pieces.iter().map(|p| p.start_read(ctx)).collect();
            f.arrived = f.reads.iter().map(|_| None).collect();
            let _ = ctx.device.poll(wgpu::PollType::Poll);
        }
        for (read, slot) in f.reads.iter().zip(&mut f.arrived) {
            if slot.is_none() {
                *slot = read.take().transpose()?;
            }
        }
        if f.arrived.iter().any(Option::is_none) {
            return Ok(None);
        }
        let Some(f) = self.in_flight.take() else {
            return Ok(None);
        };
        let done = self.first + self.batch;
        let n = done.max(1) as f32;
        let visibility = f
            .arrived
            .iter()
            .flatten()
            .flatten()
            .zip(&self.lit)
            .map(|(c, &lit)| if lit { c.count as f32 / n } else { 0.0 })
            .collect();
        self.shown = done;
        Ok(Some(Snapshot {
            key: self.key,
            visibility,
            done,
            total: self.total,
        }))
    }
}

/// A time set when the GPU has run everything submitted so far (seen on a later device poll).
fn when_done(ctx: &GpuContext) -> Arc<Mutex<Option<Instant>>> {
    let finished = Arc::new(Mutex::new(None));
    let flag = finished.clone();
    ctx.queue.on_submitted_work_done(move || {
        if let Ok(mut f) = flag.lock() {
            *f = Some(Instant::now());
        }
    });
    finished
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
    /// The most rays a dispatch takes ([`Progressive::limit_batch`]).
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

    /// At most `rays` rays a dispatch from the next reference on (a batch of one sample per
    /// pixel in slices where it is more): a test sees a small image converge over many batches.
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
                // Where the submit ran the dispatch (a CPU's Vulkan), it is done now: noticed
                // here, its time is the dispatch's and not the wait for the next frame.
                let _ = ctx.device.poll(wgpu::PollType::Poll);
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
