//! Shaders edited while the lab runs: `dbuffer gui --shaders DIR` and every user's method opened
//! (`File → Open method…`) are watched ([`crate::render::shaders::Watcher`]). On its signal the
//! lab reloads them through the render core ([`crate::render::shaders::reload`],
//! [`crate::render::methods::user::UserMethod::reload`]): a good save has the pipelines of the
//! files it changed made again ([`crate::render::view_session::ViewSession::shaders_changed`])
//! and the frame drawn again; a broken one is shown over the viewport — its file, line, column
//! and the offending line — while the last good pipelines keep drawing, until a good save.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::Duration;

use eframe::egui;

use super::{LabApp, Level};
use crate::render::methods::user::{self, UserKnob};
use crate::render::shaders::{self, ShaderError, Watcher};
use crate::render::Method;

/// The watched shaders and what their last reload said.
#[derive(Default)]
pub struct Live {
    /// `--shaders DIR`: the folder this lab reads and reloads (the render core's is the
    /// process's; a lab started without one never reloads it).
    dir: Option<PathBuf>,
    watcher: Option<Watcher>,
    /// The egui context to wake on a change.
    wake: Option<egui::Context>,
    /// The user's methods opened in the lab, in the order opened.
    pub methods: Vec<Method>,
    /// The error of the last look at each source (the folder as `""`, a user's file by its
    /// path), shown until a good save of it.
    errors: BTreeMap<String, ShaderError>,
    /// Good reloads applied so far.
    applied: u64,
    /// How long a user's method's trial frame may take ([`TRIAL_LIMIT`] unless set).
    trial_limit: Option<Duration>,
}

/// How long the trial frame of a user's method opened or saved may take on its own device
/// ([`crate::render::offline::trial`]) before the lab refuses it and keeps what it had.
pub const TRIAL_LIMIT: Duration = Duration::from_secs(10);

impl Live {
    fn watcher(&mut self) -> &Watcher {
        let wake = self.wake.clone();
        let dir = self.dir.clone();
        self.watcher.get_or_insert_with(|| {
            Watcher::new(
                dir,
                Box::new(move || {
                    if let Some(ctx) = &wake {
                        ctx.request_repaint();
                    }
                }),
            )
        })
    }
}

impl LabApp {
    /// At start: read shaders from `dir` (`--shaders DIR`) and watch it.
    pub(super) fn start_live(&mut self, ctx: &egui::Context, dir: Option<&Path>) {
        self.live.wake = Some(ctx.clone());
        let Some(dir) = dir else { return };
        self.live.dir = Some(dir.to_owned());
        if let Err(e) = shaders::set_dir(Some(dir)) {
            self.live.errors.insert(String::new(), e);
        }
        self.live.watcher();
    }

    /// Open the user's method at `path` (`File → Open method…`): it joins the methods, is
    /// shown, and its file is watched. On failure the status line says why.
    pub fn open_method(&mut self, path: &Path) {
        let text = path.display().to_string();
        match user::load(&text, &[]) {
            Ok(method) => {
                if let Err(e) = self.trial(method) {
                    let kept = self.settings.method.clone();
                    self.set_status(
                        format!("cannot open method: {e}; the lab keeps {kept}"),
                        Level::Error,
                    );
                    return;
                }
                self.live.watcher().watch(path);
                self.live.methods.retain(|m| *m != method);
                self.live.methods.push(method);
                // Opened again (or another file of the same name): nothing drawn from the
                // method of that name before is kept.
                if let (Some(core), Some(u)) = (self.core.as_mut(), user::of(method)) {
                    core.shaders_changed(&BTreeSet::from([u.shader_key()]));
                }
                self.settings.method = method.name().into();
                self.set_status(format!("opened method {text} as {method}"), Level::Info);
            }
            Err(e) => self.set_status(format!("cannot open method: {e}"), Level::Error),
        }
    }

    /// `File → Open method…`: a file dialog, then [`LabApp::open_method`].
    pub(super) fn open_method_dialog(&mut self) {
        let dialog = rfd::FileDialog::new()
            .set_title("Open a method (one WGSL file)")
            .add_filter("WGSL", &["wgsl"]);
        match super::files::pick_file(|| dialog.pick_file()) {
            Some(Ok(path)) => self.open_method(&path),
            Some(Err(why)) => self.set_status(
                format!("{why}: drop the .wgsl file on the window instead"),
                Level::Warning,
            ),
            None => {}
        }
    }

