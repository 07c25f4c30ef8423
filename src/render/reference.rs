//! The ray-cast ground truth (docs/method/metrics.md): per pixel, the surface point under the pixel's centre
//! (a primary ray through the CPU's BVH), then rays to K stratified disk samples (the geometry
//! oracle). All at once for `dbuffer render` and `compare` ([`compute`]); progressively, a few
//! samples per pixel at a time, on a worker thread for the lab ([`ReferenceWorker`]), so the
//! window keeps its frame rate while the reference converges. Either way the finished samples
//! go to the GPU as a texture (`Session::set_reference`) that the `reference` method shades and
//! the error view compares against. The exact hard shadow (`reference-hard`, [`compute_hard`])
//! is one ray per pixel: in one go offline, and for the lab on a worker of its own
//! ([`ReferenceWorker::hard`], handed over through `Session::set_reference_hard`).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, Sender, TryRecvError};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::Vec3;

use rayon::prelude::*;

use crate::geometry::bvh::Bvh;
use crate::geometry::hard_volume::centre_light;
use crate::geometry::oracle::Oracle;
use crate::geometry::progressive::ProgressiveReference;
use crate::geometry::view;
use crate::scene::{Camera, Light, Scene};

/// What a reference image depends on: it starts again when any of it changes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceKey {
    pub light: Light,
    pub camera: Camera,
    pub width: u32,
    pub height: u32,
    /// K, the light samples per pixel.
    pub samples: u32,
    /// Bumped whenever an object's mesh changes.
    pub meshes: u64,
}

/// The surface point under each pixel's centre (`None` where the ray hits nothing): the points
/// the GPU shades there.
pub fn pixel_points(scene: &Scene, bvh: &Bvh, width: u32, height: u32) -> Vec<Option<Vec3>> {
    view::points(scene, bvh, width, height)
}

/// A reference of a `width`×`height` view of `scene` with nothing sampled yet.
pub fn start(scene: &Scene, width: u32, height: u32, samples: u32) -> ProgressiveReference {
    let oracle = Oracle::from_scene(scene, samples as usize);
    let points = pixel_points(scene, oracle.bvh(), width, height);
    ProgressiveReference::new(oracle, points)
}

/// A finished reference and what it cost.
pub struct Computed {
    pub visibility: Vec<f32>,
    /// Milliseconds of shadow rays (the primary rays and the BVH left out).
    pub rays_ms: f64,
    /// Pixels that show a surface (each got K rays).
    pub hit_pixels: usize,
}

/// The whole reference at once; `progress` hears (samples done, total) after each step.
pub fn compute(
    scene: &Scene,
    width: u32,
    height: u32,
    samples: u32,
    progress: &mut dyn FnMut(usize, usize),
) -> Computed {
    let mut r = start(scene, width, height, samples);
    let total = r.samples_total();
    let hit_pixels = r.points().iter().filter(|p| p.is_some()).count();
    let t = Instant::now();
    // Steps of about a second's work on this machine's CPU, for the progress line.
    let step = (total / 16).max(1);
    while r.step(step) > 0 {
        progress(r.samples_done(), total);
    }
    Computed {
        rays_ms: t.elapsed().as_secs_f64() * 1e3,
        visibility: r.visibility().to_vec(),
        hit_pixels,
    }
}

/// The exact hard shadow (`reference-hard`): one ray per pixel to the light's centre, V 1 or 0
/// (0 behind the one-sided light, as the hard methods have it).
pub fn compute_hard(scene: &Scene, width: u32, height: u32) -> Computed {
    let oracle = Oracle::new(scene.all_triangles(), centre_light(&scene.light), 1);
    let points = pixel_points(scene, oracle.bvh(), width, height);
    let t = Instant::now();
    let visibility = points
        .par_iter()
        .with_min_len(256)
        .map(|p| p.map_or(0.0, |x| oracle.visibility(x)))
        .collect();
    Computed {
        rays_ms: t.elapsed().as_secs_f64() * 1e3,
        visibility,
        hit_pixels: points.iter().filter(|p| p.is_some()).count(),
    }
}

/// V of a reference as it stands: its key, the values, and how many samples per pixel they hold.
#[derive(Clone, Debug)]
pub struct Snapshot {
    pub key: ReferenceKey,
    pub visibility: Vec<f32>,
    pub done: u32,
    pub total: u32,
}

