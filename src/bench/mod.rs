//! `dbuffer bench`: the D-buffer paper's Table 1 reproduced (casters of 224, 960, 5760 and 1440 triangles at
//! 300², 600² and 1024²), every other method of [`Method::ALL`] timed in the same run as a ratio
//! to the D-buffer, the steady frame with the geometry cached and rebuilt every frame (Jakobsen et al.
//! 2004, §6.1), and the geometry stage from 1k to 1M caster triangles (docs/results/performance.md).
//!
//! Everything is measured through the same calls the lab makes: a [`Session`] per scene, one
//! [`FrameRequest`] per method. Frames are timed after warm-up ones (the first includes the
//! driver's shader compilation); each figure is the median (and minimum) of the steady frames.
//! Nothing here asserts a time: the report says what was measured and on which adapter.

pub mod plot;
pub mod table;

use std::time::Instant;

use glam::{Affine3A, Vec3};
use serde::{Deserialize, Serialize};

use crate::geometry::{PreparedCasters, VolumeParams, VtVariant};
use crate::render::methods::pcss;
use crate::render::passes::floor::Floor;
use crate::render::passes::view::{Mapping, View, ViewParams};
use crate::render::readback::map_now;
use crate::render::session::{FrameJob, Session};
use crate::render::timer::{PassTimer, Recorder};
use crate::render::{Frame, FrameRequest, FrameTargets, GpuContext, Knobs, Method};
use crate::scene::{self, shapes, Camera, DiskLight, Object, Scene, SceneError};

/// The Table 1 scenes of Jakobsen et al. 2004, in the paper's order.
pub const TABLE1_SCENES: [&str; 4] = ["table1-224", "table1-960", "table1-5760", "table1-1440"];

/// The scenes where occluders fuse (issue 12), timed by the full run after Table 1's.
pub const FUSION_SCENES: [&str; 3] = ["fusion-cross", "fusion-links", "fusion-many"];
/// The Table 1 image sizes (square).
pub const TABLE1_SIZES: [u32; 3] = [300, 600, 1024];
/// Caster triangle counts of the geometry-scaling curve (spheres, 4·n² triangles).
pub const SCALING_TRIANGLES: [u32; 6] = [1 << 10, 1 << 12, 1 << 14, 1 << 16, 1 << 18, 1 << 20];
/// Image size the targets of the issue are stated at.
pub const TARGET_SIZE: u32 = 1024;

/// What can stop a bench run. A method that cannot render is not one of them: its rows say why.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    // The cause is the source (printed after it by anyhow's chain), not repeated here.
    #[error("cannot load scene '{name}'")]
    Scene {
        name: String,
        #[source]
        source: Box<SceneError>,
    },
    #[error("{0}")]
    Config(String),
    #[error("drawing the scaling plot failed: {0}")]
    Plot(String),
}

/// One timed configuration of a method: the label it is reported under and its knobs.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    pub label: String,
    pub method: Method,
    pub knobs: Knobs,
}

impl Case {
    /// Every method of the registry, with the knobs its module names for the bench (PCSS with 16
    /// blocker and 32 filter taps, 16 light samples, the reference as a single
    /// 1-sample-per-pixel pass).
    pub fn all() -> Vec<Case> {
        Method::all()
            .iter()
            .copied()
            .map(Case::for_method)
            .collect()
    }

    /// The method as its [`MethodSpec::bench`](crate::render::methods::MethodSpec) says: its
    /// label and the knobs it sets, the others at their defaults.
    pub fn for_method(method: Method) -> Case {
        let bench = &method.spec().bench;
        let knobs = bench
            .knobs
            .iter()
            .fold(Knobs::default(), |k, &(knob, value)| k.with(knob, value));
        Case {
            label: bench.label.unwrap_or(method.name()).to_string(),
            method,
            knobs,
        }
    }

