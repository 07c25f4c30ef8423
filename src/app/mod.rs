//! The lab: an eframe window around the render core. `dbuffer` opens it on the default scene,
//! `dbuffer gui SCENE` on a scene file or built-in name. It renders nothing itself: every image
//! is a frame of the same [`crate::render::Session`] `dbuffer render` uses, on eframe's own
//! wgpu device, left on the GPU and shown as a texture the render core's view pass draws; only
//! the few values a person reads (the pixel under the cursor) come back.
//!
//! One file per part: [`settings`] (what persists), [`doc`] (the scene being edited, undo),
//! the view session it drives ([`crate::render::view_session`]: the session, the shown targets,
//! the ground truth's workers, probes, FLIP), [`camera`] (controls and the one projection
//! overlays and picking use), [`viewport`] (what to show, and showing it), `pointer` (mouse
//! input), [`overlays`], [`panels`] (the controls), [`inspector`] (pixel values),
//! [`stats`], [`files`] (open, save, export).

pub mod camera;
pub mod doc;
mod files;
mod inspector;
mod light_fields;
pub mod light_panel;
mod live;
pub mod motion;
mod overlays;
mod panels;
mod pointer;
pub mod record;
pub mod settings;
mod smoke;
mod stats;
pub mod study_panel;
mod viewport;
pub mod window_bench;

use std::path::PathBuf;
use std::sync::Arc;

use eframe::egui;
use eframe::egui_wgpu;

use self::doc::{Edit, History, SceneDoc};
pub use self::settings::{Overlays, Settings, DEFAULT_SCENE};
use self::stats::Stats;
pub use self::viewport::Shown;
use crate::geometry::bvh::Bvh;
pub use crate::render::passes::view::View;
use crate::render::view_session::ViewSession;
use crate::render::{GpuContext, Method};
use crate::scene::Camera;

/// How the lab starts.
#[derive(Clone, Debug, Default)]
pub struct LabOptions {
    /// Built-in scene name or path; the default scene when `None`.
    pub scene: Option<String>,
    /// `--scene N`: which scene of a glTF model to open.
    pub gltf_scene: Option<usize>,
    /// Take a screenshot of the window into this PNG once frames are showing, then exit
    /// (`DBUFFER_SMOKE_SCREENSHOT`; the Xvfb smoke run).
    pub smoke_screenshot: Option<PathBuf>,
    /// `--bench N`: time the window through [`window_bench`]'s phases of N frames, then exit.
    pub window_bench: Option<u32>,
    /// `--bench-out`: where the window bench's JSON goes.
    pub window_bench_out: Option<PathBuf>,
    /// Start from default settings rather than the saved ones.
    pub fresh_settings: bool,
    /// Tests and snapshots: default settings, and no timings on screen (they differ per run).
    pub deterministic: bool,
    /// `-v`: say on stderr which adapter eframe chose, and why.
    pub verbose: bool,
    /// `--study DIR`: show that study's plot for the open scene.
    pub study: Option<PathBuf>,
    /// `--shaders DIR`: read the shaders from this folder, and reload them when they change.
    pub shaders: Option<PathBuf>,
    /// `--geometry`: where the D-buffer's geometry stage runs (the `geometry` knob's value),
    /// over the saved setting.
    pub geometry: Option<u32>,
}

/// What a click picked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Selection {
    #[default]
    None,
    /// The whole light (a line light moves as a segment).
    Light,
    /// One end of a line light: 0 is `a`, 1 is `b`.
    LightEnd(usize),
    Object(usize),
}

impl Selection {
    /// The light or one of its ends.
    pub fn is_light(self) -> bool {
        matches!(self, Selection::Light | Selection::LightEnd(_))
    }
}

/// How serious a status line is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    Info,
    Warning,
    Error,
}

