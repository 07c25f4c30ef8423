//! `dbuffer gui SCENE --bench N`: the lab's real window, scripted and timed as a window.
//!
//! Five phases of N window frames each, after a few warm-up frames, every frame repainted, in
//! [`ROUNDS`] rounds (the floor moved by 15 % between runs of one phase after another, and a
//! phase's neighbour in time is the fairest yardstick it has):
//! - `blank`: the viewport neither renders nor paints an image — what the rest of the window
//!   costs egui, eframe and the surface (the floor);
//! - `image`: the viewport's last image painted, the render core not asked for a frame — what
//!   the image costs the window;
//! - `still`: the lab as it runs when nothing changes (the render core asked, nothing new to
//!   render) — what hovering a panel costs;
//! - `orbit`: the camera goes once round its target, as a drag of the mouse turns it — one
//!   render a frame, the shadow's light pass cached, the colour alone (the inspector waits for
//!   the drag's end);
//! - `light`: the light goes round a circle — the geometry stage, the light pass and the camera
//!   pass every frame.
//!
//! Per phase and round: window frames a second (wall clock), the process's CPU time a frame
//! (every thread: the UI's, eframe's and the rasteriser's where the GPU is a CPU one), eframe's
//! own measure of the UI thread, and the GPU time per pass of the renders; per phase the median
//! round's frames a second, and the orbit over the floor as the median of the rounds' ratios
//! (each round's orbit over the same round's floor). Printed as a table, and written as JSON
//! with `--bench-out`; then the window closes.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use eframe::egui;
use serde::Serialize;

use super::{camera, LabApp};

/// Window frames before each phase's clock starts (the first compiles pipelines).
const WARMUP: u32 = 5;
/// Times the five phases run, one after another.
pub const ROUNDS: u32 = 3;
/// Give up (and say so) when a run takes longer than this.
const TIMEOUT: Duration = Duration::from_secs(900);

/// What a phase does to the window each frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Phase {
    Blank,
    Image,
    Still,
    Orbit,
    Light,
}

pub const PHASES: [Phase; 5] = [
    Phase::Blank,
    Phase::Image,
    Phase::Still,
    Phase::Orbit,
    Phase::Light,
];

impl Phase {
    pub fn name(self) -> &'static str {
        match self {
            Phase::Blank => "blank",
            Phase::Image => "image",
            Phase::Still => "still",
            Phase::Orbit => "orbit",
            Phase::Light => "light",
        }
    }

    fn about(self) -> &'static str {
        match self {
            Phase::Blank => "viewport background, no image: the floor",
            Phase::Image => "last image painted, render core not asked",
            Phase::Still => "as the lab idles: render core asked, nothing new",
            Phase::Orbit => "camera orbit as a drag turns it, a render a frame",
            Phase::Light => "light moving, geometry + light pass + render",
        }
    }
}

/// One phase's numbers.
#[derive(Clone, Debug, Serialize)]
pub struct PhaseResult {
    pub phase: Phase,
    /// Frames timed (over every round, in the report's `phases`).
    pub frames: u32,
    pub seconds: f64,
    /// Frames a second (the median round's, in the report's `phases`).
    pub fps: f64,
    /// The process's CPU time over the phase a window frame (every thread), where the platform
    /// says it (`/proc/self/stat`).
    pub cpu_ms_per_frame: Option<f64>,
    /// eframe's CPU time of the UI thread's frame (update and paint), mean.
    pub ui_cpu_ms: Option<f64>,
    /// Renders the core made in the phase.
    pub renders: u64,
    /// Median GPU milliseconds per pass of those renders (where the adapter has timestamps; in
    /// the report's `phases`, the median of the rounds').
    pub gpu_ms: Vec<(String, f64)>,
}

/// The whole run, as `--bench-out` writes it.
#[derive(Debug, Serialize)]
pub struct WindowBenchReport {
    pub host: String,
    pub adapter: String,
    pub scene: String,
    pub method: String,
    pub window_px: [u32; 2],
    pub viewport_px: [u32; 2],
    /// Frames a phase a round.
    pub frames_per_phase: u32,
    /// Each phase over every round.
    pub phases: Vec<PhaseResult>,
    /// Each round's phases.
    pub rounds: Vec<Vec<PhaseResult>>,
    /// Orbit frames a second over the blank window's, the median of the rounds'.
    pub orbit_over_floor: Option<f64>,
    /// Each round's orbit frames a second over its blank window's.
    pub orbit_over_floor_rounds: Vec<f64>,
}