    /// Whether the method's per-frame work is done on the CPU (so only wall time measures it).
    pub fn cpu_side(&self) -> bool {
        self.method.cpu_side()
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct Config {
    pub quick: bool,
    pub scenes: Vec<String>,
    pub sizes: Vec<u32>,
    pub cases: Vec<Case>,
    /// Frames rendered and thrown away before timing, per (scene, size, method).
    pub warmup: usize,
    /// Frames timed per (scene, size, method).
    pub frames: usize,
    /// The D-buffer (and every shadow map) is this many texels square.
    pub dbuffer_size: u32,
    /// Runs of the geometry stage per Table 1 scene.
    pub geometry_runs: usize,
    /// Caster triangle counts of the scaling curve; empty for none.
    pub scaling: Vec<u32>,
    /// Runs of the geometry stage per scaling point.
    pub scaling_runs: usize,
    /// Time the steady frame with the geometry cached and rebuilt every frame.
    pub coherence: bool,
}

impl Config {
    /// The full run: Table 1's scenes and the fusion scenes, 3 warm-up and 15 timed frames,
    /// scaling up to 1M triangles.
    pub fn full() -> Config {
        Config {
            quick: false,
            scenes: TABLE1_SCENES
                .iter()
                .chain(&FUSION_SCENES)
                .map(|s| s.to_string())
                .collect(),
            sizes: TABLE1_SIZES.to_vec(),
            cases: Case::all(),
            warmup: 3,
            frames: 15,
            dbuffer_size: 1024,
            geometry_runs: 31,
            scaling: SCALING_TRIANGLES.to_vec(),
            scaling_runs: 7,
            coherence: true,
        }
    }

    /// Every row of the full run with fewer frames, scaling up to 256k triangles: under two
    /// minutes on a 2-core CPU adapter.
    pub fn quick() -> Config {
        Config {
            quick: true,
            warmup: 1,
            frames: 3,
            geometry_runs: 11,
            scaling: SCALING_TRIANGLES[..5].to_vec(),
            scaling_runs: 3,
            scenes: TABLE1_SCENES.iter().map(|s| s.to_string()).collect(),
            ..Config::full()
        }
    }

    pub fn validate(&self) -> Result<(), BenchError> {
        let bad = |m: String| Err(BenchError::Config(m));
        if self.scenes.is_empty() {
            return bad("no scene to bench".into());
        }
        if self.sizes.is_empty() {
            return bad("no image size to bench".into());
        }
        if let Some(s) = self.sizes.iter().find(|s| !(8..=8192).contains(*s)) {
            return bad(format!("image size {s}: expected 8 to 8192 pixels"));
        }
        if !(1..=8192).contains(&self.dbuffer_size) {
            return bad(format!(
                "D-buffer size {}: expected 1 to 8192 texels",
                self.dbuffer_size
            ));
        }
        if self.frames == 0 || self.frames > 10_000 {
            return bad(format!("{} timed frames: expected 1 to 10000", self.frames));
        }
        if self.warmup > 1000 {
            return bad(format!(
                "{} warm-up frames: expected 0 to 1000",
                self.warmup
            ));
        }
        if let Some(t) = self.scaling.iter().find(|t| !(64..=4_000_000).contains(*t)) {
            return bad(format!(
                "scaling point of {t} triangles: expected 64 to 4000000"
            ));
        }
        for case in &self.cases {
            case.knobs
                .validate()
                .map_err(|e| BenchError::Config(format!("{}: {e}", case.label)))?;
        }
        Ok(())
    }

    /// A rough run time in seconds on a 2-core CPU adapter (lavapipe), for the progress line.
    pub fn estimate_s(&self) -> f64 {
        let per_frame: f64 = self
            .sizes
            .iter()
            .map(|&s| 0.03 + 1.0e-7 * f64::from(s) * f64::from(s))
            .sum::<f64>()
            * 2.2;
        let frames = (self.warmup + self.frames) as f64;
        let render = self.scenes.len() as f64 * self.cases.len() as f64 * frames * per_frame;
        let scaling: f64 = self
            .scaling
            .iter()
            .map(|&t| f64::from(t) * (0.3e-6 + 0.03e-6 * self.scaling_runs as f64))
            .sum();
        render + scaling + 2.0 * self.scenes.len() as f64
    }
}

/// Median and minimum of a set of timings, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stat {
    pub median: f64,
    pub min: f64,
}

impl Stat {
    /// `None` for no samples.
    pub fn of(samples: &[f64]) -> Option<Stat> {
        let mut v: Vec<f64> = samples.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        Some(Stat { median, min: v[0] })
    }
}

/// Where a frame's figure comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameSource {
    /// The sum of the passes' GPU timestamp queries.
    GpuTimestamps,
    /// Wall time of the whole frame, fenced by the readback (the adapter has no timestamp
    /// queries, or the method works on the CPU).
    FencedWall,
}

/// One pass's GPU time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PassTime {
    pub pass: String,
    pub ms: Stat,
}

/// The steady frames of one (scene, size, method).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// The figure ratios and fps are taken from, and where it comes from.
    pub frame_ms: Stat,
    pub frame_source: FrameSource,
    pub fps: f64,
    /// GPU ms per pass (timestamp queries); empty without them.
    pub passes: Vec<PassTime>,
    /// Sum of the passes, per frame.
    pub gpu_total_ms: Option<Stat>,
    /// Sum of the light-space passes (every pass but the camera pass), per frame.
    #[serde(default)]
    pub light_ms: Option<Stat>,
    /// `Session::frame` wall time: encoding, the GPU, the readback of the camera targets.
    pub wall_ms: Stat,
    /// Pixels of the image that hit a surface.
    pub hit_pixels: usize,
    /// The reference only: one more sample per pixel without rendering a frame
    /// (`Session::advance_reference`), i.e. the ray casting alone.
    #[serde(default)]
    pub rays_ms: Option<Stat>,
}

impl Timing {
    pub fn pass(&self, name: &str) -> Option<Stat> {
        self.passes.iter().find(|p| p.pass == name).map(|p| p.ms)
    }

    /// The frame figure measured the way `source` says (wall time is always there).
    pub fn frame_by(&self, source: FrameSource) -> Option<Stat> {
        match source {
            FrameSource::GpuTimestamps => self.gpu_total_ms,
            FrameSource::FencedWall => Some(self.wall_ms),
        }
    }
}

/// One (scene, size, method): its timings, or why the method did not render.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Run {
    pub scene: String,
    pub size: u32,
    /// The case's label, e.g. "pcss 16/32".
    pub label: String,
    /// The method's command-line name.
    pub method: String,
    pub timing: Option<Timing>,
    pub error: Option<String>,
    /// For a method that counts volumes in the stencil: volume fragments per pixel of its last
    /// frame (`Session::stencil_fill`), the fill rate it pays.
    #[serde(default)]
    pub fill: Option<f64>,
}