pub struct LabApp {
    pub settings: Settings,
    /// The camera the lab looks through (not part of undo; saved with the scene).
    pub camera: Camera,
    pub selection: Selection,
    core: Option<ViewSession>,
    doc: SceneDoc,
    history: History,
    /// Bumped by every scene edit and scene change: a new frame is needed.
    revision: u64,
    /// Bumped when a mesh changes (an object moved, another scene): what depends on the
    /// triangles alone (the light panel's BVH) is made again.
    geometry_revision: u64,
    /// Per object, a BVH for picking, built when first needed after the object moved.
    bvhs: Vec<Option<Bvh>>,
    status: (String, Level),
    render_error: Option<String>,
    viewport: viewport::ViewportState,
    inspector: inspector::Inspector,
    /// The inspector's "light as seen from this pixel" panel.
    light_panel: light_panel::LightPanel,
    /// The temporal error while the light or a caster is dragged.
    motion: motion::MotionMeter,
    stats: Stats,
    open_text: String,
    smoke: Option<smoke::Smoke>,
    window_bench: Option<window_bench::WindowBench>,
    export: Option<files::PendingExport>,
    /// File → Record orbit…: its window and the recording under way.
    pub record: record::RecordState,
    /// What the overlays could not draw in full, for the legend.
    overlay_notes: Vec<String>,
    /// `--study DIR`: the study's plot of the open scene.
    pub study: study_panel::StudyPanel,
    deterministic: bool,
    /// The shaders being watched (`--shaders DIR`, the user's methods opened).
    live: live::Live,
}

pub use self::live::check_dir as check_shader_dir;

impl LabApp {
    /// The lab on eframe's (or the test harness's) wgpu device.
    pub fn new(cc: &eframe::CreationContext<'_>, options: LabOptions) -> LabApp {
        let mut settings: Settings = if options.fresh_settings || options.deterministic {
            Settings::default()
        } else {
            cc.storage
                .and_then(|s| eframe::get_value(s, eframe::APP_KEY))
                .unwrap_or_default()
        };
        settings.sanitize();
        if let Some(g) = options.geometry {
            settings.knobs = settings
                .knobs
                .with(&crate::render::methods::dbuffer::GEOMETRY, g);
        }
        let wanted = options.scene.as_deref().unwrap_or(DEFAULT_SCENE);
        let mut status = (String::new(), Level::Info);
        let load_options = crate::scene::LoadOptions {
            gltf_scene: options.gltf_scene,
        };
        let (doc, scene) = match SceneDoc::open_with(wanted, load_options) {
            Ok(loaded) => loaded,
            Err(e) => {
                status = (format!("{e}; showing {DEFAULT_SCENE}"), Level::Error);
                match SceneDoc::open(DEFAULT_SCENE) {
                    Ok(loaded) => loaded,
                    // The built-in scenes are embedded and tested; still no panic.
                    Err(e) => {
                        status = (format!("{e}"), Level::Error);
                        SceneDoc::empty()
                    }
                }
            }
        };
        let core = match cc.wgpu_render_state.as_ref() {
            Some(rs) => {
                if options.verbose {
                    // A closed stderr is no reason to stop: never `eprintln!`'s panic.
                    use std::io::Write as _;
                    let _ = writeln!(
                        std::io::stderr(),
                        "adapter   {}\nchosen by eframe: --backend, else WGPU_BACKEND, else its \
                         default",
                        crate::render::adapter::info_line(&rs.adapter.get_info())
                    );
                }
                Some(ViewSession::new(context_of(rs), scene))
            }
            None => {
                status = (
                    "no wgpu device: the lab needs eframe's wgpu renderer".into(),
                    Level::Error,
                );
                None
            }
        };
        let camera = doc.camera();
        let objects = doc.file.objects.len();
        let mut app = LabApp {
            settings,
            camera,
            selection: Selection::None,
            core,
            doc,
            history: History::default(),
            revision: 0,
            geometry_revision: 0,
            bvhs: vec![None; objects],
            status,
            render_error: None,
            viewport: viewport::ViewportState::default(),
            inspector: inspector::Inspector::default(),
            light_panel: light_panel::LightPanel::default(),
            motion: motion::MotionMeter::default(),
            stats: Stats::default(),
            open_text: String::new(),
            smoke: options.smoke_screenshot.map(smoke::Smoke::new),
            window_bench: options
                .window_bench
                .map(|n| window_bench::WindowBench::new(n, options.window_bench_out.clone())),
            export: None,
            record: record::RecordState::default(),
            overlay_notes: Vec::new(),
            study: options
                .study
                .as_deref()
                .map(study_panel::StudyPanel::load)
                .unwrap_or_default(),
            deterministic: options.deterministic,
            live: live::Live::default(),
        };
        app.start_live(&cc.egui_ctx, options.shaders.as_deref());
        let switched = app.suit_methods_to_the_light();
        if app.status.0.is_empty() {
            app.status = (app.opened_message(), Level::Info);
            if let Some(s) = switched {
                app.status.0 = format!("{}: {s}", app.status.0);
            }
        }
        app
    }

