//! The controls: menu bar, status line, and the left panel (scene, method, V(t), view, display
//! mapping, overlays, the selection's numbers, render settings).

use eframe::egui::{self, Color32, DragValue, RichText, Slider};

use super::{LabApp, Level, Selection};
use crate::geometry::VtVariant;
use crate::render::methods::{Knob, KnobKind};
use crate::render::passes::view::{ColorMap, View};
use crate::render::Method;
use crate::scene::builtin;
use crate::scene::file::Scale;

/// A labelled row of number fields: the label names them for screen readers and tests.
pub(super) fn number_row(ui: &mut egui::Ui, label: &str, values: &mut [f64], speed: f64) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        let l = ui.label(label);
        for v in values.iter_mut() {
            changed |= ui
                .add(DragValue::new(v).speed(speed).max_decimals(4))
                .labelled_by(l.id)
                .changed();
        }
    });
    changed
}

impl LabApp {
    pub(super) fn menu_bar(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        egui::Panel::top("menu").show(ui, |ui| {
            egui::MenuBar::new().ui(ui, |ui| {
                ui.menu_button("File", |ui| {
                    if ui.button("Open…").clicked() {
                        self.open_dialog();
                    }
                    if ui
                        .button("Open method…")
                        .on_hover_text("a method of your own in one WGSL file, watched for changes")
                        .clicked()
                    {
                        self.open_method_dialog();
                    }
                    ui.menu_button("Built-in scene", |ui| {
                        for name in builtin::names() {
                            if ui.button(*name).clicked() {
                                self.open_scene(name);
                            }
                        }
                    });
                    ui.menu_button("Recent", |ui| {
                        if self.settings.recent.is_empty() {
                            ui.label("(none yet)");
                        }
                        for entry in self.settings.recent.clone() {
                            if ui.button(&entry).clicked() {
                                self.open_scene(&entry);
                            }
                        }
                    });
                    ui.separator();
                    if ui.button("Save scene").clicked() {
                        self.save();
                    }
                    if ui.button("Save scene as…").clicked() {
                        self.save_as_dialog();
                    }
                    if ui.button("Export PNG…").clicked() {
                        self.export_dialog(&ctx);
                    }
                    if ui.button("Record orbit…").clicked() {
                        self.record.open = true;
                    }
                    if ui
                        .add_enabled(self.study.dir.is_some(), egui::Button::new("Study plot"))
                        .on_disabled_hover_text("start the lab with --study DIR")
                        .clicked()
                    {
                        self.study.open = true;
                    }
                    ui.separator();
                    if ui.button("Quit").clicked() {
                        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                    }
                });
                ui.menu_button("Edit", |ui| {
                    if ui
                        .add_enabled(self.history.can_undo(), egui::Button::new("Undo (Ctrl+Z)"))
                        .clicked()
                    {
                        self.undo();
                    }
                    if ui
                        .add_enabled(
                            self.history.can_redo(),
                            egui::Button::new("Redo (Ctrl+Shift+Z)"),
                        )
                        .clicked()
                    {
                        self.redo();
                    }
                });
                ui.menu_button("Camera", |ui| {
                    if ui.button("Frame all (F)").clicked() {
                        self.frame_all();
                    }
                    if ui.button("Scene camera").clicked() {
                        self.camera = self.doc.camera();
                    }
                });
                ui.menu_button("Debug", |ui| {
                    let capture = ui.button("Capture frame").on_hover_text(
                        "The next frame's GPU work, every pass under its name, in RenderDoc \
                         when the lab runs under it (docs/guide/lab.md)",
                    );
                    if capture.clicked() {
                        self.capture_frame();
                    }
                });
                ui.menu_button("Help", |ui| {
                    ui.label(CONTROLS);
                });
            });
        });
    }