/// A Table 1 scene and its geometry stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneInfo {
    pub name: String,
    pub caster_triangles: usize,
    /// Welding and adjacency, once per mesh.
    pub prepare_ms: f64,
    /// Classes, silhouettes and volumes for the scene's light (per light move).
    pub geometry_ms: Stat,
    pub umbra_triangles: usize,
    pub penumbra_triangles: usize,
}

/// The steady frame with the geometry cached against rebuilt every frame (Jakobsen et al. 2004, §6.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Coherence {
    pub scene: String,
    pub size: u32,
    /// How "rebuilt" was forced.
    pub rebuild_by: String,
    pub cached_wall_ms: Stat,
    pub rebuilt_wall_ms: Stat,
    pub cached_gpu_ms: Option<Stat>,
    pub rebuilt_gpu_ms: Option<Stat>,
    /// The geometry stage inside the rebuilt frames (`Session::geometry_ms`).
    pub rebuilt_geometry_ms: Option<Stat>,
    /// Geometry builds during the timed rebuilt frames (one per frame when it worked).
    pub rebuilds: u64,
    /// Timed frames of each kind (cached and rebuilt alternate).
    pub frames: usize,
}

/// One point of the geometry-scaling curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScalingPoint {
    pub triangles: usize,
    /// Welding and adjacency (once per mesh).
    pub prepare_ms: f64,
    /// Classes, silhouettes and volumes (per light move).
    pub build_ms: Stat,
    pub volume_triangles: usize,
}

/// A target of the issue, measured (or a figure it asks the report to give).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Target {
    pub name: String,
    /// The measured ratio or time; `None` where it could not be measured.
    pub measured: Option<f64>,
    /// Pass when `measured <= limit` (`< limit` when `strict`, `>= limit` when `at_least`);
    /// `None`: a figure to report, not a target.
    pub limit: Option<f64>,
    pub strict: bool,
    #[serde(default)]
    pub at_least: bool,
    pub unit: String,
    /// Where the figure comes from (the worst scene, the size).
    pub detail: String,
}

impl Target {
    pub fn pass(&self) -> Option<bool> {
        let (m, limit) = (self.measured?, self.limit?);
        Some(if self.at_least {
            m >= limit
        } else if self.strict {
            m < limit
        } else {
            m <= limit
        })
    }
}

/// The display path against the readback path on one scene and size (the D-buffer).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DisplayRun {
    pub scene: String,
    pub size: u32,
    /// The scene in flat colour into Rgba8 + depth: the cheapest image of it (GPU).
    pub floor_gpu_ms: Option<Stat>,
    /// The lab's frame, headless: camera pass and view pass into the display texture, fenced
    /// (the D-buffer cached: a still light).
    pub lab_still: Display,
    /// The same with the light moved before every frame: geometry, light pass, camera, view.
    pub lab_moving: Display,
    /// `Session::frame` as `dbuffer render` uses it: the camera targets and the D-buffer read
    /// back (what the lab did every frame before), light still.
    pub readback: Display,
}

/// Wall and GPU time of one kind of frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Display {
    pub wall_ms: Stat,
    pub gpu_ms: Option<Stat>,
}

/// The whole run, as written to `bench.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// The adapter's name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub adapter: String,
    pub backend: String,
    pub device_type: String,
    pub timestamps: bool,
    /// The CPU model and core count.
    pub host: String,
    pub quick: bool,
    pub warmup: usize,
    pub frames: usize,
    pub dbuffer_size: u32,
    /// Seconds since the Unix epoch when the run ended.
    pub unix_time: u64,
    pub seconds: f64,
    pub scenes: Vec<SceneInfo>,
    pub runs: Vec<Run>,
    /// The display path, per scene and size.
    #[serde(default)]
    pub display: Vec<DisplayRun>,
    pub coherence: Option<Coherence>,
    pub scaling: Vec<ScalingPoint>,
    /// Shadow rays per second of the 1-spp reference frames (their whole wall time).
    pub reference_rays_per_s: Option<f64>,
    pub targets: Vec<Target>,
}

impl Report {
    pub fn run(&self, scene: &str, size: u32, method: Method) -> Option<&Run> {
        self.runs
            .iter()
            .find(|r| r.scene == scene && r.size == size && r.method == method.name())
    }

    pub fn timing(&self, scene: &str, size: u32, method: Method) -> Option<&Timing> {
        self.run(scene, size, method)?.timing.as_ref()
    }

    /// `method`'s frame over the D-buffer's, the same scene and size, measured alike.
    pub fn ratio_to_dbuffer(&self, scene: &str, size: u32, method: Method) -> Option<f64> {
        self.ratio_to(scene, size, method, Method::DBUFFER)
    }

    /// `method`'s frame over `base`'s, the same scene and size, measured alike.
    pub fn ratio_to(&self, scene: &str, size: u32, method: Method, base: Method) -> Option<f64> {
        let m = self.timing(scene, size, method)?;
        let d = self.timing(scene, size, base)?;
        let base = d.frame_by(m.frame_source)?.median;
        (base > 0.0).then(|| m.frame_ms.median / base)
    }

    pub fn sizes(&self) -> Vec<u32> {
        let mut sizes: Vec<u32> = self.runs.iter().map(|r| r.size).collect();
        sizes.sort_unstable();
        sizes.dedup();
        sizes
    }