pub struct WindowBench {
    frames: u32,
    out: Option<PathBuf>,
    started: Instant,
    /// Whether the scene has been on screen (the phases start after its first render).
    begun: bool,
    round: u32,
    phase: usize,
    frame: u32,
    clock: Option<(Instant, Option<f64>)>,
    ui_cpu_ms: Vec<f32>,
    renders_at_start: u64,
    start_camera: Option<crate::scene::Camera>,
    start_light: Option<(crate::scene::file::LightSpec, glam::Vec3)>,
    /// Every round's results, in order.
    results: Vec<PhaseResult>,
    /// Set when the run ended: the report, or why there is none.
    pub outcome: Option<Result<WindowBenchReport, String>>,
    /// Where the ended run's table (or its error) goes for [`super::run`] to print.
    pub sink: Option<Sink>,
}

/// The window bench's result as [`super::run`] reads it after the window closed: the markdown
/// table, or why there is none.
pub type Sink = std::sync::Arc<std::sync::Mutex<Option<Result<String, String>>>>;

impl WindowBench {
    pub fn new(frames: u32, out: Option<PathBuf>) -> WindowBench {
        WindowBench {
            frames: frames.max(2),
            out,
            started: Instant::now(),
            begun: false,
            round: 0,
            phase: 0,
            frame: 0,
            clock: None,
            ui_cpu_ms: Vec::new(),
            renders_at_start: 0,
            start_camera: None,
            start_light: None,
            results: Vec::new(),
            outcome: None,
            sink: None,
        }
    }

    fn finish(&mut self, ctx: &egui::Context, outcome: Result<WindowBenchReport, String>) {
        if let Some(sink) = &self.sink {
            if let Ok(mut s) = sink.lock() {
                *s = Some(outcome.as_ref().map(markdown).map_err(Clone::clone));
            }
        }
        self.outcome = Some(outcome);
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }

    /// The phase under way (none once the run is over).
    pub fn phase(&self) -> Option<Phase> {
        if !self.begun || self.outcome.is_some() {
            return None;
        }
        PHASES.get(self.phase).copied()
    }
}

/// CPU seconds of this process so far, every thread (Linux; `None` elsewhere).
fn process_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command's closing parenthesis: state is field 3, utime 14, stime 15.
    let rest = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    // USER_HZ, which the kernel fixes at 100 for /proc on every architecture Linux ships.
    Some((utime + stime) / 100.0)
}

impl LabApp {
    /// One window frame of the bench: start, time and end the phases, and move the camera or
    /// the light for this frame's render. Called before the viewport is laid out.
    pub(super) fn window_bench_step(&mut self, ctx: &egui::Context, ui_cpu_s: Option<f32>) {
        let rendered = self.frames_rendered();
        let Some(bench) = self.window_bench.as_mut() else {
            return;
        };
        if bench.outcome.is_some() {
            return;
        }
        ctx.request_repaint();
        if bench.started.elapsed() > TIMEOUT {
            bench.finish(ctx, Err(format!("not done after {TIMEOUT:?}")));
            return;
        }
        // The first phase waits for the first rendered frame (the scene on screen).
        if rendered == 0 {
            return;
        }
        bench.begun = true;
        let Some(phase) = PHASES.get(bench.phase).copied() else {
            return;
        };
        let frames = bench.frames;
        if bench.frame == WARMUP {
            bench.clock = Some((Instant::now(), process_cpu_s()));
            bench.ui_cpu_ms.clear();
            bench.renders_at_start = rendered;
            self.stats.gpu.clear();
        } else if bench.frame > WARMUP {
            if let Some(s) = ui_cpu_s.filter(|s| s.is_finite() && *s >= 0.0) {
                bench.ui_cpu_ms.push(s * 1000.0);
            }
        }
        if bench.frame == WARMUP + frames {
            self.end_phase(phase, ctx);
            return;
        }
        if bench.frame == 0 {
            bench.start_camera = Some(self.camera);
            bench.start_light = Some((self.doc.file.light.clone(), self.doc.light().center()));
        }
        bench.frame += 1;
        let step = bench.frame;
        match phase {
            Phase::Blank | Phase::Image | Phase::Still => {}
            Phase::Orbit => {
                // As a drag of the mouse turns it (the inspector waits for the drag's end).
                self.viewport.drag = Some(super::viewport::Drag::Orbit);
                self.camera =
                    camera::orbit(&self.camera, std::f32::consts::TAU / frames as f32, 0.0);
            }
            Phase::Light => {
                let Some((start, c)) = bench.start_light.clone() else {
                    return;
                };
                // Round a circle about the light's place, a tenth of the camera's distance wide.
                let radius = 0.1 * (self.camera.eye - self.camera.target).length();
                let angle = std::f32::consts::TAU * step as f32 / (WARMUP + frames) as f32;
                let mut edit = self.doc.edit();
                edit.light = start;
                edit.light.set_center([
                    f64::from(c.x + radius * angle.cos()),
                    f64::from(c.y),
                    f64::from(c.z + radius * angle.sin()),
                ]);
                self.apply_edit(&edit);
            }
        }
    }

