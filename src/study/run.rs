//! Running a study: per scene, the reference once (and its noise floor), then every cell's
//! error as `compare` measures it, then every cell's cost as `bench` times it — each result
//! cached as it is made, so a stopped run resumes where it stopped.

use crate::render::truth;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::cache::{binary_id, scene_hash, Cache};
use super::spec::{Setting, StudySpec};
use crate::bench::{time_frames, Stat, Timing};
use crate::compare::{counted_pixels, rgb_of};
use crate::geometry::bvh::Bvh;
use crate::geometry::metrics::{self, Metrics};
use crate::geometry::{flip, view};
use crate::render::offline::render_in;
use crate::render::session::Session;
use crate::render::truth::SAMPLES;
use crate::render::{FrameRequest, GpuContext, Method, RenderError};
use crate::scene::Scene;

/// Sessions timed together, interleaved (about the bench's one per method): more would hold
/// every cell's light-space maps at once.
pub const COST_BATCH: usize = 20;

/// A cell whose first timed frame takes longer than this (wall) is timed on that frame alone:
/// `bitmask` on the many thin casters of `pergola` takes tens of seconds a frame on lavapipe.
pub const SLOW_FRAME_MS: f64 = 2000.0;

/// A cell's error against the scene's reference: `compare`'s metrics and FLIP's mean.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellError {
    pub class_mismatch_pct: f64,
    pub mae: f64,
    pub penumbra_mae: f64,
    pub p99: f64,
    pub flip: f64,
    pub pixels: usize,
    pub penumbra_pixels: usize,
}

impl CellError {
    fn of(m: &Metrics, flip: f64) -> CellError {
        CellError {
            class_mismatch_pct: m.class_mismatch_pct,
            mae: m.mae,
            penumbra_mae: m.penumbra_mae,
            p99: m.p99,
            flip,
            pixels: m.pixels,
            penumbra_pixels: m.penumbra_pixels,
        }
    }
}

/// A cell's cost: the bench's timing of its frame. For the reference, whose frame takes one
/// sample a pixel, `frame_ms` is K times one sample's ray casting plus the frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellCost {
    /// The figure the plots use: the sum of the GPU passes, or wall time for a CPU-side method.
    pub frame_ms: f64,
    pub timing: Timing,
}

/// One cell: a method at one setting on one scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Cell {
    pub scene: String,
    pub method: String,
    /// The setting's label (`blocker-taps 16, filter-taps 32`, `defaults`).
    pub setting: String,
    /// The axes it sets, as `(flag name, value)`.
    pub values: Vec<(String, u32)>,
    pub map_size: u32,
    pub error: Option<CellError>,
    pub cost: Option<CellCost>,
    /// Why it was not measured: a light the method does not take, a device without what it
    /// needs, a failure.
    pub not_measured: Option<String>,
    /// Taken from the cache rather than measured in this run.
    pub cached: bool,
}

impl Cell {
    /// Measured both ways.
    pub fn complete(&self) -> bool {
        self.not_measured.is_some() || (self.error.is_some() && self.cost.is_some())
    }
}

/// A scene's reference and cells.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SceneStudy {
    pub name: String,
    pub light: String,
    pub caster_triangles: usize,
    /// The reference's K, and the penumbra MAE of that reference against one of 4K: the error
    /// no method can be told apart below (the reference's own).
    pub reference_samples: u32,
    pub noise_floor: f64,
    pub cells: Vec<Cell>,
}

/// What the study ran on.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Machine {
    pub cpu: String,
    pub adapter: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
    pub timestamps: bool,
    pub build: String,
}

impl Machine {
    pub fn of(ctx: &GpuContext) -> Machine {
        Machine {
            cpu: crate::render::adapter::host_description(),
            adapter: ctx.adapter.name.clone(),
            backend: format!("{:?}", ctx.adapter.backend),
            device_type: format!("{:?}", ctx.adapter.device_type),
            driver: ctx.adapter.driver.clone(),
            driver_info: ctx.adapter.driver_info.clone(),
            timestamps: ctx.timestamps,
            build: format!(
                "dbuffer {} ({} build)",
                env!("CARGO_PKG_VERSION"),
                if cfg!(debug_assertions) {
                    "debug"
                } else {
                    "release"
                }
            ),
        }
    }

    fn key(&self) -> String {
        format!(
            "{}|{:?}|{}|{}|{}",
            self.adapter, self.backend, self.driver, self.driver_info, self.timestamps
        )
    }
}