    /// On the watcher's signal: reload what changed, and apply a good change.
    pub(super) fn live_step(&mut self, ctx: &egui::Context) {
        let Some(watcher) = self.live.watcher.as_ref() else {
            return;
        };
        if !watcher.take() {
            return;
        }
        let mut changed = BTreeSet::new();
        if self.live.dir.is_some() {
            match shaders::reload() {
                Ok(reloaded) => {
                    self.live.errors.remove("");
                    changed.extend(reloaded.into_iter().flat_map(|r| r.changed));
                }
                Err(e) => {
                    self.live.errors.insert(String::new(), e);
                }
            }
        }
        for m in self.live.methods.clone() {
            let Some(u) = user::of(m) else { continue };
            match u.reload() {
                Ok(again) => {
                    self.live.errors.remove(&u.path);
                    if !again {
                        continue;
                    }
                    // A new version draws in the lab only once its trial frame finished on a
                    // device of its own: one that loses its device, or never ends, is refused
                    // and the last good version keeps drawing.
                    match self.trial(m) {
                        Ok(()) => {
                            changed.insert(u.shader_key());
                        }
                        Err(e) => {
                            u.revert();
                            let prefix = format!("{}: ", u.path);
                            let message = e.strip_prefix(&prefix).unwrap_or(&e).to_owned();
                            let error = ShaderError {
                                file: u.path.clone(),
                                line: 0,
                                column: 0,
                                message,
                                text: None,
                            };
                            self.live.errors.insert(u.path.clone(), error);
                        }
                    }
                }
                Err(e) => {
                    self.live.errors.insert(u.path.clone(), e);
                }
            }
        }
        if !changed.is_empty() {
            if let Some(core) = self.core.as_mut() {
                let made = core.shaders_changed(&changed);
                self.live.applied += 1;
                let files: Vec<&str> = changed.iter().map(String::as_str).collect();
                self.set_status(
                    format!(
                        "reloaded {} ({made} cached pipeline objects to make again)",
                        files.join(", ")
                    ),
                    Level::Info,
                );
            }
        }
        if !self.live.errors.is_empty() {
            self.set_status(
                "a shader does not validate (see the viewport): the last good ones keep drawing",
                Level::Warning,
            );
        }
        ctx.request_repaint();
    }

    /// One small frame of `method` on a device and thread of its own, on the lab's scene
    /// ([`crate::render::offline::trial`]), waited for at most the trial limit.
    fn trial(&self, method: Method) -> Result<(), String> {
        let Some(scene) = self.core.as_ref().map(|c| c.scene().clone()) else {
            return Ok(());
        };
        let limit = self.live.trial_limit.unwrap_or(TRIAL_LIMIT);
        crate::render::offline::trial(method, &scene, limit)
    }

    /// How long a user's method's trial frame may take (tests set a tiny one to stand in for
    /// a shader that never ends).
    pub fn set_trial_limit(&mut self, limit: Duration) {
        self.live.trial_limit = Some(limit);
    }

    /// Good reloads applied so far (tests wait for it to grow).
    pub fn shader_reloads(&self) -> u64 {
        self.live.applied
    }

    /// The shader errors shown now.
    pub fn shader_errors(&self) -> Vec<&ShaderError> {
        self.live.errors.values().collect()
    }

    /// The watcher, once something is watched (tests wait on its signal).
    pub fn shader_watcher(&self) -> Option<&Watcher> {
        self.live.watcher.as_ref()
    }

    /// The methods the lab lists: the registry's and the user's opened.
    pub(super) fn listed_methods(&self) -> Vec<Method> {
        let mut all = Method::all().to_vec();
        all.extend(self.live.methods.iter().copied());
        all
    }

    /// The sliders of a user's method's knobs (its file's header), if `method` is one.
    pub(super) fn user_knobs_ui(&mut self, ui: &mut egui::Ui, method: Method) {
        let Some(u) = user::of(method) else { return };
        let values = u.values();
        let knobs: Vec<UserKnob> = u.knobs();
        let mut moved = false;
        for (k, mut v) in knobs.iter().zip(values) {
            if ui
                .add(egui::Slider::new(&mut v, k.min..=k.max).text(&k.name))
                .on_hover_text(format!("{}:{}", u.path, k.line))
                .changed()
            {
                moved |= u.set_value(&k.name, v);
            }
        }
        if moved {
            if let Some(core) = self.core.as_mut() {
                core.redraw();
            }
        }
    }

    /// The errors over the viewport: each `file:line:column: message` and the offending line.
    pub(super) fn shader_error_ui(&self, ctx: &egui::Context) {
        let (Some(rect), false) = (self.viewport.rect, self.live.errors.is_empty()) else {
            return;
        };
        egui::Area::new(egui::Id::unique("shader-errors"))
            .fixed_pos(rect.left_top() + egui::vec2(8.0, 8.0))
            .order(egui::Order::Foreground)
            .show(ctx, |ui| {
                egui::Frame::popup(ui.style())
                    .fill(egui::Color32::from_rgba_unmultiplied(40, 0, 0, 230))
                    .show(ui, |ui| {
                        ui.set_width((rect.width() - 32.0).max(120.0));
                        for e in self.live.errors.values() {
                            ui.colored_label(egui::Color32::from_rgb(255, 120, 110), e.headline());
                            if let Some(text) = &e.text {
                                ui.monospace(text.trim_end());
                            }
                        }
                        ui.small("the last good shaders keep drawing; save a fix to reload");
                    });
            });
    }
}

/// `--shaders DIR` as the lab takes it: a folder.
pub fn check_dir(dir: &Path) -> Result<PathBuf, String> {
    if dir.is_dir() {
        Ok(dir.to_owned())
    } else {
        Err(format!("--shaders {}: not a folder", dir.display()))
    }
}