    /// The status line: the last message and how serious it is.
    pub fn status(&self) -> (&str, Level) {
        (&self.status.0, self.status.1)
    }

    pub fn scene_name(&self) -> &str {
        &self.doc.name
    }

    /// The scene as the render core has it.
    pub fn scene(&self) -> Option<&crate::scene::Scene> {
        self.core.as_ref().map(|c| c.scene())
    }

    /// What the viewport shows (left side of a split).
    pub fn shown(&self) -> Option<&Shown> {
        self.shown_at(0)
    }

    /// What the inspector's "light as seen from this pixel" panel shows, once computed.
    pub fn pixel_light(&self) -> Option<&light_panel::PixelLight> {
        self.light_panel.shown.as_ref()
    }

    /// The light panel's state (its oracle, whether it is preparing).
    pub fn light_panel(&self) -> &light_panel::LightPanel {
        &self.light_panel
    }

    /// Blocks until the light panel's worker is done (tests; the window never waits).
    pub fn wait_for_light_panel(&mut self) {
        self.light_panel.wait();
    }

    /// The right side of a split view.
    pub fn shown_split(&self) -> Option<&Shown> {
        self.shown_at(1)
    }

    /// Read the frame the viewport shows (`split`: its right side) back whole, with the shown
    /// method's light-space maps. For tests and exports: the lab itself never reads a frame.
    pub fn read_shown(&mut self, split: bool) -> Option<crate::render::Frame> {
        let method = self.shown_at(usize::from(split))?.method;
        self.core
            .as_mut()?
            .read(usize::from(split), Some(method))
            .ok()
    }

    /// The view session (tests look at its session and the truths' workers).
    pub fn core(&self) -> Option<&ViewSession> {
        self.core.as_ref()
    }

    /// What side `side` of the viewport shows (0 the main one, 1 the right of a split).
    fn shown_at(&self, side: usize) -> Option<&Shown> {
        self.core.as_ref()?.shown(side)
    }

    /// Where the viewport was last drawn, in points.
    pub fn viewport_rect(&self) -> Option<egui::Rect> {
        self.viewport.rect
    }

    /// How many frames the render core has made for the lab.
    pub fn frames_rendered(&self) -> u64 {
        self.stats.renders_total
    }

    /// The passes the Stats panel lists GPU times for, in its order.
    pub fn gpu_passes(&self) -> Vec<String> {
        self.stats
            .median_gpu_ms()
            .into_iter()
            .map(|(pass, _)| pass)
            .collect()
    }

    /// How many window frames have run.
    pub fn window_frames(&self) -> u64 {
        self.stats.window_frames
    }

    /// Bytes read back from the GPU by the last window frame that submitted work, and the most
    /// over the last few seconds of them.
    /// The motion meter's values over its window and what the newest measured (tests).
    pub fn motion_series(&self) -> (Vec<f32>, Option<motion::Measure>) {
        self.motion.series()
    }

    /// Whether the motion meter's plot is on screen.
    pub fn motion_showing(&self) -> bool {
        self.motion.showing()
    }

    /// What `--bench` ended with, once it has: its report, or why there is none.
    pub fn window_bench_outcome(&self) -> Option<&Result<window_bench::WindowBenchReport, String>> {
        self.window_bench.as_ref()?.outcome.as_ref()
    }

    /// The pixels the NaN / range view marks on the main side (`split`: the right), as the GPU
    /// last counted them; `None` before a count arrived.
    pub fn out_of_range_px(&self, split: bool) -> Option<u64> {
        self.inspector.range_px(usize::from(split))
    }

    pub fn read_bytes(&self) -> Option<(u64, u64)> {
        self.stats.read_bytes()
    }

    pub fn adapter(&self) -> Option<String> {
        self.core.as_ref().map(|c| c.ctx.adapter_description())
    }