    /// The case labels in the order they ran.
    pub fn labels(&self) -> Vec<(String, String)> {
        let mut out: Vec<(String, String)> = Vec::new();
        for r in &self.runs {
            if !out.iter().any(|(l, _)| *l == r.label) {
                out.push((r.label.clone(), r.method.clone()));
            }
        }
        out
    }
}

/// What the run reports as it goes (for a progress line on stderr).
pub type Progress<'a> = &'a mut dyn FnMut(&str);

/// Load the scenes `config` names, in order (before any GPU work: a bad name fails first).
pub fn load_scenes(config: &Config) -> Result<Vec<Scene>, BenchError> {
    config
        .scenes
        .iter()
        .map(|name| {
            scene::load(name).map_err(|source| BenchError::Scene {
                name: name.clone(),
                source: Box::new(source),
            })
        })
        .collect()
}

/// Run the bench on `ctx` over `loaded`, the scenes of [`load_scenes`].
pub fn run(
    ctx: &GpuContext,
    config: &Config,
    loaded: Vec<Scene>,
    progress: Progress,
) -> Result<Report, BenchError> {
    config.validate()?;
    let started = Instant::now();
    let mut scenes = Vec::new();
    for scene in &loaded {
        let name = &scene.name;
        progress(&format!("geometry  {name}"));
        scenes.push(scene_info(scene, config.geometry_runs));
    }

    let total = loaded.len() * config.sizes.len();
    let mut runs = Vec::with_capacity(total * config.cases.len());
    let mut display = Vec::new();
    let mut done = 0;
    for scene in &loaded {
        // One session per method, so no method pays for another's targets or volumes.
        let mut sessions: Vec<Session> = config
            .cases
            .iter()
            .map(|case| Session::new(ctx, scene_for(case.method, scene)))
            .collect();
        // Cases timed under the other kind of light (see `scene_for`) say so in their label.
        let converted: Vec<bool> = sessions
            .iter()
            .map(|s| s.scene().light.kind() != scene.light.kind())
            .collect();
        for &size in &config.sizes {
            progress(&format!(
                "display   {} {size}²: lab frame, readback path, floor",
                scene.name
            ));
            display.push(time_display(ctx, scene, config, size));
            let elapsed = started.elapsed().as_secs_f64();
            let eta = if done == 0 {
                String::new()
            } else {
                let left = elapsed / done as f64 * (total - done) as f64;
                format!(", ~{left:.0} s of frames left")
            };
            progress(&format!(
                "[{}/{total}] {} {size}²: {} methods, {} frames each, interleaved{eta}",
                done + 1,
                scene.name,
                config.cases.len(),
                config.warmup + config.frames,
            ));
            runs.extend(time_size(ctx, &mut sessions, &converted, config, size));
            done += 1;
        }
    }

    let coherence = if config.coherence {
        let name = config
            .scenes
            .iter()
            .position(|s| s == "table1-5760")
            .unwrap_or(config.scenes.len() - 1);
        let size = config
            .sizes
            .iter()
            .copied()
            .max()
            .unwrap_or(TABLE1_SIZES[1]);
        let scene = &loaded[name.min(loaded.len() - 1)];
        progress(&format!(
            "coherence {} {size}²: geometry cached, then rebuilt every frame",
            scene.name
        ));
        Some(coherence(ctx, scene, config, size))
    } else {
        None
    };

    let mut scaling = Vec::new();
    for &t in &config.scaling {
        progress(&format!("scaling   geometry of a {t}-triangle sphere"));
        scaling.push(scaling_point(t, config.scaling_runs));
    }

    let reference_rays_per_s = reference_throughput(&runs);
    let mut report = Report {
        adapter: ctx.adapter.name.clone(),
        backend: format!("{:?}", ctx.adapter.backend),
        device_type: format!("{:?}", ctx.adapter.device_type),
        timestamps: ctx.timestamps,
        host: host_description(),
        quick: config.quick,
        warmup: config.warmup,
        frames: config.frames,
        dbuffer_size: config.dbuffer_size,
        unix_time: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs())
            .unwrap_or(0),
        seconds: 0.0,
        scenes,
        runs,
        display,
        coherence,
        scaling,
        reference_rays_per_s,
        targets: Vec::new(),
    };
    report.targets = targets(&report);
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The scene's caster count and its geometry stage: prepared once, built `runs` times.
fn scene_info(scene: &Scene, runs: usize) -> SceneInfo {
    let t = Instant::now();
    let prepared = PreparedCasters::new(scene);
    let prepare_ms = ms_since(t);
    let params = VolumeParams::for_scene(scene);
    let mut samples = Vec::with_capacity(runs);
    let mut last = None;
    // The geometry stage is the D-buffer's: a disk light's (none for a line light).
    for light in std::iter::repeat_n(scene.light.as_disk(), runs.max(1)).flatten() {
        let t = Instant::now();
        let g = prepared.build(light, &params);
        samples.push(ms_since(t));
        last = Some(std::hint::black_box(g));
    }
    let stats = last.map(|g| g.stats).unwrap_or_default();
    SceneInfo {
        name: scene.name.clone(),
        caster_triangles: scene.caster_triangle_count(),
        prepare_ms,
        geometry_ms: Stat::of(&samples).unwrap_or_default(),
        umbra_triangles: stats.umbra_triangles,
        penumbra_triangles: stats.penumbra_triangles,
    }
}

