//! File → Record orbit…: the orbit `dbuffer animate` renders, recorded from the lab's current
//! view (its scene as edited, its camera, method, V(t), knobs and viewport size) into a folder of
//! PNG frames and an APNG. One frame is rendered per window frame in a session of its own, so
//! the window stays live and shows the progress; Cancel leaves the folder as it was.

use std::path::PathBuf;

use eframe::egui;

use super::{LabApp, Level};
use crate::animation::{AnimationSpec, Recording, MAX_FRAMES};
use crate::scene::orbit::Orbit;

/// The Record window's choices, and the recording under way.
pub struct RecordState {
    pub open: bool,
    pub orbit: Orbit,
    pub frames: usize,
    pub fps: u32,
    /// The folder to write into; empty: `recording-SCENE` in the working directory.
    pub folder: String,
    active: Option<Recording>,
}

impl Default for RecordState {
    fn default() -> Self {
        RecordState {
            open: false,
            orbit: Orbit::Light,
            frames: 48,
            fps: 24,
            folder: String::new(),
            active: None,
        }
    }
}

impl RecordState {
    /// (frames done, total) while recording.
    pub fn progress(&self) -> Option<(usize, usize)> {
        self.active.as_ref().map(Recording::progress)
    }
}

impl LabApp {
    /// The Record window (when open) and one step of a recording under way.
    pub(super) fn record_ui(&mut self, ctx: &egui::Context) {
        if self.record.active.is_some() {
            self.record_step();
            ctx.request_repaint();
        }
        if !self.record.open {
            return;
        }
        let mut open = self.record.open;
        let mut start = false;
        let mut cancel = false;
        let size = self.record_size();
        let default_folder = self.default_record_folder();
        egui::Window::new("Record orbit")
            .open(&mut open)
            .resizable(false)
            .show(ctx, |ui| {
                let busy = self.record.active.is_some();
                ui.add_enabled_ui(!busy, |ui| {
                    ui.horizontal(|ui| {
                        ui.label("Orbit");
                        ui.radio_value(&mut self.record.orbit, Orbit::Light, "light");
                        ui.radio_value(&mut self.record.orbit, Orbit::Camera, "camera");
                    });
                    ui.horizontal(|ui| {
                        let label = ui.label("Frames");
                        ui.add(egui::DragValue::new(&mut self.record.frames).range(1..=MAX_FRAMES))
                            .labelled_by(label.id);
                        let label = ui.label("at fps");
                        ui.add(egui::DragValue::new(&mut self.record.fps).range(1..=60))
                            .labelled_by(label.id);
                    });
                    ui.horizontal(|ui| {
                        let label = ui.label("Folder");
                        ui.add(
                            egui::TextEdit::singleline(&mut self.record.folder)
                                .hint_text(default_folder.display().to_string())
                                .desired_width(220.0),
                        )
                        .labelled_by(label.id);
                    });
                });
                match size {
                    Some((w, h)) => ui.label(format!(
                        "{w}x{h} (the viewport), {}, {}",
                        self.settings.method(),
                        self.settings.vt()
                    )),
                    None => ui.label("nothing shown yet"),
                };
                match self.record.progress() {
                    Some((done, total)) => {
                        ui.add(
                            egui::ProgressBar::new(done as f32 / total.max(1) as f32)
                                .text(format!("{done} / {total} frames")),
                        );
                        cancel = ui.button("Cancel").clicked();
                    }
                    None => {
                        start = ui
                            .add_enabled(size.is_some(), egui::Button::new("Record"))
                            .clicked()
                    }
                }
            });
        self.record.open = open;
        if cancel || (!open && self.record.active.is_some()) {
            self.record.active = None;
            self.set_status(
                "recording cancelled; the folder was left as it was",
                Level::Warning,
            );
        }
        if start {
            self.start_recording();
        }
    }

    /// The viewport's render size (the main view).
    fn record_size(&self) -> Option<(u32, u32)> {
        let shown = self.shown_at(0)?;
        Some((shown.request.width, shown.request.height))
    }

    fn default_record_folder(&self) -> PathBuf {
        let safe: String = self
            .doc
            .name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        PathBuf::from(format!("recording-{safe}"))
    }

    /// Start recording the current view with the Record window's choices.
    pub fn start_recording(&mut self) {
        let Some((width, height)) = self.record_size() else {
            self.set_status("nothing to record yet", Level::Error);
            return;
        };
        let method = self.settings.method();
        if method.cpu_side() {
            self.set_status(
                format!(
                    "{method} casts its rays on the CPU, too slow to record in the window: \
                     use `dbuffer animate SCENE --method {method}`"
                ),
                Level::Error,
            );
            return;
        }
        let folder = if self.record.folder.trim().is_empty() {
            self.default_record_folder()
        } else {
            PathBuf::from(self.record.folder.trim())
        };
        let spec = AnimationSpec {
            frames: self.record.frames,
            fps: self.record.fps,
            orbit: self.record.orbit,
            request: self.base_request(width, height),
        };
        let camera = self.camera;
        let Some(core) = self.core.as_ref() else {
            self.set_status("no wgpu device: nothing to record with", Level::Error);
            return;
        };
        let mut scene = core.session.scene().clone();
        scene.camera = camera;
        match Recording::start(&core.ctx, scene, spec, &folder) {
            Ok(r) => {
                let note = r.note().map(|n| format!(" ({n})")).unwrap_or_default();
                self.set_status(
                    format!(
                        "recording {} frames into {}{note}",
                        spec.frames,
                        folder.display()
                    ),
                    Level::Info,
                );
                self.record.active = Some(r);
            }
            Err(e) => self.set_status(format!("not recorded: {e}"), Level::Error),
        }
    }

    /// Render the next frame of the recording; at the end, write it all.
    fn record_step(&mut self) {
        let (Some(core), Some(rec)) = (self.core.as_ref(), self.record.active.as_mut()) else {
            return;
        };
        if let Err(e) = rec.step(&core.ctx, &mut |_, _| {}) {
            self.record.active = None;
            self.set_status(format!("recording failed: {e}"), Level::Error);
            return;
        }
        if !rec.is_done() {
            return;
        }
        let Some(rec) = self.record.active.take() else {
            return;
        };
        let out = rec.out().to_path_buf();
        match rec.finish() {
            Ok(w) => self.set_status(
                format!(
                    "recorded {} frames and an APNG ({} KiB) into {}",
                    w.files.len().saturating_sub(1),
                    w.animation_bytes.div_ceil(1024),
                    out.display()
                ),
                Level::Info,
            ),
            Err(e) => self.set_status(format!("not recorded: {e}"), Level::Error),
        }
    }
}