enum Command {
    Start(Box<(Scene, ReferenceKey)>),
    Pause,
    Quit,
}

#[derive(Default)]
struct Outbox {
    /// The newest snapshot no one has taken yet.
    latest: Mutex<Option<Snapshot>>,
    /// (key, done, total) of the reference being worked on or finished.
    progress: Mutex<Option<(ReferenceKey, u32, u32)>>,
    /// Steps finished since the worker started.
    steps: AtomicU64,
    busy: AtomicBool,
    /// Counts the worker's news (a snapshot handed over, or it went idle), and wakes whoever
    /// waits for the next ([`ReferenceWorker::wait_for_news`]).
    news: Mutex<u64>,
    news_arrived: Condvar,
}

impl Outbox {
    fn announce(&self) {
        if let Ok(mut n) = self.news.lock() {
            *n += 1;
        }
        self.news_arrived.notify_all();
    }
}

/// The lab's reference: rays cast on a worker thread (at a lower scheduling priority than the
/// window, on its own small thread pool), finished samples handed over as snapshots about ten
/// times a second.
pub struct ReferenceWorker {
    tx: Sender<Command>,
    outbox: Arc<Outbox>,
    thread: Option<JoinHandle<()>>,
    current: Option<ReferenceKey>,
}

/// About this long per step: snapshots arrive this often while the reference converges.
const STEP_MS: f64 = 90.0;

impl ReferenceWorker {
    /// The area reference's worker: K samples per pixel, progressively.
    pub fn new() -> ReferenceWorker {
        ReferenceWorker::spawn(false)
    }

    /// The exact hard shadow's worker (`reference-hard`): each wanted key is computed whole
    /// ([`compute_hard`]) and handed over as one snapshot holding 1 of 1 samples.
    pub fn hard() -> ReferenceWorker {
        ReferenceWorker::spawn(true)
    }

    fn spawn(hard: bool) -> ReferenceWorker {
        let (tx, rx) = mpsc::channel();
        let outbox = Arc::new(Outbox::default());
        let sink = outbox.clone();
        let thread = std::thread::Builder::new()
            .name(
                if hard {
                    "dbuffer-reference-hard"
                } else {
                    "dbuffer-reference"
                }
                .into(),
            )
            .spawn(move || {
                lower_priority();
                work(&rx, &sink, hard);
            })
            .ok();
        ReferenceWorker {
            tx,
            outbox,
            thread,
            current: None,
        }
    }

    /// Work toward the reference `key` of `scene`; a no-op if that is the one being worked on
    /// (or finished).
    pub fn want(&mut self, scene: &Scene, key: ReferenceKey) {
        if self.current == Some(key) {
            return;
        }
        self.current = Some(key);
        self.outbox.busy.store(true, Ordering::Release);
        let _ = self.tx.send(Command::Start(Box::new((scene.clone(), key))));
    }

    /// Stop working: nothing shown needs the reference.
    pub fn pause(&mut self) {
        if self.current.take().is_some() {
            let _ = self.tx.send(Command::Pause);
        }
    }

    /// The newest samples not yet taken, if any.
    pub fn take(&self) -> Option<Snapshot> {
        self.outbox.latest.lock().ok().and_then(|mut l| l.take())
    }

    /// (key, samples per pixel done, total) of the reference being worked on.
    pub fn progress(&self) -> Option<(ReferenceKey, u32, u32)> {
        self.outbox.progress.lock().ok().and_then(|p| *p)
    }

    /// Whether the worker is still adding samples (or starting).
    pub fn busy(&self) -> bool {
        self.outbox.busy.load(Ordering::Acquire)
    }

    /// Steps finished since the worker started.
    pub fn steps(&self) -> u64 {
        self.outbox.steps.load(Ordering::Acquire)
    }

    /// How much news the worker has had (snapshots handed over, and times it went idle): what
    /// [`ReferenceWorker::wait_for_news`] waits to see grow.
    pub fn news(&self) -> u64 {
        self.outbox.news.lock().map_or(0, |n| *n)
    }

    /// Blocks until the worker has news after `seen` (a value of [`ReferenceWorker::news`]) or
    /// `timeout` has passed, and returns the count then. For tests, which step the window once
    /// there is something new to show instead of polling; the lab itself never waits on the
    /// worker (its frames ask for a repaint while the worker is busy).
    pub fn wait_for_news(&self, seen: u64, timeout: Duration) -> u64 {
        let Ok(n) = self.outbox.news.lock() else {
            return seen;
        };
        match self
            .outbox
            .news_arrived
            .wait_timeout_while(n, timeout, |n| *n <= seen)
        {
            Ok((n, _)) => *n,
            Err(_) => seen,
        }
    }
}