    /// Capture the next frame in the attached graphics debugger (Debug → Capture frame).
    pub fn capture_frame(&mut self) {
        let Some(core) = self.core.as_mut() else {
            return;
        };
        core.capture_next_frame();
        if crate::render::context::renderdoc_attached() == Some(false) {
            self.set_status(
                "Capture frame: no graphics debugger is attached, so nothing is captured; run \
                 the lab under RenderDoc (renderdoccmd capture dbuffer gui, or its Launch \
                 Application)",
                Level::Warning,
            );
        }
    }

    fn set_status(&mut self, text: impl Into<String>, level: Level) {
        self.status = (text.into(), level);
    }

    fn opened_message(&self) -> String {
        let warnings = self.scene_warnings().len();
        if warnings > 0 {
            let s = if warnings == 1 { "" } else { "s" };
            format!("opened {} ({warnings} warning{s})", self.doc.label)
        } else {
            format!("opened {}", self.doc.label)
        }
    }

    /// Open a built-in scene name, a `.toml` scene, an `.obj` or a `.glb`/`.gltf`; on failure the error goes to
    /// the status line and the current scene stays.
    /// After the light's kind changed: a shown method that cannot take it is replaced by the
    /// method made for that kind (the D-buffer for a disk, `linear-ssm` for a line); returns
    /// what was switched, to say so.
    fn suit_methods_to_the_light(&mut self) -> Option<String> {
        let kind = self.doc.file.light.kind();
        let fallback = Method::made_for(kind);
        let mut said = Vec::new();
        for name in [&mut self.settings.method, &mut self.settings.split_method] {
            if let Ok(m) = name.parse::<Method>() {
                if !m.takes(kind) {
                    said.push(format!("{m} needs {}", m.takes_in_words()));
                    *name = fallback.name().to_string();
                }
            }
        }
        (!said.is_empty()).then(|| format!("{}: showing {fallback}", said.join(", ")))
    }

    pub fn open_scene(&mut self, name_or_path: &str) {
        match SceneDoc::open(name_or_path) {
            Ok((doc, scene)) => {
                if let Some(core) = self.core.as_mut() {
                    core.replace_scene(scene);
                }
                self.bvhs = vec![None; doc.file.objects.len()];
                self.motion.reset();
                self.camera = doc.camera();
                self.doc = doc;
                self.history.clear();
                self.selection = Selection::None;
                self.revision += 1;
                self.geometry_revision += 1;
                self.viewport.drag = None;
                if !SceneDoc::is_builtin(name_or_path) {
                    self.settings.push_recent(name_or_path);
                }
                let switched = self.suit_methods_to_the_light();
                let mut warnings = self.scene_warnings();
                warnings.extend(switched);
                match warnings.first() {
                    Some(w) => {
                        self.set_status(format!("opened {}: {w}", self.doc.label), Level::Warning)
                    }
                    None => self.set_status(self.opened_message(), Level::Info),
                }
            }
            Err(e) => {
                // Scene file errors already name their file.
                let e = e.to_string();
                let what = if e.contains(name_or_path) {
                    e
                } else {
                    format!("{name_or_path}: {e}")
                };
                self.set_status(
                    format!("cannot open {what} (kept {})", self.doc.name),
                    Level::Error,
                )
            }
        }
    }

    /// What the model's reader said about it ([`SceneDoc::notes`]) and what the geometry stage
    /// warned about (the shown method's, or the paper's, geometry).
    pub fn scene_warnings(&self) -> Vec<String> {
        let mut warnings = self.doc.notes.clone();
        if let Some(core) = self.core.as_ref() {
            warnings.extend(
                core.session
                    .geometry(self.settings.method())
                    .or_else(|| core.session.geometry(crate::render::Method::DBUFFER))
                    .map(|g| g.warnings.clone())
                    .unwrap_or_default(),
            );
            // The GPU stage's refusals, known a frame or more after its build.
            if let Some(gpu) = core.session.gpu_geometry(self.settings.method()) {
                warnings.extend(gpu.refused_warnings());
            }
        }
        warnings
    }

    /// Change the scene through `change` (one undo step per gesture).
    fn edit_scene(&mut self, change: impl FnOnce(&mut Edit)) {
        let before = self.doc.edit();
        let mut after = before.clone();
        change(&mut after);
        if after != before {
            self.history.checkpoint(before);
            self.apply_edit(&after);
        }
    }