fn request(config: &Config, size: u32, case: &Case) -> FrameRequest {
    FrameRequest {
        width: size,
        height: size,
        dbuffer_size: config.dbuffer_size,
        method: case.method,
        vt: VtVariant::Smoothstep,
        knobs: case.knobs,
        read_dbuffer: false,
    }
}

/// Sum of a frame's GPU passes, or `None` without timestamps.
fn gpu_total(gpu_ms: &[(String, f64)]) -> Option<f64> {
    (!gpu_ms.is_empty()).then(|| gpu_ms.iter().map(|(_, ms)| ms).sum())
}

/// The light-space passes of a frame: every pass but the camera pass.
fn light_total(gpu_ms: &[(String, f64)]) -> Option<f64> {
    let light: Vec<f64> = gpu_ms
        .iter()
        .filter(|(p, _)| p != "camera_pass")
        .map(|(_, ms)| *ms)
        .collect();
    (!light.is_empty()).then(|| light.iter().sum())
}

/// The frames of one method at one size, as they come in.
#[derive(Default)]
struct Samples {
    wall: Vec<f64>,
    totals: Vec<f64>,
    light: Vec<f64>,
    passes: Vec<(String, Vec<f64>)>,
    hit_pixels: usize,
    rays: Vec<f64>,
}

impl Samples {
    fn add(&mut self, frame: &Frame, wall_ms: f64) {
        self.wall.push(wall_ms);
        self.totals.extend(gpu_total(&frame.gpu_ms));
        self.light.extend(light_total(&frame.gpu_ms));
        for (pass, ms) in &frame.gpu_ms {
            match self.passes.iter_mut().find(|(p, _)| p == pass) {
                Some((_, v)) => v.push(*ms),
                None => self.passes.push((pass.clone(), vec![*ms])),
            }
        }
        self.hit_pixels = (0..frame.len()).filter(|&i| frame.hit(i)).count();
    }

    fn timing(self, case: &Case) -> Timing {
        let wall_ms = Stat::of(&self.wall).unwrap_or_default();
        let gpu_total_ms = Stat::of(&self.totals);
        let (frame_ms, frame_source) = match gpu_total_ms {
            Some(g) if !case.cpu_side() => (g, FrameSource::GpuTimestamps),
            _ => (wall_ms, FrameSource::FencedWall),
        };
        Timing {
            fps: if frame_ms.median > 0.0 {
                1e3 / frame_ms.median
            } else {
                0.0
            },
            frame_ms,
            frame_source,
            passes: self
                .passes
                .into_iter()
                .filter_map(|(pass, v)| {
                    Some(PassTime {
                        pass,
                        ms: Stat::of(&v)?,
                    })
                })
                .collect(),
            gpu_total_ms,
            light_ms: Stat::of(&self.light),
            wall_ms,
            hit_pixels: self.hit_pixels,
            rays_ms: Stat::of(&self.rays),
        }
    }
}

/// Every method at one size: warm-up frames, then `config.frames` rounds of one frame per
/// method, so a machine whose speed drifts (a shared CPU adapter) slows every method alike.
/// Every timed frame makes its light-space maps again (`Session::invalidate_light_maps`): Table 1
/// times the whole frame, light pass and camera pass. `sessions[i]` renders `config.cases[i]`; a
/// method that fails is dropped from the rounds and its row says why.
/// The scene `method` is timed on: `scene` itself, or, for a method that refuses its light, the
/// same scene under the light converted to the kind the method takes (`Light::converted`: a
/// disk's diameter as a segment, a segment's length as a disk), so every method of the registry
/// has a frame on the same casters at the same size to compare with the D-buffer's.
pub fn scene_for(method: Method, scene: &Scene) -> Scene {
    match method.needs() {
        Some(kind) if kind != scene.light.kind() => Scene {
            light: scene.light.converted(kind),
            ..scene.clone()
        },
        _ => scene.clone(),
    }
}

fn time_size(
    ctx: &GpuContext,
    sessions: &mut [Session],
    converted: &[bool],
    config: &Config,
    size: u32,
) -> Vec<Run> {
    let requests: Vec<FrameRequest> = config
        .cases
        .iter()
        .map(|case| request(config, size, case))
        .collect();
    let mut errors: Vec<Option<String>> = vec![None; config.cases.len()];
    let mut samples: Vec<Samples> = config.cases.iter().map(|_| Samples::default()).collect();
    for round in 0..config.warmup + config.frames {
        for (i, session) in sessions.iter_mut().enumerate() {
            if errors[i].is_some() {
                continue;
            }
            session.invalidate_light_maps();
            let t = Instant::now();
            let frame = if config.cases[i].method.is_reference() {
                // The reference: one more sample per pixel, then its frame (reference-hard, also
                // CPU-side, casts its rays again in the frame: its image was invalidated).
                session
                    .advance_reference(ctx, &requests[i], 1)
                    .and_then(|_| session.frame(ctx, &requests[i]))
            } else {
                session.frame(ctx, &requests[i])
            };
            match frame {
                Ok(frame) if round >= config.warmup => samples[i].add(&frame, ms_since(t)),
                Ok(_) => {}
                Err(e) => errors[i] = Some(e.to_string()),
            }
        }
    }
    // The reference's ray casting alone: one more sample per pixel without a frame.
    for (i, case) in config.cases.iter().enumerate() {
        if !case.method.is_reference() || errors[i].is_some() {
            continue;
        }
        for _ in 0..config.frames {
            let t = Instant::now();
            if sessions[i].advance_reference(ctx, &requests[i], 1).is_err() {
                break;
            }
            samples[i].rays.push(ms_since(t));
        }
    }
    config
        .cases
        .iter()
        .zip(sessions.iter().zip(converted))
        .zip(samples.into_iter().zip(errors))
        .map(|((case, (session, &converted)), (samples, error))| Run {
            scene: session.scene().name.clone(),
            size,
            label: if converted {
                format!("{} ({} light)", case.label, session.scene().light.kind())
            } else {
                case.label.clone()
            },
            method: case.method.name().to_string(),
            timing: error.is_none().then(|| samples.timing(case)),
            fill: error
                .is_none()
                .then(|| session.stencil_fill(ctx, case.method)?.ok())
                .flatten(),
            error,
        })
        .collect()
}

