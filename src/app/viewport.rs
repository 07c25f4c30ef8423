//! The central panel: records a frame when something changed (camera, light, an object, method,
//! V(t), size, the reference's samples) into targets that stay on the GPU, draws the chosen view
//! of it on the GPU into the texture the viewport shows (two methods split by a draggable divider
//! if asked), probes the few values a person reads (the pixel under the cursor, the samples of an
//! auto-fitted range), and turns mouse input into camera moves, selection and scene edits.

use eframe::egui::{self, Color32, Pos2, Rect, Sense, Vec2};
use glam::Vec3;

use super::camera::{self, Projector};
use super::doc::f3;
use super::motion::Measure;
use super::{LabApp, Level, Selection};
use crate::geometry::bvh::Bvh;
use crate::render::methods::reference::SAMPLES;
use crate::render::passes::probe::ProbeRequest;
use crate::render::passes::view::{Mapping, View, ViewParams};
use crate::render::passes::view_twin::NO_DATA;
use crate::render::session::FrameJob;
use crate::render::{FrameRequest, Method};
use crate::scene::{Camera, Light};

/// Everything that decides a frame's pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RenderKey {
    request: FrameRequest,
    camera: Camera,
    revision: u64,
    /// The reference snapshot the frame shades (the reference method only).
    reference: u64,
}

/// Everything that decides how a frame is shown.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ViewKey {
    params: ViewParams,
    /// The reference snapshot it compares with (the error view only).
    reference: u64,
}

/// What a slot shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Shown {
    pub method: Method,
    pub request: FrameRequest,
    /// The light the frame was rendered with.
    pub light: crate::scene::Light,
    /// Reference samples (done, total) on the GPU when the frame was shown, if any.
    pub reference: Option<(u32, u32)>,
    /// Why the view cannot be drawn as asked (e.g. no reference yet).
    pub note: Option<String>,
    /// Bumped for every new frame the slot shows.
    pub serial: u64,
}

/// What the mouse is doing in the viewport.
#[derive(Clone, Copy, Debug)]
pub enum Drag {
    Orbit,
    Pan,
    Split,
    Move {
        target: Selection,
        normal: Vec3,
        start_hit: Vec3,
        start_anchor: Vec3,
    },
}

/// The pixel under the mouse.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Hover {
    /// Over the right-hand (split) frame.
    pub split: bool,
    pub x: u32,
    pub y: u32,
}

#[derive(Default)]
pub struct ViewportState {
    pub shown: [Option<Shown>; 2],
    pub rect: Option<Rect>,
    pub drag: Option<Drag>,
    pub hover: Option<Hover>,
    keys: [Option<RenderKey>; 2],
    views: [Option<ViewKey>; 2],
    /// The frame and reference the FLIP map on the GPU was made for, and a count of the maps
    /// handed over (the FLIP view draws again when it grows).
    flipped: Option<(RenderKey, u64)>,
    flip_serial: u64,
    /// The frame and view the last fit probe of each slot was for.
    fitted: [Option<(RenderKey, View, [bool; 4])>; 2],
    /// The pixel probed last, per slot.
    probed: [Option<Probed>; 2],
    serial: u64,
    /// The size frames are rendered at, and a different one asked for by the last pass.
    size: Option<(u32, u32)>,
    asked: Option<(u32, u32)>,
}

impl ViewportState {
    /// The render size for a pass whose viewport is `asked` pixels: a new size is taken once two
    /// passes in a row ask for it. A panel laid out narrower for a single pass (egui does so when
    /// its content changes, e.g. as the cursor moves on) would otherwise make a frame at that
    /// size and start the reference over twice.
    fn settled_size(&mut self, asked: (u32, u32)) -> ((u32, u32), bool) {
        let size = *self.size.get_or_insert(asked);
        if asked == size {
            self.asked = None;
            return (size, true);
        }
        if self.asked == Some(asked) {
            self.size = Some(asked);
            self.asked = None;
            return (asked, true);
        }
        self.asked = Some(asked);
        (size, false)
    }
}

/// A pixel probe's circumstances: the pixel, the frame serial it was probed on, the view, and
/// the reference's serial then (the inspector shows the reference's V there, which grows as it
/// converges): any of them changed, the pixel is probed again.
type Probed = (u32, u32, u64, View, u64);

/// Colour of the divider and of selections.
pub const HIGHLIGHT: Color32 = Color32::from_rgb(255, 220, 60);