    pub(super) fn status_bar(&mut self, ui: &mut egui::Ui) {
        egui::Panel::bottom("status").show(ui, |ui| {
            ui.horizontal(|ui| {
                let (text, level) = self.status();
                let color = match level {
                    Level::Info => ui.visuals().text_color(),
                    Level::Warning => Color32::from_rgb(230, 190, 60),
                    Level::Error => Color32::from_rgb(255, 110, 100),
                };
                // One line, so a long message (a TOML error draws a caret diagram) never
                // shrinks the viewport, which would restart the reference; all of it on hover.
                let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
                let first = lines.next().unwrap_or_default();
                let line = match lines.next_back() {
                    Some(last) => format!("{first} … {last}"),
                    None => first.to_string(),
                };
                ui.add(egui::Label::new(RichText::new(line).color(color)).truncate())
                    .on_hover_text(text);
                let warnings = self.scene_warnings();
                if !warnings.is_empty() {
                    ui.label(
                        RichText::new(match warnings.len() {
                            1 => "1 warning".to_string(),
                            n => format!("{n} warnings"),
                        })
                        .color(Color32::from_rgb(230, 190, 60)),
                    )
                    .on_hover_text(warnings.join("\n"));
                }
                if let Some(core) = self.core.as_ref() {
                    let current = core
                        .shown(0)
                        .or_else(|| core.shown(1))
                        .map(|s| core.session.reference_key(&s.request));
                    let progress = core.tracing_progress().filter(|(k, _, _)| {
                        Some(*k).map(|k| k.samples) == current.map(|c| c.samples)
                    });
                    if let Some((_, done, total)) = progress {
                        if done < total && self.settings.needs_reference() {
                            ui.add(
                                egui::ProgressBar::new(done as f32 / total.max(1) as f32)
                                    .desired_width(160.0)
                                    .text(format!(
                                        "reference {done}/{total} samples ({})",
                                        core.reference_engine().name().to_uppercase()
                                    )),
                            );
                        }
                    }
                }
            });
        });
    }