/// A whole study's results.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Study {
    pub machine: Machine,
    pub width: u32,
    pub height: u32,
    pub dbuffer_size: u32,
    pub vt: String,
    pub warmup: usize,
    pub frames: usize,
    pub quick: bool,
    pub scenes: Vec<SceneStudy>,
    /// Cells measured in this run and taken from the cache.
    pub measured: usize,
    pub cached: usize,
    pub seconds: f64,
    /// Stopped before every cell was measured (the rest come from the next run).
    pub stopped: bool,
}

/// What the run tells its caller as it goes, and the caller's answer.
pub enum Progress<'a> {
    /// Starting a stage of a scene (`ground truth`, `errors`, `costs`).
    Stage { scene: &'a str, stage: &'a str },
    /// `done` of `total` measurements (cell errors and costs, references) finished.
    Done { done: usize, total: usize },
}

/// Whether to go on after a progress report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    Go,
    Stop,
}

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("{0}")]
    Render(#[from] RenderError),
    #[error("the study's cache in {dir}: {error}")]
    Cache { dir: String, error: std::io::Error },
}

/// The reference of one scene at the study's size: its V, colour, the counted pixels and the
/// noise floor.
struct Reference {
    visibility: Vec<f32>,
    rgb: Vec<[u8; 3]>,
    mask: Vec<bool>,
    noise_floor: f64,
}

impl Reference {
    fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.visibility.len() * 8 + 8);
        out.extend_from_slice(&self.noise_floor.to_le_bytes());
        for ((v, c), &m) in self.visibility.iter().zip(&self.rgb).zip(&self.mask) {
            out.extend_from_slice(&v.to_le_bytes());
            out.extend_from_slice(c);
            out.push(u8::from(m));
        }
        out
    }

    fn from_bytes(bytes: &[u8], pixels: usize) -> Option<Reference> {
        if bytes.len() != 8 + pixels * 8 {
            return None;
        }
        let noise_floor = f64::from_le_bytes(bytes[..8].try_into().ok()?);
        let (mut visibility, mut rgb, mut mask) = (
            Vec::with_capacity(pixels),
            Vec::with_capacity(pixels),
            Vec::with_capacity(pixels),
        );
        for px in bytes[8..].chunks_exact(8) {
            visibility.push(f32::from_le_bytes([px[0], px[1], px[2], px[3]]));
            rgb.push([px[4], px[5], px[6]]);
            mask.push(px[7] != 0);
        }
        Some(Reference {
            visibility,
            rgb,
            mask,
            noise_floor,
        })
    }
}

/// The frame request of a cell.
/// A method in a cell's cache key: its name, and for a user's method the hash of its shader
/// and its knob values, so an edited file or another `--knob` is measured again.
fn method_key(method: Method) -> String {
    match method.user_shader() {
        Some((source, values)) => format!(
            "{}#{:016x}{values:?}",
            method.name(),
            super::cache::hash_str(&source)
        ),
        None => method.name().to_string(),
    }
}

fn request(spec: &StudySpec, method: Method, setting: &Setting) -> FrameRequest {
    FrameRequest {
        width: spec.width,
        height: spec.height,
        dbuffer_size: setting.map_size(spec.dbuffer_size),
        method,
        vt: spec.vt,
        knobs: setting.knobs(),
        read_dbuffer: false,
        read_cost: false,
        colour_only: false,
    }
}