    fn end_phase(&mut self, phase: Phase, ctx: &egui::Context) {
        let rendered = self.frames_rendered();
        let gpu_ms = self.stats.median_gpu_ms();
        let camera_start;
        let light_start;
        {
            let Some(bench) = self.window_bench.as_mut() else {
                return;
            };
            let (seconds, cpu_ms_per_frame) = match bench.clock {
                Some((t0, cpu0)) => {
                    let seconds = t0.elapsed().as_secs_f64();
                    let cpu = cpu0
                        .zip(process_cpu_s())
                        .map(|(a, b)| (b - a) * 1000.0 / f64::from(bench.frames));
                    (seconds, cpu)
                }
                None => (0.0, None),
            };
            let ui_cpu_ms = (!bench.ui_cpu_ms.is_empty()).then(|| {
                bench.ui_cpu_ms.iter().map(|&v| f64::from(v)).sum::<f64>()
                    / bench.ui_cpu_ms.len() as f64
            });
            let renders = rendered.saturating_sub(bench.renders_at_start);
            bench.results.push(PhaseResult {
                phase,
                frames: bench.frames,
                seconds,
                fps: if seconds > 0.0 {
                    f64::from(bench.frames) / seconds
                } else {
                    0.0
                },
                cpu_ms_per_frame,
                ui_cpu_ms,
                renders,
                gpu_ms: if renders > 0 { gpu_ms } else { Vec::new() },
            });
            bench.phase += 1;
            if bench.phase >= PHASES.len() && bench.round + 1 < ROUNDS {
                bench.round += 1;
                bench.phase = 0;
            }
            bench.frame = 0;
            bench.clock = None;
            camera_start = bench.start_camera.take();
            light_start = bench.start_light.take();
        }
        // Each phase starts from where the scene was, the mouse let go.
        if let Some(c) = camera_start {
            self.camera = c;
        }
        self.viewport.drag = None;
        if let (Phase::Light, Some((light, _))) = (phase, light_start) {
            let mut edit = self.doc.edit();
            edit.light = light;
            self.apply_edit(&edit);
        }
        let done = self
            .window_bench
            .as_ref()
            .is_some_and(|b| b.phase >= PHASES.len());
        if done {
            let report = self.window_bench_report(ctx);
            if let Some(bench) = self.window_bench.as_mut() {
                bench.finish(ctx, report);
            }
        }
    }

    fn window_bench_report(&self, ctx: &egui::Context) -> Result<WindowBenchReport, String> {
        let bench = self.window_bench.as_ref().ok_or("no bench")?;
        let ppp = ctx.pixels_per_point();
        let screen = ctx.content_rect();
        let viewport = self.viewport.rect.unwrap_or(egui::Rect::NOTHING);
        let px = |r: egui::Rect| {
            [
                (r.width() * ppp).round().max(0.0) as u32,
                (r.height() * ppp).round().max(0.0) as u32,
            ]
        };
        let rounds: Vec<Vec<PhaseResult>> = bench
            .results
            .chunks(PHASES.len())
            .map(<[PhaseResult]>::to_vec)
            .collect();
        let ratios: Vec<f64> = rounds
            .iter()
            .filter_map(|r| over_floor(r, Phase::Orbit))
            .collect();
        let report = WindowBenchReport {
            host: crate::render::adapter::host_description(),
            adapter: self.adapter().unwrap_or_else(|| "none".into()),
            scene: self.doc.label.clone(),
            method: self.settings.method().to_string(),
            window_px: px(screen),
            viewport_px: px(viewport),
            frames_per_phase: bench.frames,
            phases: PHASES
                .iter()
                .map(|&p| over_rounds(p, &bench.results))
                .collect(),
            orbit_over_floor: median(ratios.clone()),
            orbit_over_floor_rounds: ratios,
            rounds,
        };
        if let Some(path) = &bench.out {
            let json = serde_json::to_vec_pretty(&report).map_err(|e| e.to_string())?;
            crate::fsutil::write_atomic(path, &json)
                .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        }
        Ok(report)
    }
}