impl LabApp {
    pub(super) fn viewport_ui(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        let ctx = ui.ctx().clone();
        let mut rect = ui.available_rect_before_wrap();
        // Up to the inspector's fixed width, whatever width egui gave the panel this pass (it
        // lays it out a few points narrower for a pass when its rows change).
        rect.max.x = rect
            .max
            .x
            .min(ctx.content_rect().max.x - super::inspector::INSPECTOR_WIDTH)
            .max(rect.min.x);
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "viewport"));
        self.viewport.rect = Some(rect);
        // Where last frame's image will cover the viewport, nothing is painted under it: on a CPU
        // rasteriser every layer egui blends over the viewport costs about what the image does
        // (`dbuffer gui --bench`).
        // The window bench's floor: the window with its viewport's background and no image.
        let bench = self.window_bench.as_ref().and_then(|b| b.phase());
        let floor = bench == Some(super::window_bench::Phase::Blank);
        if floor || !self.image_covers_viewport() {
            let [r, g, b, _] = NO_DATA;
            ui.painter()
                .rect_filled(rect, 0.0, Color32::from_rgb(r, g, b));
        }
        let ppp = ctx.pixels_per_point();
        let scale = self.settings.render_scale;
        let w = (rect.width() * ppp * scale).round().max(0.0) as u32;
        let h = (rect.height() * ppp * scale).round().max(0.0) as u32;
        if w == 0 || h == 0 || rect.width() < 1.0 || rect.height() < 1.0 {
            // Collapsed or minimised: nothing to render (the render core refuses size 0).
            return;
        }
        self.interact(&ctx, &response, rect);
        let image_rect = self.image_rect(rect);
        self.hover(&response, image_rect);
        let ((w, h), settled) = self.viewport.settled_size((w, h));
        if !settled {
            ctx.request_repaint();
        }
        if floor {
            return;
        }
        if bench != Some(super::window_bench::Phase::Image) {
            self.render_if_needed(&ctx, frame, w, h);
        }
        self.paint_frames(ui, image_rect);
        if self.settings.view != View::DBuffer {
            self.draw_overlays(ui.painter(), image_rect);
        }
        self.draw_legends(ui, rect);
        self.draw_motion(ui, rect);
        if let Some(note) = self.viewport_note() {
            ui.painter().text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                note,
                egui::FontId::proportional(14.0),
                Color32::from_rgb(255, 140, 120),
            );
        }
    }

    /// The motion meter's plot, top right of the viewport, while a drag moves the light or a
    /// caster (and shortly after).
    fn draw_motion(&self, ui: &egui::Ui, rect: Rect) {
        if !self.motion.showing() {
            return;
        }
        let (values, measure) = self.motion.series();
        let Some(measure) = measure else { return };
        let size = Vec2::new(260.0f32.min(rect.width() - 16.0), 74.0);
        let area = Rect::from_min_size(
            Pos2::new(rect.right() - size.x - 8.0, rect.top() + 8.0),
            size,
        );
        if size.x < 120.0 {
            return;
        }
        let painter = ui.painter().with_clip_rect(area);
        painter.rect_filled(area, 4.0, Color32::from_black_alpha(170));
        let title = match measure {
            Measure::AgainstReference => "temporal error",
            Measure::MethodAlone => "frame-to-frame |ΔV|",
        };
        let top = values.iter().copied().fold(0.01f32, f32::max);
        painter.text(
            area.left_top() + Vec2::new(6.0, 3.0),
            egui::Align2::LEFT_TOP,
            format!(
                "{title}: {:.4} (max {top:.3})",
                values.last().copied().unwrap_or(0.0)
            ),
            egui::FontId::proportional(11.0),
            Color32::WHITE,
        );
        let plot = Rect::from_min_max(
            area.left_top() + Vec2::new(6.0, 18.0),
            area.right_bottom() - Vec2::new(6.0, 14.0),
        );
        if values.len() >= 2 {
            let n = values.len() - 1;
            let points: Vec<Pos2> = values
                .iter()
                .enumerate()
                .map(|(k, v)| {
                    Pos2::new(
                        plot.left() + plot.width() * k as f32 / n as f32,
                        plot.bottom() - plot.height() * (v / top).clamp(0.0, 1.0),
                    )
                })
                .collect();
            painter.add(egui::Shape::line(
                points,
                egui::Stroke::new(1.5, Color32::from_rgb(250, 170, 60)),
            ));
        }
        painter.text(
            area.left_bottom() + Vec2::new(6.0, -2.0),
            egui::Align2::LEFT_BOTTOM,
            format!(
                "last {} s · {}",
                super::motion::WINDOW.as_secs(),
                measure.short()
            ),
            egui::FontId::proportional(9.0),
            Color32::GRAY,
        );
    }

    /// Where the image goes inside the viewport: all of it, or a centred square for the
    /// light-space view (which is square).
    fn image_rect(&self, rect: Rect) -> Rect {
        if self.settings.view == View::DBuffer {
            let side = rect.width().min(rect.height());
            Rect::from_center_size(rect.center(), Vec2::splat(side))
        } else {
            rect
        }
    }

    fn viewport_note(&self) -> Option<String> {
        if let Some(e) = &self.render_error {
            return Some(e.clone());
        }
        self.viewport.shown[0].as_ref().and_then(|s| s.note.clone())
    }

    pub(super) fn base_request(&self, width: u32, height: u32) -> FrameRequest {
        let knobs = self.settings.knobs;
        FrameRequest {
            width,
            height,
            dbuffer_size: self.settings.dbuffer_size,
            method: self.settings.method(),
            vt: self.settings.vt(),
            knobs: knobs.with(&SAMPLES, self.settings.reference_samples),
            read_dbuffer: false,
            read_cost: false,
            colour_only: false,
        }
    }

    fn view_params(&self) -> ViewParams {
        let view = self.settings.view;
        ViewParams {
            view,
            channels: self.settings.channels,
            mapping: self
                .settings
                .mapping(view)
                .copied()
                .unwrap_or_else(Mapping::unit),
        }
    }

    fn render_if_needed(
        &mut self,
        ctx: &egui::Context,
        frame: &eframe::Frame,
        width: u32,
        height: u32,
    ) {
        let base = self.base_request(width, height);
        let params = self.view_params();
        let methods = [
            Some(self.settings.method()),
            self.settings.split.then(|| self.settings.split_method()),
        ];
        let needs_reference = self.settings.needs_reference();
        let hover = self.viewport.hover;
        let revision = self.revision;
        // A drag of the light or a caster: the motion meter follows the shown method.
        let moving = matches!(
            self.viewport.drag,
            Some(Drag::Move {
                target: Selection::Light | Selection::LightEnd(_) | Selection::Object(_),
                ..
            })
        );
        // Turning the camera: the inspector waits for the drag to end (its pixel shows another
        // surface every frame), so the final image needs the colour alone
        // (`FrameRequest::colour_only`: on lavapipe a third of the camera pass).
        let turning = matches!(self.viewport.drag, Some(Drag::Orbit | Drag::Pan));
        let hover = hover.filter(|_| !turning);
        let base = FrameRequest {
            colour_only: params.view == View::Final && !moving && hover.is_none(),
            ..base
        };
        let camera = self.camera;
        let Some(core) = self.core.as_mut() else {
            return;
        };
        core.session.set_camera(camera);
        let mut errors = Vec::new();

        // The reference: rays on the worker thread, finished samples to the GPU.
        let reference_request = FrameRequest {
            method: Method::REFERENCE,
            ..base
        };
        if needs_reference {
            let key = core.session.reference_key(&reference_request);
            core.worker.want(core.session.scene(), key);
            if let Err(e) = core.take_reference() {
                errors.push(format!("reference: {e}"));
            }
            if core.worker.busy() {
                // Keep frames coming while it converges (new samples about every 90 ms).
                ctx.request_repaint_after(std::time::Duration::from_millis(30));
            }
        } else {
            core.worker.pause();
        }
        let reference_ready = core.session.has_reference(&reference_request);
        let reference_serial = if reference_ready {
            core.reference_serial
        } else {
            0
        };
        let progress = core
            .session
            .reference_progress()
            .filter(|_| reference_ready);

        // The exact hard shadow: its rays on a worker too, V to the GPU when done; meanwhile the
        // slot keeps its last picture and says what it waits for.
        let hard_request = FrameRequest {
            method: Method::REFERENCE_HARD,
            ..base
        };
        if methods.contains(&Some(Method::REFERENCE_HARD)) {
            if let Err(e) = core.take_reference_hard() {
                errors.push(format!("reference-hard: {e}"));
            }
            if !core.session.has_reference_hard(&hard_request) {
                let key = core.session.reference_hard_key(&hard_request);
                core.hard_worker.want(core.session.scene(), key);
            }
            if core.hard_worker.busy() {
                ctx.request_repaint_after(std::time::Duration::from_millis(30));
            }
        } else {
            core.hard_worker.pause();
        }
        let hard_ready = core.session.has_reference_hard(&hard_request);
        let hard_serial = if hard_ready { core.hard_serial } else { 0 };

        let [main_slot, split_slot] = &mut core.slots;
        let mut jobs: Vec<FrameJob<'_>> = Vec::new();
        for (i, (slot, method)) in [main_slot, split_slot].into_iter().zip(methods).enumerate() {
            let Some(method) = method else {
                self.viewport.shown[i] = None;
                self.viewport.keys[i] = None;
                self.viewport.views[i] = None;
                continue;
            };
            // A method that cannot take this light draws nothing and says why (never a
            // picture made with another light).
            if let Some(why) =
                method.refusal(core.session.scene().light.kind(), Some(&core.ctx.caps))
            {
                self.viewport.shown[i] = None;
                self.viewport.keys[i] = None;
                self.viewport.views[i] = None;
                errors.push(why);
                continue;
            }
            let request = FrameRequest { method, ..base };
            if method.is_reference() && !reference_ready {
                let shown = self.viewport.shown[i].get_or_insert_with(|| Shown {
                    method,
                    request,
                    light: core.session.scene().light,
                    reference: None,
                    note: None,
                    serial: 0,
                });
                shown.note = Some("reference: waiting for its first samples".into());
                continue;
            }
            if method == Method::REFERENCE_HARD && !hard_ready {
                let shown = self.viewport.shown[i].get_or_insert_with(|| Shown {
                    method,
                    request,
                    light: core.session.scene().light,
                    reference: None,
                    note: None,
                    serial: 0,
                });
                shown.note = Some("reference-hard: casting its rays (off the UI thread)…".into());
                continue;
            }
            // Whether a frame is colour-only is not what it shows: the mouse leaving the
            // viewport renders nothing again, and a view or probe that needs the V/t target of
            // a colour-only frame has the render core draw it in full.
            let key = RenderKey {
                request: FrameRequest {
                    colour_only: false,
                    ..request
                },
                camera,
                revision,
                reference: if method.is_reference() {
                    reference_serial
                } else if method == Method::REFERENCE_HARD {
                    hard_serial
                } else {
                    0
                },
            };
            let view_key = ViewKey {
                params,
                reference: match params.view {
                    View::Error => reference_serial,
                    View::Flip => self.viewport.flip_serial,
                    _ => 0,
                },
            };
            let render = self.viewport.keys[i] != Some(key) || slot.targets.rendered.is_none();
            let redraw = render || self.viewport.views[i] != Some(view_key);
            let mut probes = Vec::new();
            let serial = if render {
                self.viewport.serial + 1
            } else {
                self.viewport.shown[i].as_ref().map_or(0, |s| s.serial)
            };
            if let Some(h) = hover.filter(|h| h.split == (i == 1)) {
                let here = Some((h.x, h.y, serial, params.view, reference_serial));
                if redraw || self.viewport.probed[i] != here {
                    probes.push(ProbeRequest::Pixel {
                        x: h.x,
                        y: h.y,
                        params,
                    });
                    self.viewport.probed[i] = here;
                }
            }
            if moving && render && i == 0 {
                let tag = self
                    .motion
                    .frame(core.session.scene(), request.width, request.height);
                probes.push(ProbeRequest::Motion { tag, params });
            }
            let fit_key = Some((key, params.view, params.channels));
            if params.mapping.auto
                && params.view != View::Final
                && params.view != View::Classes
                && (self.viewport.fitted[i] != fit_key
                    || view_key.reference != self.viewport.views[i].map_or(0, |v| v.reference))
            {
                probes.push(ProbeRequest::Fit { params });
                self.viewport.fitted[i] = fit_key;
            }
            if !redraw && probes.is_empty() {
                continue;
            }
            if render {
                self.viewport.serial += 1;
            }
            self.viewport.keys[i] = Some(key);
            self.viewport.views[i] = Some(view_key);
            let note = (matches!(params.view, View::Error | View::Flip) && !reference_ready)
                .then(|| "no reference of this size yet: the error view waits for it".to_string());
            self.viewport.shown[i] = Some(Shown {
                method,
                request,
                light: core.session.scene().light,
                reference: progress,
                note,
                serial: self.viewport.serial,
            });
            jobs.push(FrameJob {
                targets: &mut slot.targets,
                request,
                view: Some(params),
                render,
                probes,
            });
        }
        if !jobs.is_empty() {
            let builds = core.session.geometry_builds(base.method).0;
            let t = std::time::Instant::now();
            match core.session.submit(&core.ctx, &mut jobs) {
                Ok(bytes) => {
                    // As submitted: a view that needs a colour-only frame in full renders it.
                    let renders = jobs.iter().filter(|j| j.render).count();
                    drop(jobs);
                    let wall_ms = t.elapsed().as_secs_f64() * 1e3;
                    let (after, geometry_ms) = core.session.geometry_builds(base.method);
                    let rebuilt = (after != builds).then_some(geometry_ms);
                    self.stats.submitted(renders, wall_ms, rebuilt, bytes);
                }
                Err(e) => errors.push(e.to_string()),
            }
        } else {
            drop(jobs);
            self.stats.submitted(0, 0.0, None, 0);
        }
        // The FLIP view: the main slot's image against the reference's, on this thread, once per
        // new frame or reference snapshot; drawn by the next frame's view pass.
        if params.view == View::Flip && reference_ready {
            if let Some(key) = self.viewport.keys[0] {
                let wanted = Some((key, reference_serial));
                if self.viewport.flipped != wanted {
                    match flip_map(core, &key.request) {
                        Ok(()) => {
                            self.viewport.flipped = wanted;
                            self.viewport.flip_serial += 1;
                            ctx.request_repaint();
                        }
                        Err(e) => errors.push(format!("FLIP: {e}")),
                    }
                }
            }
        }
        if let Some(rs) = frame.wgpu_render_state() {
            core.register_textures(rs);
        }
        if let Some(timings) = core.session.poll_timings(&core.ctx) {
            self.stats.gpu(timings);
        }
        // Overlay data some methods get back from the GPU a frame later (hybrid's walls): look
        // again shortly, without spinning.
        if core.session.poll_geometry(&core.ctx) {
            ctx.request_repaint_after(std::time::Duration::from_millis(15));
        }
        // A scripted (deterministic) window waits for its answers here, so it settles in a
        // known number of frames whatever the load on the GPU: a test's `run()` then never
        // runs out of steps while lavapipe is still busy with the frame the probe reads.
        for (i, results) in core
            .probe_results(self.deterministic)
            .into_iter()
            .enumerate()
        {
            if !results.is_empty() {
                // The panels drawn before the viewport show them on the next frame.
                ctx.request_repaint();
            }
            for r in results {
                match r.request {
                    ProbeRequest::Pixel { x, y, params } => {
                        self.inspector.arrived(i, x, y, params.view, r.values);
                    }
                    ProbeRequest::Motion { tag, .. } if i == 0 => {
                        self.motion.arrived(tag, r.values);
                        ctx.request_repaint();
                    }
                    ProbeRequest::Motion { .. } => {}
                    ProbeRequest::Fit { params } => {
                        if let Some(m) = self.settings.mapping_mut(params.view) {
                            let before = *m;
                            m.fit(r.values.iter().copied());
                            if *m != before {
                                ctx.request_repaint();
                            }
                        }
                    }
                }
            }
        }
        // Answers still on their way are picked up by the next frame.
        if core
            .slots
            .iter()
            .any(|s| s.targets.probe.as_ref().is_some_and(|p| p.pending()))
        {
            ctx.request_repaint();
        }
        // The light-space view of a method that keeps no such maps says so.
        for shown in self.viewport.shown.iter_mut().flatten() {
            if params.view == View::DBuffer && core.session.light_maps(shown.method).is_none() {
                shown.note = Some(format!("{} keeps no light-space maps", shown.method));
            }
        }
        if errors.is_empty() {
            self.render_error = None;
        } else {
            let text = errors.join("; ");
            if self.render_error.as_deref() != Some(text.as_str()) {
                self.set_status(text.clone(), Level::Error);
            }
            self.render_error = Some(text);
        }
    }

    /// Whether [`Self::paint_frames`] will cover the whole viewport with an image: a view as
    /// large as the viewport (not the D-buffer's square) with a texture for every side shown.
    fn image_covers_viewport(&self) -> bool {
        let Some(core) = self.core.as_ref() else {
            return false;
        };
        let sides = if self.settings.split { 2 } else { 1 };
        self.settings.view != View::DBuffer
            && (0..sides).all(|k| {
                self.viewport.shown[k].is_some()
                    && core.slots.get(k).is_some_and(|s| s.texture.is_some())
            })
    }

    fn split_x(&self, rect: Rect) -> Option<f32> {
        (self.settings.split && self.viewport.shown[1].is_some())
            .then(|| rect.left() + rect.width() * self.settings.split_at)
    }

    fn paint_frames(&self, ui: &egui::Ui, rect: Rect) {
        let painter = ui.painter();
        let Some(core) = self.core.as_ref() else {
            return;
        };
        let Some(main) = self.viewport.shown[0].as_ref() else {
            return;
        };
        let split_x = self.split_x(rect);
        // Every view's display is opaque (the view pass draws "no surface"): nothing under it.
        let texture = |slot: usize| core.slots[slot].texture.map(|(id, _)| id);
        if let Some(id) = texture(0) {
            match split_x {
                None => {
                    let full = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
                    painter.image(id, rect, full, Color32::WHITE);
                }
                Some(x) => {
                    let s = self.settings.split_at;
                    let left = Rect::from_min_max(rect.min, Pos2::new(x, rect.bottom()));
                    let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(s, 1.0));
                    painter.image(id, left, uv, Color32::WHITE);
                }
            }
        }
        let label = |pos: Pos2, align: egui::Align2, text: String| {
            painter.text(
                pos,
                align,
                text,
                egui::FontId::proportional(13.0),
                Color32::WHITE,
            );
        };
        if let (Some(x), Some(split)) = (split_x, self.viewport.shown[1].as_ref()) {
            if let Some(id) = texture(1) {
                let s = self.settings.split_at;
                let right = Rect::from_min_max(Pos2::new(x, rect.top()), rect.max);
                let uv = Rect::from_min_max(Pos2::new(s, 0.0), Pos2::new(1.0, 1.0));
                painter.image(id, right, uv, Color32::WHITE);
            }
            painter.line_segment(
                [Pos2::new(x, rect.top()), Pos2::new(x, rect.bottom())],
                egui::Stroke::new(2.0, HIGHLIGHT),
            );
            label(
                Pos2::new(x - 6.0, rect.top() + 4.0),
                egui::Align2::RIGHT_TOP,
                main.method.name().to_string(),
            );
            label(
                Pos2::new(x + 6.0, rect.top() + 4.0),
                egui::Align2::LEFT_TOP,
                split.method.name().to_string(),
            );
        }
    }

    fn hover(&mut self, response: &egui::Response, rect: Rect) {
        self.viewport.hover = None;
        let Some(pos) = response.hover_pos() else {
            return;
        };
        let split = self.split_x(rect).is_some_and(|x| pos.x >= x);
        let Some(shown) = self.viewport.shown[usize::from(split)].as_ref() else {
            return;
        };
        let r = &shown.request;
        let (w, h) = if self.settings.view == View::DBuffer {
            (r.dbuffer_size, r.dbuffer_size)
        } else {
            (r.width, r.height)
        };
        if let Some((x, y)) = camera::pixel_at(rect, pos, w, h) {
            self.viewport.hover = Some(Hover { split, x, y });
        }
    }

    fn interact(&mut self, ctx: &egui::Context, response: &egui::Response, rect: Rect) {
        if response.hovered() {
            let scroll = ctx.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.camera = camera::zoom(&self.camera, scroll / 50.0);
            }
        }
        if response.drag_started() {
            let press = ctx
                .input(|i| i.pointer.press_origin())
                .or_else(|| response.interact_pointer_pos());
            let (other_button, shift) = ctx.input(|i| {
                (
                    i.pointer.button_down(egui::PointerButton::Middle)
                        || i.pointer.button_down(egui::PointerButton::Secondary),
                    i.modifiers.shift,
                )
            });
            let near_divider = match (press, self.split_x(self.image_rect(rect))) {
                (Some(p), Some(x)) => (p.x - x).abs() < 6.0,
                _ => false,
            };
            self.viewport.drag = Some(if other_button {
                Drag::Pan
            } else if near_divider {
                Drag::Split
            } else {
                press
                    .and_then(|p| self.start_move(rect, p, shift))
                    .unwrap_or(Drag::Orbit)
            });
        }
        if response.dragged() {
            let delta = response.drag_delta();
            match self.viewport.drag {
                Some(Drag::Orbit) => {
                    self.camera = camera::orbit(&self.camera, delta.x * 0.008, delta.y * 0.008);
                }
                Some(Drag::Pan) => {
                    self.camera = camera::pan(&self.camera, delta.x, delta.y, rect.height());
                }
                Some(Drag::Split) => {
                    if let Some(p) = response.interact_pointer_pos() {
                        let r = self.image_rect(rect);
                        self.settings.split_at = ((p.x - r.left()) / r.width()).clamp(0.02, 0.98);
                    }
                }
                Some(Drag::Move {
                    target,
                    normal,
                    start_hit,
                    start_anchor,
                }) => {
                    let hit = response
                        .interact_pointer_pos()
                        .and_then(|p| camera::ray_at(&self.camera, rect, p))
                        .and_then(|(o, d)| camera::ray_plane(o, d, start_hit, normal));
                    if let Some(hit) = hit {
                        let to = f3(start_anchor + (hit - start_hit));
                        self.edit_scene(|e| match target {
                            Selection::Light => e.light.set_center(to),
                            Selection::LightEnd(k) => e.light.set_corner(k, to),
                            Selection::Object(i) => {
                                if let Some(o) = e.objects.get_mut(i) {
                                    o.translate = to;
                                }
                            }
                            Selection::None => {}
                        });
                    }
                }
                None => {}
            }
        }
        if response.drag_stopped() {
            self.viewport.drag = None;
            self.motion.drag_ended();
            // The plot lingers a moment after the drag: draw it away then.
            ctx.request_repaint_after(std::time::Duration::from_secs(4));
            self.history.close();
        }
        if response.clicked() {
            if let Some(p) = response.interact_pointer_pos() {
                self.selection = camera::ray_at(&self.camera, rect, p)
                    .map_or(Selection::None, |(o, d)| self.pick(o, d));
            }
        }
    }

    /// A move of the selection if the press was on it: on the plane through it facing the
    /// camera, or (Shift) on the horizontal plane through it.
    fn start_move(&mut self, rect: Rect, press: Pos2, shift: bool) -> Option<Drag> {
        if self.selection == Selection::None || self.settings.view == View::DBuffer {
            return None;
        }
        let (origin, dir) = camera::ray_at(&self.camera, rect, press)?;
        let picked = self.pick(origin, dir);
        if picked.is_light() && self.selection.is_light() {
            // A line light selected: the press decides whether an end or the whole segment moves.
            self.selection = picked;
        } else if picked != self.selection {
            return None;
        }
        let anchor = match self.selection {
            Selection::Light => self.doc.light().center(),
            Selection::LightEnd(k) => match self.doc.light() {
                Light::Line(l) if k == 0 => l.a,
                Light::Line(l) => l.b,
                Light::Area(a) => *a.corners()?.vertices().get(k)?,
            },
            Selection::Object(i) => {
                let t = self.doc.file.objects.get(i)?.translate;
                Vec3::new(t[0] as f32, t[1] as f32, t[2] as f32)
            }
            Selection::None => return None,
        };
        let normal = match (self.selection, self.doc.light()) {
            // A corner handle moves in the light's own plane.
            (Selection::LightEnd(_), Light::Area(a)) => a.normal,
            _ if shift => Vec3::Y,
            _ => camera::basis(&self.camera).2,
        };
        let start_hit = camera::ray_plane(origin, dir, anchor, normal)?;
        Some(Drag::Move {
            target: self.selection,
            normal,
            start_hit,
            start_anchor: anchor,
        })
    }

    /// The nearest of the light disk and the objects along a ray.
    pub fn pick(&mut self, origin: Vec3, dir: Vec3) -> Selection {
        let mut best = (f32::INFINITY, Selection::None);
        let Some(core) = self.core.as_ref() else {
            return Selection::None;
        };
        match core.scene().light {
            Light::Area(light) => {
                if let Some(p) = camera::ray_plane(origin, dir, light.center, light.normal) {
                    let t = (p - origin).length();
                    // A rectangle's or polygon's corner within a few pixels' width (as a line
                    // light's end) is its handle; elsewhere in its disk the whole light.
                    let corner = light.corners().and_then(|c| {
                        c.vertices()
                            .iter()
                            .position(|v| v.distance(p) <= 0.012 * t + 0.02)
                    });
                    if let Some(k) = corner {
                        best = (t, Selection::LightEnd(k));
                    } else if (p - light.center).length() <= light.radius * 1.15 {
                        best = (t, Selection::Light);
                    }
                }
            }
            Light::Line(line) => {
                // The point of the segment nearest the ray, within a few pixels' width (a
                // hundredth of its distance): an end (its outer fifth) or the whole segment.
                let (t, s, gap) = ray_segment(origin, dir, line.a, line.b);
                if t > 0.0 && gap <= 0.015 * t + 0.02 {
                    let pick = if s < 0.2 {
                        Selection::LightEnd(0)
                    } else if s > 0.8 {
                        Selection::LightEnd(1)
                    } else {
                        Selection::Light
                    };
                    best = (t, pick);
                }
            }
        }
        let objects = &core.scene().objects;
        self.bvhs.resize_with(objects.len(), || None);
        for (i, object) in objects.iter().enumerate() {
            let bvh = self.bvhs[i]
                .get_or_insert_with(|| Bvh::build(object.mesh.triangle_corners().collect()));
            if let Some(hit) = bvh.closest_hit(origin, dir, 0.0, best.0) {
                if hit.t < best.0 {
                    best = (hit.t, Selection::Object(i));
                }
            }
        }
        best.1
    }

    /// The light centre's screen position in the viewport, if it is in front of the camera.
    pub fn light_screen_pos(&self) -> Option<Pos2> {
        let rect = self.viewport.rect?;
        Projector::new(&self.camera, rect).point(self.doc.light().center())
    }

    /// Where world point `p` is drawn in the viewport.
    pub fn screen_pos(&self, p: Vec3) -> Option<Pos2> {
        let rect = self.viewport.rect?;
        Projector::new(&self.camera, rect).point(p)
    }
}