/// Run `spec` over `scenes` (loaded in its order) on `ctx`, with its cache in `out/cache`.
/// `progress` hears each stage and measurement and may stop the run (the cells measured so far
/// are kept and cached).
pub fn run(
    ctx: &GpuContext,
    spec: &StudySpec,
    scenes: &[Scene],
    out: &std::path::Path,
    progress: &mut dyn FnMut(Progress<'_>) -> Flow,
) -> Result<Study, RunError> {
    let started = Instant::now();
    let cache = Cache::new(out).map_err(|error| RunError::Cache {
        dir: out.join("cache").display().to_string(),
        error,
    })?;
    let machine = Machine::of(ctx);
    let binary = binary_id();
    let per_scene: usize = spec.methods.iter().map(|m| m.settings.len()).sum();
    let total = scenes.len() * (1 + 2 * per_scene);
    let mut done = 0;
    let mut stopped = false;
    let mut tick = |n: usize, progress: &mut dyn FnMut(Progress<'_>) -> Flow| {
        done += n;
        progress(Progress::Done { done, total }) == Flow::Stop
    };
    let mut study = Study {
        machine: machine.clone(),
        width: spec.width,
        height: spec.height,
        dbuffer_size: spec.dbuffer_size,
        vt: spec.vt.to_string(),
        warmup: spec.warmup,
        frames: spec.frames,
        quick: spec.quick,
        scenes: Vec::new(),
        measured: 0,
        cached: 0,
        seconds: 0.0,
        stopped: false,
    };
    'scenes: for scene in scenes {
        let name = scene.name.as_str();
        let base = format!(
            "{binary}|{}|{:016x}|{}x{}",
            machine.key(),
            scene_hash(scene),
            spec.width,
            spec.height
        );
        // Every cell of the scene, in registry order, with its cache keys.
        let mut cells = Vec::new();
        for sweep in &spec.methods {
            for setting in &sweep.settings {
                let req = request(spec, sweep.method, setting);
                let cell_key = format!(
                    "{base}|{}|{:?}|{}",
                    method_key(sweep.method),
                    req.knobs,
                    req.dbuffer_size
                );
                let not_measured = sweep
                    .method
                    .refusal(scene.light.kind(), Some(&ctx.caps))
                    .or_else(|| {
                        // The yardstick is not measured against itself.
                        (truth::is_soft(sweep.method) && req.knobs.get(&SAMPLES) >= spec.samples)
                            .then(|| format!("the study's reference is K = {}", spec.samples))
                    });
                cells.push((
                    Cell {
                        scene: name.to_string(),
                        method: sweep.method.name().to_string(),
                        setting: setting.label(),
                        values: setting
                            .values
                            .iter()
                            .map(|(q, v)| (q.name().to_string(), *v))
                            .collect(),
                        map_size: req.dbuffer_size,
                        error: None,
                        cost: None,
                        not_measured,
                        cached: false,
                    },
                    req,
                    format!("{cell_key}|K{}|{}", spec.samples, spec.vt),
                    format!("{cell_key}|w{}f{}", spec.warmup, spec.frames),
                ));
            }
        }
        // The reference and its noise floor.
        if progress(Progress::Stage {
            scene: name,
            stage: "ground truth",
        }) == Flow::Stop
        {
            stopped = true;
            break;
        }
        let reference_key = format!("{base}|K{}|{}", spec.samples, spec.vt);
        let pixels = spec.width as usize * spec.height as usize;
        let reference = match cache
            .get_bytes("truth", &reference_key)
            .and_then(|b| Reference::from_bytes(&b, pixels))
        {
            Some(r) => r,
            None => {
                let r = reference(ctx, spec, scene)?;
                cache
                    .put_bytes("truth", &reference_key, &r.to_bytes())
                    .map_err(|error| RunError::Cache {
                        dir: out.display().to_string(),
                        error,
                    })?;
                r
            }
        };
        if tick(1, progress) {
            stopped = true;
            break;
        }
        // Errors, one cell at a time, each cached as it is made.
        if progress(Progress::Stage {
            scene: name,
            stage: "errors",
        }) == Flow::Stop
        {
            stopped = true;
            break;
        }
        let mut session_of: Option<(Method, Session)> = None;
        for (cell, req, error_key, _) in &mut cells {
            if cell.not_measured.is_none() {
                if let Some(e) = cache.get::<CellError>("error", error_key) {
                    cell.error = Some(e);
                    cell.cached = true;
                } else {
                    if session_of.as_ref().is_none_or(|(m, _)| *m != req.method) {
                        session_of = Some((req.method, Session::new(ctx, scene.clone())));
                    }
                    let Some((_, session)) = session_of.as_mut() else {
                        continue;
                    };
                    match cell_error(ctx, session, req, &reference) {
                        Ok(e) => {
                            cell.error = Some(e);
                            let _ = cache.put("error", error_key, &e);
                        }
                        Err(e) => cell.not_measured = Some(e.to_string()),
                    }
                }
            }
            if tick(1, progress) {
                stopped = true;
                break;
            }
        }
        drop(session_of);
        // Costs, in batches of sessions timed together.
        if !stopped
            && progress(Progress::Stage {
                scene: name,
                stage: "costs",
            }) == Flow::Stop
        {
            stopped = true;
        }
        let mut pending = Vec::new();
        for (i, (cell, _, _, cost_key)) in cells.iter_mut().enumerate() {
            if cell.not_measured.is_some() {
                if !stopped && tick(1, progress) {
                    stopped = true;
                }
                continue;
            }
            match cache.get::<CellCost>("cost", cost_key) {
                Some(c) => {
                    cell.cost = Some(c);
                    if !stopped && tick(1, progress) {
                        stopped = true;
                    }
                }
                None => pending.push(i),
            }
        }
        for batch in pending.chunks(COST_BATCH) {
            if stopped {
                break;
            }
            let mut sessions: Vec<Session> = batch
                .iter()
                .map(|_| Session::new(ctx, scene.clone()))
                .collect();
            let requests: Vec<FrameRequest> = batch.iter().map(|&i| cells[i].1).collect();
            let timings = time_frames(
                ctx,
                &mut sessions,
                &requests,
                spec.warmup,
                spec.frames,
                Some(SLOW_FRAME_MS),
            );
            for (&i, timing) in batch.iter().zip(timings) {
                let (cell, req, _, cost_key) = &mut cells[i];
                match timing {
                    Ok(t) => {
                        let cost = cell_cost(req, t);
                        let _ = cache.put("cost", cost_key, &cost);
                        cell.cost = Some(cost);
                    }
                    Err(e) => cell.not_measured = Some(e),
                }
            }
            if tick(batch.len(), progress) {
                stopped = true;
            }
        }
        let light = scene.light.kind().to_string();
        study.scenes.push(SceneStudy {
            name: name.to_string(),
            light,
            caster_triangles: scene.caster_triangle_count(),
            reference_samples: spec.samples,
            noise_floor: reference.noise_floor,
            cells: cells.into_iter().map(|(c, ..)| c).collect(),
        });
        if stopped {
            break 'scenes;
        }
    }
    for s in &study.scenes {
        for c in &s.cells {
            if c.cached {
                study.cached += 1;
            } else if c.complete() {
                study.measured += 1;
            }
        }
    }
    study.stopped = stopped;
    study.seconds = started.elapsed().as_secs_f64();
    Ok(study)
}