/// A phase's frames a second in one round's results (none where it did not run or stood still).
fn fps_in(round: &[PhaseResult], phase: Phase) -> Option<f64> {
    round
        .iter()
        .find(|r| r.phase == phase)
        .map(|r| r.fps)
        .filter(|f| *f > 0.0)
}

/// A phase's frames a second over the same round's floor (`blank`).
fn over_floor(round: &[PhaseResult], phase: Phase) -> Option<f64> {
    Some(fps_in(round, phase)? / fps_in(round, Phase::Blank)?)
}

/// The median of `v` (the mean of the middle two where their count is even); none of nothing.
fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some((v[n / 2 - 1] + v[n / 2]) / 2.0),
    }
}

/// One phase over every round: frames and seconds added up, the median round's frames a second,
/// the mean CPU a frame, the renders added up, each pass's median of the rounds' GPU times.
fn over_rounds(phase: Phase, results: &[PhaseResult]) -> PhaseResult {
    let of: Vec<&PhaseResult> = results.iter().filter(|r| r.phase == phase).collect();
    let mean = |f: &dyn Fn(&PhaseResult) -> Option<f64>| {
        let v: Vec<f64> = of.iter().filter_map(|r| f(r)).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let mut passes: Vec<String> = Vec::new();
    for r in &of {
        for (p, _) in &r.gpu_ms {
            if !passes.contains(p) {
                passes.push(p.clone());
            }
        }
    }
    let gpu_ms = passes
        .into_iter()
        .filter_map(|p| {
            let times = of
                .iter()
                .filter_map(|r| r.gpu_ms.iter().find(|(q, _)| *q == p).map(|(_, ms)| *ms))
                .collect();
            Some((p, median(times)?))
        })
        .collect();
    PhaseResult {
        phase,
        frames: of.iter().map(|r| r.frames).sum(),
        seconds: of.iter().map(|r| r.seconds).sum(),
        fps: median(of.iter().map(|r| r.fps).collect()).unwrap_or(0.0),
        cpu_ms_per_frame: mean(&|r| r.cpu_ms_per_frame),
        ui_cpu_ms: mean(&|r| r.ui_cpu_ms),
        renders: of.iter().map(|r| r.renders).sum(),
        gpu_ms,
    }
}

/// The report as a markdown table, for the terminal and the docs.
pub fn markdown(report: &WindowBenchReport) -> String {
    let mut s = format!(
        "The lab's window: {}, method {}, on {} ({}), window {}×{} px, viewport {}×{} px, {} frames a phase, {} rounds.\n\n",
        report.scene,
        report.method,
        report.adapter,
        report.host,
        report.window_px[0],
        report.window_px[1],
        report.viewport_px[0],
        report.viewport_px[1],
        report.frames_per_phase,
        report.rounds.len(),
    );
    s.push_str(
        "| phase | what | window fps (median round) | fps by round | × floor (median of rounds) | CPU ms a frame (process) | UI thread ms | renders | GPU ms a render |\n|---|---|---:|---|---:|---:|---:|---:|---|\n",
    );
    for r in &report.phases {
        let gpu: Vec<String> = r
            .gpu_ms
            .iter()
            .map(|(p, ms)| format!("{p} {ms:.1}"))
            .collect();
        let by_round: Vec<String> = report
            .rounds
            .iter()
            .filter_map(|round| fps_in(round, r.phase))
            .map(|f| format!("{f:.1}"))
            .collect();
        let ratio = median(
            report
                .rounds
                .iter()
                .filter_map(|round| over_floor(round, r.phase))
                .collect(),
        );
        let opt = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v:.1}"));
        s.push_str(&format!(
            "| {} | {} | {:.1} | {} | {} | {} | {} | {} | {} |\n",
            r.phase.name(),
            r.phase.about(),
            r.fps,
            by_round.join(" / "),
            ratio.map_or("—".into(), |f| format!("{f:.2}×")),
            opt(r.cpu_ms_per_frame),
            opt(r.ui_cpu_ms),
            r.renders,
            if gpu.is_empty() {
                "—".into()
            } else {
                gpu.join(", ")
            }
        ));
    }
    let rounds: Vec<String> = report
        .orbit_over_floor_rounds
        .iter()
        .map(|r| format!("{r:.2}×"))
        .collect();
    s.push_str(&format!(
        "\nOrbit over the floor, round by round: {} (median {}).\n",
        rounds.join(", "),
        report
            .orbit_over_floor
            .map_or("—".into(), |r| format!("{r:.2}×"))
    ));
    s
}