/// The FLIP map of the main slot's frame (`request`) against the reference's shaded image of
/// the same view, handed to the GPU for the FLIP view: the reference's camera pass into the
/// core's own targets, both images read back (what the map needs: two colour images), FLIP.
fn flip_map(core: &mut super::core::Core, request: &FrameRequest) -> Result<(), String> {
    use crate::geometry::flip;
    let reference = FrameRequest {
        method: Method::REFERENCE,
        ..*request
    };
    core.session
        .submit(
            &core.ctx,
            &mut [FrameJob {
                targets: &mut core.flip_targets,
                request: reference,
                view: None,
                render: true,
                probes: Vec::new(),
            }],
        )
        .map_err(|e| e.to_string())?;
    let truth = core
        .session
        .read(&core.ctx, &mut core.flip_targets, None)
        .map_err(|e| e.to_string())?;
    let shown = core.read_slot(0, None).map_err(|e| e.to_string())?;
    let map = flip::ldr_flip(
        &crate::compare::rgb_of(&truth),
        &crate::compare::rgb_of(&shown),
        shown.width,
        shown.height,
        flip::DEFAULT_PPD,
    )
    .map_err(|e| e.to_string())?;
    let key = core.session.reference_key(&reference);
    core.session
        .set_flip(&core.ctx, key, &map)
        .map_err(|e| e.to_string())
}