/// The reference at the study's K, as `compare` renders it, with its counted pixels; its noise
/// floor against the same reference at 4K (at most the budget's K).
fn reference(ctx: &GpuContext, spec: &StudySpec, scene: &Scene) -> Result<Reference, RenderError> {
    let mut noop = |_: usize, _: usize| {};
    let at = |k: u32| FrameRequest {
        width: spec.width,
        height: spec.height,
        dbuffer_size: spec.dbuffer_size,
        method: truth::SOFT,
        vt: spec.vt,
        knobs: crate::render::Knobs::default().with(&SAMPLES, k),
        read_dbuffer: false,
        read_cost: false,
        colour_only: false,
    };
    let mut session = Session::new(ctx, scene.clone());
    let (frame, _) = render_in(ctx, &mut session, &at(spec.samples), &mut noop)?;
    let receivers = view::receivers(
        scene,
        &Bvh::build(scene.all_triangles()),
        spec.width,
        spec.height,
    );
    let mask = counted_pixels(&receivers, &frame);
    let finer = spec.samples.saturating_mul(4).min(SAMPLES.range().1);
    let noise_floor = if finer > spec.samples {
        let (fine, _) = render_in(ctx, &mut session, &at(finer), &mut noop)?;
        metrics::compare(&fine.visibility, &frame.visibility, &mask).penumbra_mae
    } else {
        0.0
    };
    Ok(Reference {
        rgb: rgb_of(&frame),
        visibility: frame.visibility,
        mask,
        noise_floor,
    })
}

/// One cell's frame against the reference, by `compare`'s metrics and FLIP.
fn cell_error(
    ctx: &GpuContext,
    session: &mut Session,
    request: &FrameRequest,
    reference: &Reference,
) -> Result<CellError, RenderError> {
    let mut noop = |_: usize, _: usize| {};
    let (frame, _) = render_in(ctx, session, request, &mut noop)?;
    let m = metrics::compare(&reference.visibility, &frame.visibility, &reference.mask);
    let map = flip::ldr_flip(
        &reference.rgb,
        &rgb_of(&frame),
        request.width,
        request.height,
        flip::DEFAULT_PPD,
    )
    .map_err(|e| RenderError::Request(e.to_string()))?;
    Ok(CellError::of(&m, flip::mean(&map)))
}

/// A cell's cost from its timing: the bench's frame figure; for the reference, K samples'
/// ray casting (one sample's, times K) and the frame.
fn cell_cost(request: &FrameRequest, timing: Timing) -> CellCost {
    let frame_ms = if truth::is_soft(request.method) {
        let k = f64::from(request.knobs.get(&SAMPLES));
        let rays = timing.rays_ms.map_or(0.0, |s: Stat| s.median);
        k * rays + timing.wall_ms.median
    } else {
        timing.frame_ms.median
    };
    CellCost { frame_ms, timing }
}