    pub(super) fn controls_panel(&mut self, ui: &mut egui::Ui) {
        egui::Panel::left("controls")
            .default_size(250.0)
            .min_size(200.0)
            .resizable(true)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    self.scene_section(ui);
                    ui.separator();
                    self.method_section(ui);
                    ui.separator();
                    self.view_section(ui);
                    ui.separator();
                    self.overlay_section(ui);
                    ui.separator();
                    self.selection_section(ui);
                    ui.separator();
                    self.render_section(ui);
                });
            });
    }

    fn scene_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Scene");
        ui.label(RichText::new(&self.doc.label).small());
        let mut pick = None;
        egui::ComboBox::from_label("Built-in")
            .selected_text(if self.doc.path.is_none() {
                self.doc.name.clone()
            } else {
                "(file)".into()
            })
            .show_ui(ui, |ui| {
                for name in builtin::names() {
                    if ui.selectable_label(*name == self.doc.name, *name).clicked() {
                        pick = Some(name.to_string());
                    }
                }
            });
        ui.horizontal(|ui| {
            let l = ui.label("Scene path");
            let field = ui
                .add(
                    egui::TextEdit::singleline(&mut self.open_text)
                        .hint_text("scene.toml or mesh.obj")
                        .desired_width(120.0),
                )
                .labelled_by(l.id);
            let enter = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            if (ui.button("Open path").clicked() || enter) && !self.open_text.trim().is_empty() {
                pick = Some(self.open_text.trim().to_string());
            }
        });
        if ui.button("Open file…").clicked() {
            self.open_dialog();
        }
        if let Some(name) = pick {
            self.open_scene(&name);
        }
    }

    fn method_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Method");
        let current = self.settings.method();
        // Methods that cannot take the scene's light are greyed, their reason on hover.
        let light = self.doc.file.light.kind();
        // … and so are those the device cannot run (what it lacks on hover).
        let caps = self.core.as_ref().map(|c| c.ctx.caps.clone());
        let refuses = |m: Method| m.refusal(light, caps.as_ref());
        let listed = self.listed_methods();
        ui.horizontal_wrapped(|ui| {
            for &m in &listed {
                let refused = refuses(m);
                if ui
                    .add_enabled(
                        refused.is_none(),
                        egui::Button::selectable(current == m, m.name()),
                    )
                    .on_hover_text(m.description())
                    .on_disabled_hover_text(refused.unwrap_or_default())
                    .clicked()
                {
                    self.settings.method = m.name().into();
                }
            }
        });
        ui.label("V(t)");
        let vt = self.settings.vt();
        ui.horizontal_wrapped(|ui| {
            for v in VtVariant::ALL {
                if ui.selectable_label(vt == v, v.name()).clicked() {
                    self.settings.vt = v.name().into();
                }
            }
        });
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.settings.split, "Split view");
            let split = self.settings.split_method();
            egui::ComboBox::from_id_salt("split-method")
                .selected_text(format!("right: {}", split.name()))
                .show_ui(ui, |ui| {
                    for &m in &listed {
                        let refused = refuses(m);
                        if ui
                            .add_enabled(
                                refused.is_none(),
                                egui::Button::selectable(split == m, m.name()),
                            )
                            .on_disabled_hover_text(refused.unwrap_or_default())
                            .clicked()
                        {
                            self.settings.split_method = m.name().into();
                        }
                    }
                })
                .response
                .on_hover_text("the method on the right of the split");
        });
    }

    fn view_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("View");
        let current = self.settings.view;
        ui.horizontal_wrapped(|ui| {
            for v in View::ALL
                .into_iter()
                .filter(|v| *v != View::DBuffer && *v != View::Flip)
            {
                // The error view is |ΔV| or FLIP (the choice below it).
                let on = current == v || (v == View::Error && current == View::Flip);
                if ui
                    .selectable_label(on, v.name())
                    .on_hover_text(v.description())
                    .clicked()
                {
                    self.settings.view = v;
                }
            }
        });
        if matches!(current, View::Error | View::Flip) {
            ui.horizontal(|ui| {
                ui.label("Error");
                for (v, name) in [(View::Error, "|ΔV|"), (View::Flip, "FLIP")] {
                    if ui
                        .selectable_label(current == v, name)
                        .on_hover_text(v.description())
                        .clicked()
                    {
                        self.settings.view = v;
                    }
                }
            });
        }
        // The shown method's light-space channels (the D-buffer's by default).
        let channels = self
            .core
            .as_ref()
            .and_then(|c| c.session.light_maps(self.settings.method()))
            .map(|m| m.channels)
            .unwrap_or(crate::render::methods::dbuffer::CHANNELS);
        let names: Vec<&'static str> = channels.iter().map(|c| c.name).take(4).collect();
        ui.horizontal_wrapped(|ui| {
            for (c, name) in names.iter().enumerate() {
                let only = current == View::DBuffer
                    && self.settings.channels == std::array::from_fn(|k| k == c);
                if ui
                    .selectable_label(only, *name)
                    .on_hover_text("this light-space channel alone")
                    .clicked()
                {
                    self.settings.view = View::DBuffer;
                    self.settings.channels = std::array::from_fn(|k| k == c);
                }
            }
        });
        if current == View::DBuffer {
            ui.horizontal(|ui| {
                ui.label("Channels");
                for (c, letter) in ["R", "G", "B", "A"].iter().enumerate().take(names.len()) {
                    ui.checkbox(&mut self.settings.channels[c], *letter)
                        .on_hover_text(format!("{} (several: R, G, B composite)", names[c]));
                }
            });
        }
        let view = self.settings.view;
        if let Some(m) = self.settings.mapping_mut(view) {
            ui.horizontal(|ui| {
                let l = ui.label("Range");
                let speed = ((m.white - m.black).abs() * 0.005).max(1e-4);
                let b = ui
                    .add(DragValue::new(&mut m.black).speed(speed).max_decimals(4))
                    .labelled_by(l.id)
                    .on_hover_text("black point");
                let w = ui
                    .add(DragValue::new(&mut m.white).speed(speed).max_decimals(4))
                    .labelled_by(l.id)
                    .on_hover_text("white point");
                if b.changed() || w.changed() {
                    m.auto = false;
                }
            });
            ui.horizontal(|ui| {
                ui.checkbox(&mut m.auto, "Auto-fit");
                egui::ComboBox::from_label("Colour map")
                    .selected_text(m.map.name())
                    .show_ui(ui, |ui| {
                        for map in ColorMap::ALL {
                            ui.selectable_value(&mut m.map, map, map.name());
                        }
                    });
            });
        }
    }

    fn overlay_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Overlays");
        let o = &mut self.settings.overlays;
        ui.checkbox(&mut o.classes, "Face classes");
        ui.checkbox(&mut o.umbra_volume, "Umbra volume");
        ui.checkbox(&mut o.penumbra_volume, "Penumbra volume");
        ui.checkbox(&mut o.silhouettes, "Silhouette edges");
        ui.checkbox(&mut o.light_outline, "Light outline");
    }

    fn selection_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Selection");
        ui.horizontal_wrapped(|ui| {
            if ui
                .selectable_label(self.selection.is_light(), "light")
                .clicked()
            {
                self.selection = Selection::Light;
            }
            let names: Vec<String> = self
                .doc
                .file
                .objects
                .iter()
                .map(|o| o.display_name().to_string())
                .collect();
            for (i, name) in names.iter().enumerate() {
                if ui
                    .selectable_label(self.selection == Selection::Object(i), name)
                    .clicked()
                {
                    self.selection = Selection::Object(i);
                }
            }
        });
        match self.selection {
            Selection::None => {
                ui.label(RichText::new("click the light or an object in the viewport").small());
            }
            Selection::Light | Selection::LightEnd(_) => self.light_fields(ui),
            Selection::Object(i) => self.object_fields(ui, i),
        }
        ui.horizontal(|ui| {
            if ui
                .add_enabled(self.history.can_undo(), egui::Button::new("Undo"))
                .clicked()
            {
                self.undo();
            }
            if ui
                .add_enabled(self.history.can_redo(), egui::Button::new("Redo"))
                .clicked()
            {
                self.redo();
            }
        });
    }

    fn object_fields(&mut self, ui: &mut egui::Ui, i: usize) {
        let Some(mut object) = self.doc.file.objects.get(i).cloned() else {
            self.selection = Selection::None;
            return;
        };
        ui.label(RichText::new(format!("mesh {}", object.mesh)).small());
        let mut changed = number_row(ui, "Position", &mut object.translate, 0.01);
        changed |= number_row(ui, "Rotation °", &mut object.rotate_deg, 0.5);
        let mut uniform = matches!(object.scale, Scale::Uniform(_));
        let mut xyz = object.scale.xyz();
        if uniform {
            let mut s = [xyz[0]];
            if number_row(ui, "Scale", &mut s, 0.005) {
                changed = true;
                xyz = [s[0]; 3];
            }
        } else {
            changed |= number_row(ui, "Scale xyz", &mut xyz, 0.005);
        }
        if ui.checkbox(&mut uniform, "Uniform scale").changed() {
            changed = true;
        }
        // A zero factor is refused by the scene file; keep the field off it.
        for v in &mut xyz {
            if v.abs() < 1e-4 {
                *v = 1e-4_f64.copysign(*v);
            }
        }
        object.scale = if uniform {
            Scale::Uniform(xyz[0])
        } else {
            Scale::PerAxis(xyz)
        };
        if changed {
            self.edit_scene(|e| {
                if let Some(o) = e.objects.get_mut(i) {
                    *o = object;
                }
            });
        }
    }

    /// Where the reference's rays are traced: auto (the GPU where the adapter can), GPU or
    /// CPU, with the engine tracing now and why the GPU cannot, where it cannot.
    fn reference_engine_ui(&mut self, ui: &mut egui::Ui) {
        let refusal = self
            .core
            .as_ref()
            .and_then(|c| crate::render::gpu_reference::refuses_on(&c.ctx.caps));
        let now = self.core.as_ref().map(|c| c.reference_engine());
        let label = |e: &str| match e {
            "gpu" => "GPU",
            "cpu" => "CPU",
            _ => "auto",
        };
        let choice = self.settings.reference_engine.clone();
        // The choice, and where it differs from it the engine tracing now (auto's pick, or the
        // CPU standing in for a GPU that cannot).
        let selected = match now {
            Some(engine) if engine.name() != choice => {
                format!("{} ({})", label(&choice), label(engine.name()))
            }
            _ => label(&choice).to_string(),
        };
        let combo = egui::ComboBox::from_label("Reference engine")
            .selected_text(selected)
            .show_ui(ui, |ui| {
                for e in [super::settings::AUTO_ENGINE, "gpu", "cpu"] {
                    ui.selectable_value(
                        &mut self.settings.reference_engine,
                        e.to_string(),
                        label(e),
                    );
                }
            });
        let hover = match refusal {
            Some(why) => format!("where the reference's rays are traced; {why}"),
            None => "where the reference's rays are traced: the GPU (progressively, a batch of \
                     samples a frame) or the CPU's threads; auto takes the GPU where it can"
                .to_string(),
        };
        combo.response.on_hover_text(hover);
    }

    fn render_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Render");
        egui::ComboBox::from_label("D-buffer size")
            .selected_text(format!("{}²", self.settings.dbuffer_size))
            .show_ui(ui, |ui| {
                for n in [256, 512, 1024, 2048] {
                    ui.selectable_value(&mut self.settings.dbuffer_size, n, format!("{n}²"));
                }
            });
        ui.add(
            Slider::new(&mut self.settings.render_scale, 0.25..=1.0)
                .text("Resolution")
                .custom_formatter(|v, _| format!("{:.0} %", v * 100.0)),
        );
        let max = crate::render::methods::reference::MAX_SAMPLES;
        ui.horizontal(|ui| {
            let l = ui.label("Reference K");
            ui.add(DragValue::new(&mut self.settings.reference_samples).range(1..=max))
                .labelled_by(l.id)
                .on_hover_text("disk samples per pixel of the reference");
        });
        self.reference_engine_ui(ui);
        // The knobs of the shown methods, from their modules.
        let mut shown = vec![self.settings.method()];
        if self.settings.split {
            shown.push(self.settings.split_method());
        }
        // A knob two shown methods share (`sv-open`) is shown once.
        let mut knobs: Vec<&'static Knob> = Vec::new();
        for &knob in shown.iter().flat_map(|m| m.knobs()) {
            if !knobs.iter().any(|k| k.name == knob.name) {
                knobs.push(knob);
            }
        }
        for knob in knobs {
            if knob.name == crate::render::truth::SAMPLES.name {
                continue;
            }
            let mut value = self.settings.knobs.raw(knob);
            if knob_control(ui, knob, &mut value) {
                self.settings.knobs = self.settings.knobs.with(knob, value);
            }
        }
        for m in shown {
            self.user_knobs_ui(ui, m);
        }
    }
}