/// The closest approach of the ray `origin + t·dir` (unit `dir`) to the segment `a`–`b`: the
/// ray's `t`, the segment's parameter `s` ∈ [0, 1], and the distance between the two points.
fn ray_segment(origin: Vec3, dir: Vec3, a: Vec3, b: Vec3) -> (f32, f32, f32) {
    let e = b - a;
    let w = origin - a;
    let (ee, de, dw, ew) = (e.dot(e), dir.dot(e), dir.dot(w), e.dot(w));
    let denom = ee - de * de;
    let s = if denom > 1e-12 * ee.max(1e-12) {
        ((ew - de * dw) / denom).clamp(0.0, 1.0)
    } else {
        0.5
    };
    let q = a + e * s;
    let t = (q - origin).dot(dir);
    (t, s, (origin + dir * t - q).length())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_size_asked_for_one_pass_is_not_rendered_two_passes_are() {
        let mut v = ViewportState::default();
        assert_eq!(v.settled_size((695, 750)), ((695, 750), true));
        // One pass at another width (a panel laid out narrower), then back: never taken.
        assert_eq!(v.settled_size((701, 750)), ((695, 750), false));
        assert_eq!(v.settled_size((695, 750)), ((695, 750), true));
        // A real resize: taken on its second pass, and kept.
        assert_eq!(v.settled_size((800, 600)), ((695, 750), false));
        assert_eq!(v.settled_size((800, 600)), ((800, 600), true));
        assert_eq!(v.settled_size((800, 600)), ((800, 600), true));
        // A window dragged wider every pass is followed once it holds a size for two passes.
        assert_eq!(v.settled_size((810, 600)), ((800, 600), false));
        assert_eq!(v.settled_size((820, 600)), ((800, 600), false));
        assert_eq!(v.settled_size((820, 600)), ((820, 600), true));
    }
}