/// The lab's display path headless (light still and light moving), the readback path
/// `dbuffer render` takes, and the floor, on one scene and size, interleaved frame by frame.
fn time_display(ctx: &GpuContext, scene: &Scene, config: &Config, size: u32) -> DisplayRun {
    let mut session = Session::new(ctx, scene.clone());
    let req = request(config, size, &Case::for_method(Method::DBUFFER));
    let view = ViewParams {
        view: View::Final,
        channels: [true, false, false, false],
        mapping: Mapping::unit(),
    };
    let mut targets = FrameTargets::new();
    let base = scene.light;
    let mut nudge = 0u32;
    let mut lab = |session: &mut Session, targets: &mut FrameTargets, moving: bool| {
        if moving {
            // The light a centimetre to one side or the other: everything light-space is redone.
            nudge += 1;
            let dx = if nudge.is_multiple_of(2) { 0.01 } else { -0.01 };
            session.set_light(base.with_center(base.center() + Vec3::new(dx, 0.0, 0.0)));
        }
        let t = Instant::now();
        let job = FrameJob {
            targets,
            request: req,
            view: Some(view),
            render: true,
            probes: Vec::new(),
        };
        session.submit(ctx, &mut [job]).ok()?;
        map_now(&ctx.device).ok()?;
        let wall = ms_since(t);
        let gpu = session.poll_timings(ctx).as_deref().and_then(gpu_total);
        Some((wall, gpu))
    };
    let mut floor = Floor::new(ctx);
    let timer = PassTimer::new(ctx);
    let mut timer = timer;
    let mut floor_frame = |session: &Session| -> Option<f64> {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("floor"),
            });
        {
            let mut rec = Recorder::new(&mut encoder, timer.as_ref());
            floor.record(
                ctx,
                &mut rec,
                session.scene(),
                session.surfaces(),
                (size, size),
            );
        }
        let t = timer.as_mut()?;
        t.finish(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        t.request_maps();
        gpu_total(&t.wait(ctx).ok()?)
    };
    let (mut still, mut moving, mut readback, mut floors) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let readback_req = FrameRequest {
        read_dbuffer: true,
        ..req
    };
    session.set_light(base);
    for round in 0..config.warmup + config.frames {
        let timed = round >= config.warmup;
        let s = lab(&mut session, &mut targets, false);
        let m = lab(&mut session, &mut targets, true);
        session.set_light(base);
        // The readback path with the D-buffer cached, as the lab had it with a still light.
        let _ = session.frame(ctx, &readback_req);
        let t = Instant::now();
        let r = session
            .frame(ctx, &readback_req)
            .ok()
            .map(|f| (ms_since(t), gpu_total(&f.gpu_ms)));
        let f = floor_frame(&session);
        if timed {
            still.extend(s);
            moving.extend(m);
            readback.extend(r);
            floors.extend(f);
        }
    }
    let display = |v: &[(f64, Option<f64>)]| Display {
        wall_ms: Stat::of(&v.iter().map(|x| x.0).collect::<Vec<_>>()).unwrap_or_default(),
        gpu_ms: Stat::of(&v.iter().filter_map(|x| x.1).collect::<Vec<_>>()),
    };
    DisplayRun {
        scene: scene.name.clone(),
        size,
        floor_gpu_ms: Stat::of(&floors),
        lab_still: display(&still),
        lab_moving: display(&moving),
        readback: display(&readback),
    }
}

/// The D-buffer's steady frame with the geometry cached, then with the geometry invalidated before
/// every frame (`Session::invalidate_geometry`: what a light dragged every frame costs).
fn coherence(ctx: &GpuContext, scene: &Scene, config: &Config, size: u32) -> Coherence {
    let mut session = Session::new(ctx, scene.clone());
    let req = request(config, size, &Case::for_method(Method::DBUFFER));
    let frames = config.frames.max(3);
    // Cached and rebuilt frames alternate, so both see the same machine (a shared CPU adapter
    // drifts more over a run than the geometry stage costs).
    let (mut cached_wall, mut cached_gpu) = (Vec::new(), Vec::new());
    let (mut rebuilt_wall, mut rebuilt_gpu, mut geometry) = (Vec::new(), Vec::new(), Vec::new());
    let mut rebuilds = 0;
    for i in 0..2 * (config.warmup + frames) {
        let rebuild = i % 2 == 1;
        let (before, _) = session.geometry_builds(Method::DBUFFER);
        if rebuild {
            session.invalidate_geometry();
        } else {
            session.invalidate_light_maps();
        }
        let t = Instant::now();
        let Ok(frame) = session.frame(ctx, &req) else {
            continue;
        };
        let ms = ms_since(t);
        let (after, geometry_ms) = session.geometry_builds(Method::DBUFFER);
        if i < 2 * config.warmup {
            continue;
        }
        let gpu = gpu_total(&frame.gpu_ms);
        if rebuild {
            rebuilds += after - before;
            rebuilt_wall.push(ms);
            rebuilt_gpu.extend(gpu);
            geometry.push(geometry_ms);
        } else {
            cached_wall.push(ms);
            cached_gpu.extend(gpu);
        }
    }
    Coherence {
        scene: scene.name.clone(),
        size,
        rebuild_by: "Session::invalidate_geometry() before every frame".into(),
        cached_wall_ms: Stat::of(&cached_wall).unwrap_or_default(),
        rebuilt_wall_ms: Stat::of(&rebuilt_wall).unwrap_or_default(),
        cached_gpu_ms: Stat::of(&cached_gpu),
        rebuilt_gpu_ms: Stat::of(&rebuilt_gpu),
        rebuilt_geometry_ms: Stat::of(&geometry),
        rebuilds,
        frames,
    }
}