    fn apply_edit(&mut self, edit: &Edit) {
        let previous = self.doc.edit();
        let (light, moved) = self.doc.apply(edit);
        if let Err(e) = self.doc.validate() {
            self.doc.apply(&previous);
            self.set_status(format!("edit refused: {e}"), Level::Error);
            return;
        }
        if let Some(core) = self.core.as_mut() {
            if light {
                core.set_light(self.doc.light());
            }
            for &i in &moved {
                if let Some(mesh) = self.doc.world_mesh(i) {
                    core.set_object_mesh(i, mesh);
                }
            }
        }
        for &i in &moved {
            if let Some(b) = self.bvhs.get_mut(i) {
                *b = None;
            }
        }
        if !moved.is_empty() {
            self.geometry_revision += 1;
        }
        self.revision += 1;
    }

    pub fn undo(&mut self) {
        if let Some(edit) = self.history.undo(self.doc.edit()) {
            self.apply_edit(&edit);
            self.set_status("undone", Level::Info);
        }
    }

    pub fn redo(&mut self) {
        if let Some(edit) = self.history.redo(self.doc.edit()) {
            self.apply_edit(&edit);
            self.set_status("redone", Level::Info);
        }
    }

    /// Keyboard shortcuts that act on the whole lab (not while typing in a field).
    fn shortcuts(&mut self, ctx: &egui::Context) {
        // Not while typing in a text field (a clicked button has focus too, and must not block).
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        use egui::{Key, KeyboardShortcut, Modifiers};
        let redo = KeyboardShortcut::new(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
        let redo_y = KeyboardShortcut::new(Modifiers::COMMAND, Key::Y);
        let undo = KeyboardShortcut::new(Modifiers::COMMAND, Key::Z);
        if ctx.input_mut(|i| i.consume_shortcut(&redo) || i.consume_shortcut(&redo_y)) {
            self.redo();
        } else if ctx.input_mut(|i| i.consume_shortcut(&undo)) {
            self.undo();
        }
        if ctx.input(|i| i.key_pressed(Key::F) && i.modifiers.is_none()) {
            self.frame_all();
        }
    }

    /// The study's plot of the open scene; a point clicked shows its method and setting.
    fn study_ui(&mut self, ctx: &egui::Context) {
        let (method, knobs, map) = (
            self.settings.method.clone(),
            self.settings.knobs,
            self.settings.dbuffer_size,
        );
        let current = |cell: &crate::study::Cell| {
            cell.method == method
                && cell.values.iter().all(|(name, v)| {
                    if name == crate::render::methods::MAP_SIZE_NAME {
                        *v == map
                    } else {
                        crate::render::methods::all_knobs()
                            .iter()
                            .find(|k| k.name == name)
                            .is_some_and(|k| knobs.raw(k) == *v)
                    }
                })
        };
        let name = self.doc.name.clone();
        if let Some(pick) = self.study.ui(ctx, &name, &current) {
            self.show_study_cell(&pick);
        }
    }

    /// Show `pick`'s method with its setting (its knobs, its map size).
    pub fn show_study_cell(&mut self, pick: &study_panel::Pick) {
        self.settings.method = pick.method.name().to_string();
        // The cell as measured: the knobs it does not sweep at their defaults, its map size.
        self.settings.knobs = crate::render::Knobs::default();
        self.settings.dbuffer_size = pick.map_size;
        for (name, value) in &pick.values {
            if name == crate::render::methods::MAP_SIZE_NAME {
                self.settings.dbuffer_size = *value;
            } else if self.settings.knobs.set(name, *value).is_err() {
                self.set_status(format!("study: unknown knob {name}"), Level::Warning);
                return;
            }
        }
        self.set_status(format!("study: showing {}", pick.label), Level::Info);
    }

    /// Point the camera at every caster and the light.
    pub fn frame_all(&mut self) {
        let Some(scene) = self.scene() else { return };
        let light = scene.light;
        let mut lo = light.center() - glam::Vec3::splat(light.half_extent());
        let mut hi = light.center() + glam::Vec3::splat(light.half_extent());
        for o in scene.casters() {
            if let Some((a, b)) = o.mesh.bounds() {
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
        self.camera = camera::frame_all(&self.camera, (lo, hi));
    }
}

/// The render core's context on a device eframe (or the test harness) opened.
fn context_of(rs: &egui_wgpu::RenderState) -> GpuContext {
    GpuContext::with_adapter(rs.device.clone(), rs.queue.clone(), &rs.adapter)
}

impl eframe::App for LabApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.stats.ui_frame(&ctx, frame.info().cpu_usage);
        self.window_bench_step(&ctx, frame.info().cpu_usage);
        self.live_step(&ctx);
        self.shortcuts(&ctx);
        self.open_dropped(&ctx);
        self.menu_bar(ui);
        self.status_bar(ui);
        self.controls_panel(ui);
        self.inspector_panel(ui);
        egui::CentralPanel::no_frame().show(ui, |ui| self.viewport_ui(ui, frame));
        self.shader_error_ui(&ctx);
        if !ctx.input(|i| i.pointer.any_down()) {
            self.history.close();
        }
        self.finish_export(&ctx);
        self.study_ui(&ctx);
        self.record_ui(&ctx);
        self.drop_hint(&ctx);
        self.smoke_step(&ctx);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        if self.smoke.is_some() || self.window_bench.is_some() || self.deterministic {
            return; // scripted runs leave the user's settings alone
        }
        eframe::set_value(storage, eframe::APP_KEY, &self.settings);
    }
}

/// Open the lab window (blocks until it is closed).
pub fn run(options: LabOptions) -> anyhow::Result<()> {
    let smoke = options.smoke_screenshot.clone();
    let mut setup = egui_wgpu::WgpuSetupCreateNew {
        // What `GpuContext::from_adapter` asks for: timestamp queries where the adapter has them,
        // so the stats show GPU time per pass.
        device_descriptor: Arc::new(|adapter: &egui_wgpu::wgpu::Adapter| {
            egui_wgpu::wgpu::DeviceDescriptor {
                label: Some("dbuffer::lab device"),
                required_features: crate::render::context::wanted_features(adapter.features()),
                required_limits: crate::render::context::wanted_limits(&adapter.limits()),
                ..Default::default()
            }
        }),
        ..egui_wgpu::WgpuSetupCreateNew::without_display_handle()
    };
    // `--backend` as for the headless commands (eframe reads `WGPU_BACKEND` itself).
    if let Some(backends) = crate::render::adapter::backend() {
        setup.instance_descriptor.backends = backends;
    }
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("dbuffer lab")
            .with_inner_size([1280.0, 800.0])
            .with_min_inner_size([480.0, 320.0]),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: egui_wgpu::WgpuConfiguration {
            wgpu_setup: egui_wgpu::WgpuSetup::CreateNew(setup),
            ..Default::default()
        },
        ..Default::default()
    };
    let outcome = Arc::new(std::sync::Mutex::new(None::<Result<(), String>>));
    let sink = Arc::clone(&outcome);
    let bench = options.window_bench.is_some();
    let bench_outcome: window_bench::Sink = Arc::new(std::sync::Mutex::new(None));
    let bench_sink = Arc::clone(&bench_outcome);
    eframe::run_native(
        // The window's title and where eframe keeps the settings: the program's name.
        env!("CARGO_PKG_NAME"),
        native,
        Box::new(move |cc| {
            let mut app = LabApp::new(cc, options);
            if let Some(s) = app.smoke.as_mut() {
                s.outcome = Some(sink);
            }
            if let Some(b) = app.window_bench.as_mut() {
                b.sink = Some(bench_sink);
            }
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| match e {
        // wgpu's own words (several lines) go to the error formatter as a GPU's.
        eframe::Error::Wgpu(e) => {
            anyhow::Error::new(crate::render::RenderError::Device(e.to_string()))
                .context("the lab window failed")
        }
        e => anyhow::anyhow!("the lab window failed: {e}"),
    })?;
    if bench {
        let result = bench_outcome.lock().ok().and_then(|mut o| o.take());
        match result {
            Some(Ok(table)) => {
                use std::io::Write as _;
                let _ = writeln!(std::io::stdout(), "{table}");
            }
            Some(Err(e)) => anyhow::bail!("window bench: {e}"),
            None => anyhow::bail!("window bench: the window closed before the bench ended"),
        }
    }
    if smoke.is_some() {
        let result = outcome.lock().ok().and_then(|mut o| o.take());
        match result {
            Some(Ok(())) => {}
            Some(Err(e)) => anyhow::bail!("smoke run: {e}"),
            None => anyhow::bail!("smoke run: the window closed before a screenshot was taken"),
        }
    }
    Ok(())
}