impl Default for ReferenceWorker {
    fn default() -> Self {
        Self::new()
    }
}

impl Drop for ReferenceWorker {
    fn drop(&mut self) {
        let _ = self.tx.send(Command::Quit);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn work(rx: &Receiver<Command>, outbox: &Outbox, hard: bool) {
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("dbuffer-reference-{i}"))
        .start_handler(|_| lower_priority())
        .build()
        .ok();
    let mut job: Option<(ReferenceKey, ProgressiveReference)> = None;
    let mut per_step = 1usize;
    loop {
        let command = if job.is_some() {
            match rx.try_recv() {
                Ok(c) => Some(c),
                Err(TryRecvError::Empty) => None,
                Err(TryRecvError::Disconnected) => return,
            }
        } else {
            outbox.busy.store(false, Ordering::Release);
            outbox.announce();
            match rx.recv() {
                Ok(c) => Some(c),
                Err(_) => return,
            }
        };
        match command {
            Some(Command::Quit) => return,
            Some(Command::Pause) => {
                job = None;
                continue;
            }
            Some(Command::Start(b)) if hard => {
                // Only the newest key matters (an orbit asks for one a frame): skip those the
                // window has already moved past.
                let mut newest = Some(b);
                loop {
                    match rx.try_recv() {
                        Ok(Command::Start(n)) => newest = Some(n),
                        Ok(Command::Pause) => newest = None,
                        Ok(Command::Quit) | Err(TryRecvError::Disconnected) => return,
                        Err(TryRecvError::Empty) => break,
                    }
                }
                let Some(b) = newest else { continue };
                let (scene, key) = *b;
                let computed = on(&pool, || compute_hard(&scene, key.width, key.height));
                publish(
                    outbox,
                    Snapshot {
                        key,
                        visibility: computed.visibility,
                        done: 1,
                        total: 1,
                    },
                );
                continue;
            }
            Some(Command::Start(b)) => {
                let (scene, key) = *b;
                let r = on(&pool, || start(&scene, key.width, key.height, key.samples));
                job = Some((key, r));
                per_step = 1;
                if let Ok(mut p) = outbox.progress.lock() {
                    *p = Some((key, 0, key.samples));
                }
                continue;
            }
            None => {}
        }
        let Some((key, r)) = job.as_mut() else {
            continue;
        };
        let t = Instant::now();
        on(&pool, || r.step(per_step));
        let ms = t.elapsed().as_secs_f64() * 1e3;
        // Aim for STEP_MS per step.
        per_step = ((per_step as f64 * STEP_MS / ms.max(1.0)).round() as usize).clamp(1, 256);
        let (done, total) = (r.samples_done() as u32, r.samples_total() as u32);
        publish(
            outbox,
            Snapshot {
                key: *key,
                visibility: r.visibility().to_vec(),
                done,
                total,
            },
        );
        if r.is_complete() {
            job = None;
        }
    }
}

/// Hand `snapshot` over (replacing one not yet taken) and count the step.
fn publish(outbox: &Outbox, snapshot: Snapshot) {
    let progress = (snapshot.key, snapshot.done, snapshot.total);
    if let Ok(mut l) = outbox.latest.lock() {
        *l = Some(snapshot);
    }
    if let Ok(mut p) = outbox.progress.lock() {
        *p = Some(progress);
    }
    outbox.steps.fetch_add(1, Ordering::AcqRel);
    outbox.announce();
}

/// `f` on `pool` (its parallel iterators on its threads), or here without one.
fn on<R: Send>(pool: &Option<rayon::ThreadPool>, f: impl FnOnce() -> R + Send) -> R {
    match pool {
        Some(p) => p.install(f),
        None => f(),
    }
}

/// Run the calling thread at a lower scheduling priority (Linux: nice 10), so a window on the
/// same cores keeps its frame rate.
pub(crate) fn lower_priority() {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: setpriority only reads its integer arguments; on Linux PRIO_PROCESS with a
        // thread id changes that thread alone.
        unsafe {
            let tid = libc::gettid();
            libc::setpriority(libc::PRIO_PROCESS, tid as libc::id_t, 10);
        }
    }
}