/// A UV sphere of about `triangles` triangles (4·n², n = √(t/4) rounded) under a tilted light,
/// alone in a scene.
pub fn scaling_scene(triangles: u32) -> Scene {
    let n = ((f64::from(triangles) / 4.0).sqrt().round() as u32).max(2);
    let mesh = shapes::sphere(2 * n, n + 1)
        .transformed(&Affine3A::from_translation(Vec3::new(0.0, 1.5, 0.0)));
    Scene {
        name: format!("sphere-{}", mesh.triangles.len()),
        camera: Camera {
            eye: Vec3::new(0.0, 3.0, 6.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            fov_y_deg: 45.0,
        },
        light: DiskLight {
            center: Vec3::new(0.3, 4.0, -0.2),
            normal: Vec3::new(0.1, -1.0, 0.05).normalize(),
            radius: 0.6,
            intensity: 1.0,
        }
        .into(),
        objects: vec![Object {
            name: "sphere".into(),
            mesh,
            casts_shadow: true,
        }],
    }
}

fn scaling_point(triangles: u32, runs: usize) -> ScalingPoint {
    let scene = scaling_scene(triangles);
    let t = Instant::now();
    let prepared = PreparedCasters::new(&scene);
    let prepare_ms = ms_since(t);
    let params = VolumeParams::for_scene(&scene);
    let mut samples = Vec::new();
    let mut volume_triangles = 0;
    for light in std::iter::repeat_n(scene.light.as_disk(), runs.max(1)).flatten() {
        let t = Instant::now();
        let g = prepared.build(light, &params);
        samples.push(ms_since(t));
        volume_triangles = g.stats.umbra_triangles + g.stats.penumbra_triangles;
        drop(std::hint::black_box(g));
    }
    ScalingPoint {
        triangles: scene.caster_triangle_count(),
        prepare_ms,
        build_ms: Stat::of(&samples).unwrap_or_default(),
        volume_triangles,
    }
}

/// Shadow rays per second of the reference: one ray per hit pixel per 1-spp step of
/// `Session::advance_reference` (surfaces facing away from the light may cast none, so this is a
/// lower bound), the median over the runs.
fn reference_throughput(runs: &[Run]) -> Option<f64> {
    let rates: Vec<f64> = runs
        .iter()
        .filter(|r| r.method == Method::REFERENCE.name())
        .filter_map(|r| r.timing.as_ref())
        .filter_map(|t| Some((t.hit_pixels, t.rays_ms?.median)))
        .filter(|&(px, ms)| ms > 0.0 && px > 0)
        .map(|(px, ms)| px as f64 / (ms * 1e-3))
        .collect();
    Stat::of(&rates).map(|s| s.median)
}

/// The targets, measured on the worst Table 1 scene at 1024² (or the largest size run).
pub fn targets(report: &Report) -> Vec<Target> {
    let size = if report.sizes().contains(&TARGET_SIZE) {
        TARGET_SIZE
    } else {
        report.sizes().last().copied().unwrap_or(TARGET_SIZE)
    };
    // The targets are the Table 1 scenes' where the run has any (other scenes, such as the
    // fusion ones, are in the tables but not in the targets).
    let table1 = report
        .scenes
        .iter()
        .any(|s| TABLE1_SCENES.contains(&s.name.as_str()));
    let judged = || {
        report
            .scenes
            .iter()
            .filter(move |s| !table1 || TABLE1_SCENES.contains(&s.name.as_str()))
    };
    let worst = |f: &dyn Fn(&str) -> Option<f64>| -> (Option<f64>, String) {
        let mut best: Option<(f64, &str)> = None;
        let mut all = Vec::new();
        let mut missing = Vec::new();
        for s in judged() {
            match f(&s.name) {
                Some(v) => {
                    all.push(v);
                    if best.is_none_or(|(b, _)| v > b) {
                        best = Some((v, &s.name));
                    }
                }
                None => missing.push(s.name.as_str()),
            }
        }
        let median = Stat::of(&all).map_or(f64::NAN, |s| s.median);
        match best {
            Some((v, name)) => {
                let mut detail =
                    format!("worst scene {name} at {size}² (median over scenes {median:.2})");
                if !missing.is_empty() {
                    detail += &format!("; not measured on {}", missing.join(", "));
                }
                (Some(v), detail)
            }
            None => (None, format!("not measured at {size}²")),
        }
    };
    let ratio = |a: Option<Stat>, b: Option<Stat>| {
        let (a, b) = (a?.median, b?.median);
        (b > 0.0).then(|| a / b)
    };
    let dbuffer = |s: &str| report.timing(s, size, Method::DBUFFER);
    let hard = |s: &str| report.timing(s, size, Method::HARD);
    let frame = worst(&|s| {
        let (d, h) = (dbuffer(s)?, hard(s)?);
        ratio(Some(d.frame_ms), h.frame_by(d.frame_source))
    });
    let light = worst(&|s| ratio(dbuffer(s)?.light_ms, hard(s)?.light_ms));
    let camera_hard = worst(&|s| {
        ratio(
            dbuffer(s)?.pass("camera_pass"),
            hard(s)?.pass("camera_pass"),
        )
    });
    let camera_pcss = worst(&|s| {
        let p = report.timing(s, size, Method::of(&pcss::PCSS)?)?;
        ratio(dbuffer(s)?.pass("camera_pass"), p.pass("camera_pass"))
    });
    let display = |s: &str, sz: u32| report.display.iter().find(|d| d.scene == s && d.size == sz);
    let lab = worst(&|s| {
        let d = display(s, size)?;
        ratio(Some(d.lab_still.wall_ms), Some(d.readback.wall_ms))
    });
    let floor = worst(&|s| {
        let d = dbuffer(s)?;
        ratio(d.gpu_total_ms, display(s, size)?.floor_gpu_ms)
    });
    let moving = display("table1-960", 600).map(|d| {
        let ms = d.lab_moving.wall_ms.median;
        (ms > 0.0).then(|| 1e3 / ms)
    });
    let geometry = report
        .scenes
        .iter()
        .find(|s| s.caster_triangles == 5760)
        .map(|s| (s.geometry_ms.median, format!("{} (CPU)", s.name)));
    let at_most = |name: &str, (measured, detail): (Option<f64>, String), limit: f64| Target {
        name: name.into(),
        measured,
        limit: Some(limit),
        strict: false,
        at_least: false,
        unit: "×".into(),
        detail,
    };
    vec![
        at_most("lab frame (light still) / readback path", lab, 0.6),
        Target {
            name: "lab frame fps, light moving, table1-960 at 600²".into(),
            measured: moving.flatten(),
            limit: Some(30.0),
            strict: false,
            at_least: true,
            unit: "fps".into(),
            detail: "wall time of geometry, light pass and camera pass (the final image), fenced"
                .into(),
        },
        at_most("D-buffer light pass / hard-shadow light pass", light, 1.5),
        at_most(
            "D-buffer camera pass / hard-shadow camera pass",
            camera_hard,
            1.05,
        ),
        at_most("D-buffer frame / hard-shadow frame", frame, 1.5),
        Target {
            strict: true,
            ..at_most("D-buffer camera pass / PCSS camera pass", camera_pcss, 1.0)
        },
        Target {
            limit: None,
            ..at_most("D-buffer frame / floor (flat colour + depth)", floor, 0.0)
        },
        Target {
            name: "geometry of the 5760-triangle caster".into(),
            measured: geometry.as_ref().map(|g| g.0),
            limit: Some(1.0),
            strict: true,
            at_least: false,
            unit: "ms".into(),
            detail: geometry.map_or_else(|| "table1-5760 not run".into(), |g| g.1),
        },
    ]
}

/// "AMD EPYC 7B13, 2 cores" from /proc/cpuinfo where there is one.
fn host_description() -> String {
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, m)| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    format!("{model}, {cores} cores")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::methods::reference::{MAX_SAMPLES, SAMPLES};

    #[test]
    fn stat_median_and_min() {
        let s = Stat::of(&[3.0, 1.0, 2.0]).unwrap();
        assert_eq!((s.median, s.min), (2.0, 1.0));
        let s = Stat::of(&[4.0, 1.0, 2.0, 3.0]).unwrap();
        assert_eq!((s.median, s.min), (2.5, 1.0));
        assert!(Stat::of(&[]).is_none());
        assert!(Stat::of(&[f64::NAN]).is_none());
    }

    #[test]
    fn every_method_has_a_case() {
        let cases = Case::all();
        for &m in Method::all() {
            assert!(cases.iter().any(|c| c.method == m), "{m} has no case");
        }
        for c in &cases {
            assert!(c.knobs.validate().is_ok(), "{}", c.label);
        }
        let r = Case::for_method(Method::REFERENCE);
        assert_eq!(r.knobs.get(&SAMPLES), MAX_SAMPLES);
        assert!(r.cpu_side());
    }

    #[test]
    fn scaling_scene_sizes() {
        for t in SCALING_TRIANGLES {
            let s = scaling_scene(t);
            assert_eq!(s.caster_triangle_count(), t as usize);
        }
    }

    #[test]
    fn configs_validate() {
        assert!(Config::full().validate().is_ok());
        assert!(Config::quick().validate().is_ok());
        let bad = Config {
            frames: 0,
            ..Config::quick()
        };
        assert!(bad.validate().is_err());
        let bad = Config {
            sizes: vec![4],
            ..Config::quick()
        };
        assert!(bad.validate().is_err());
        assert!(Config::quick().estimate_s() < Config::full().estimate_s());
    }
}