/// The lab's control of `knob` as its kind asks (a slider, a checkbox, a picker, a slider of the
/// fraction), editing `value`, the whole number its flag takes; whether it changed.
fn knob_control(ui: &mut egui::Ui, knob: &Knob, value: &mut u32) -> bool {
    let (min, max) = knob.range();
    let response = match knob.kind {
        KnobKind::Switch => {
            let mut on = *value != 0;
            let r = ui.checkbox(&mut on, knob.name);
            *value = u32::from(on);
            r
        }
        KnobKind::Choice { choices } => {
            let shown = choices.get(*value as usize).copied().unwrap_or("?");
            let mut r = egui::ComboBox::from_label(knob.name)
                .selected_text(shown)
                .show_ui(ui, |ui| {
                    let mut changed = false;
                    for (i, name) in (0u32..).zip(choices) {
                        changed |= ui.selectable_value(value, i, *name).changed();
                    }
                    changed
                });
            if r.inner == Some(true) {
                r.response.mark_changed();
            }
            r.response
        }
        KnobKind::Int { .. } => ui.add(
            Slider::new(value, min..=max)
                .text(knob.name)
                .logarithmic(max >= 64 * min.max(1)),
        ),
        KnobKind::Scaled { per, .. } => {
            let per = f64::from(per.max(1));
            let mut fraction = f64::from(*value) / per;
            let r = ui.add(
                Slider::new(&mut fraction, f64::from(min) / per..=f64::from(max) / per)
                    .text(knob.name)
                    .step_by(1.0 / per)
                    .fixed_decimals(per.log10().ceil() as usize),
            );
            *value = (fraction * per).round() as u32;
            r
        }
    };
    response.on_hover_text(knob.help).changed()
}

/// Controls, for the Help menu and the README.
pub const CONTROLS: &str = "\
Left drag: orbit · Middle or right drag: pan · Wheel: zoom · F: frame all
Click: select the light or an object · Drag the selection: move it on a plane facing the camera
Shift + drag the selection: move it along the ground · Ctrl+Z / Ctrl+Shift+Z: undo / redo
Split view: drag the yellow divider";
