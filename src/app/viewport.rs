//! The central panel: tells the view session ([`ViewSession`]) what to show (methods, view, the
//! pixel under the cursor, whether something is dragged), shows the texture it draws each side's
//! view into (two methods split by a draggable divider if asked), hands what comes back to the
//! inspector, the motion meter and the Stats panel, and turns mouse input into camera moves,
//! selection and scene edits (`pointer.rs`).

use eframe::egui::{self, Color32, Pos2, Rect, Sense, Vec2};
use eframe::{egui_wgpu, wgpu};
use glam::Vec3;

use super::camera::{self, Projector};
use super::{LabApp, Level, Selection};
use crate::render::passes::probe::{range_count, ProbeRequest};
use crate::render::passes::view::{Mapping, View, ViewParams};
use crate::render::passes::view_twin::NO_DATA;
use crate::render::truth;
use crate::render::view_session::{Intent, PixelProbe, Update, ViewSession};
use crate::render::FrameRequest;

pub use crate::render::view_session::Shown;

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
    pub rect: Option<Rect>,
    pub drag: Option<Drag>,
    pub hover: Option<Hover>,
    /// The egui texture showing each side's display, and the display generation it was
    /// registered for.
    textures: [Option<(egui::TextureId, u64)>; 2],
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

    /// Where the image goes inside the viewport: all of it, or a centred square for the
    /// light-space view (which is square).
    pub(super) fn image_rect(&self, rect: Rect) -> Rect {
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
        self.shown_at(0).and_then(|s| s.note.clone())
    }

    pub(super) fn base_request(&self, width: u32, height: u32) -> FrameRequest {
        let mut knobs = self.settings.knobs;
        // The overlays of the geometry stage (classes, silhouettes, volumes) draw what the CPU
        // stage made, which the GPU stage keeps on the GPU: with one on, `auto` runs it on the
        // CPU (`gpu` chosen by name keeps the GPU, and the overlay says it has nothing).
        let o = self.settings.overlays;
        let geometry = &crate::render::methods::dbuffer::GEOMETRY;
        if (o.classes || o.umbra_volume || o.penumbra_volume || o.silhouettes)
            && knobs.get(geometry) == 0
        {
            knobs = knobs.with(geometry, 1);
        }
        FrameRequest {
            width,
            height,
            dbuffer_size: self.settings.dbuffer_size,
            method: self.settings.method(),
            vt: self.settings.vt(),
            knobs: truth::with_samples(knobs, self.settings.reference_samples),
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
        // A drag of the light or a caster: the motion meter follows the shown method.
        let moving = matches!(
            self.viewport.drag,
            Some(Drag::Move {
                target: Selection::Light | Selection::LightEnd(_) | Selection::Object(_),
                ..
            })
        );
        // Turning the camera: the inspector waits for the drag to end (its pixel shows another
        // surface every frame).
        let turning = matches!(self.viewport.drag, Some(Drag::Orbit | Drag::Pan));
        let probe = self
            .viewport
            .hover
            .filter(|_| !turning)
            .map(|h| PixelProbe {
                side: usize::from(h.split),
                x: h.x,
                y: h.y,
            });
        let intent = Intent {
            request: self.base_request(width, height),
            split: self.settings.split.then(|| self.settings.split_method()),
            params: self.view_params(),
            probe,
            moving,
            // A scripted (deterministic) window waits for its answers, so it settles in a known
            // number of frames whatever the load on the GPU: a test's `run()` then never runs
            // out of steps while lavapipe is still busy with the frame the probe reads.
            wait: self.deterministic,
        };
        let camera = self.camera;
        let Some(core) = self.core.as_mut() else {
            return;
        };
        core.set_camera(camera);
        core.set_reference_engine(self.settings.reference_engine());
        let motion = &mut self.motion;
        let update = core.advance(&intent, &mut |scene, w, h| motion.frame(scene, w, h));
        if let Some(rs) = frame.wgpu_render_state() {
            register_textures(core, &mut self.viewport.textures, rs);
        }
        self.take_update(ctx, update);
    }

    /// What the view session did and what came back: statistics, probe answers (the
    /// inspector, the motion meter, the display range's fit), repaints, errors.
    fn take_update(&mut self, ctx: &egui::Context, update: Update) {
        if update.captured && crate::render::context::renderdoc_attached() != Some(false) {
            self.set_status(
                "Captured one frame for the graphics debugger (RenderDoc lists it under its \
                 captures)",
                Level::Info,
            );
        }
        if update.methods_changed {
            // The Stats panel lists the passes of the methods shown, not those shown before.
            self.stats.gpu.clear();
        }
        if let Some(s) = update.submitted {
            self.stats
                .submitted(s.renders, s.wall_ms, s.rebuilt, s.bytes);
        }
        if let Some(timings) = update.timings {
            self.stats.gpu(timings);
        }
        if update.repaint.now {
            // The panels drawn before the viewport show what arrived on the next frame.
            ctx.request_repaint();
        }
        if let Some(after) = update.repaint.after {
            ctx.request_repaint_after(after);
        }
        for (i, results) in update.probes.into_iter().enumerate() {
            for r in results {
                match r.request {
                    ProbeRequest::Pixel { x, y, params } => {
                        self.inspector.arrived(i, x, y, params.view, r.values);
                    }
                    ProbeRequest::Motion { tag, .. } if i == 0 => {
                        self.motion.arrived(tag, r.values);
                    }
                    ProbeRequest::Motion { .. } => {}
                    ProbeRequest::Range { .. } => {
                        let count = range_count(&r.values);
                        if self.inspector.range_px(i) != Some(count) {
                            ctx.request_repaint();
                        }
                        self.inspector.range_counted(i, count);
                    }
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
        if update.errors.is_empty() {
            self.render_error = None;
        } else {
            let text = update.errors.join("; ");
            if self.render_error.as_deref() != Some(text.as_str()) {
                self.set_status(text.clone(), Level::Error);
            }
            self.render_error = Some(text);
        }
    }

    /// Whether [`Self::paint_frames`] will cover the whole viewport with an image: a view as
    /// large as the viewport (not the D-buffer's square) with a texture for every side shown.
    fn image_covers_viewport(&self) -> bool {
        let sides = if self.settings.split { 2 } else { 1 };
        self.settings.view != View::DBuffer
            && (0..sides).all(|k| self.shown_at(k).is_some() && self.viewport.textures[k].is_some())
    }

    pub(super) fn split_x(&self, rect: Rect) -> Option<f32> {
        (self.settings.split && self.shown_at(1).is_some())
            .then(|| rect.left() + rect.width() * self.settings.split_at)
    }

    fn paint_frames(&self, ui: &egui::Ui, rect: Rect) {
        let painter = ui.painter();
        let Some(main) = self.shown_at(0) else {
            return;
        };
        let split_x = self.split_x(rect);
        // Every view's display is opaque (the view pass draws "no surface"): nothing under it.
        let texture = |side: usize| self.viewport.textures[side].map(|(id, _)| id);
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
        if let (Some(x), Some(split)) = (split_x, self.shown_at(1)) {
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
        let Some(shown) = self.shown_at(usize::from(split)) else {
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

/// Show each side's display through an egui texture (registered once, again when the display
/// was made again).
fn register_textures(
    core: &ViewSession,
    textures: &mut [Option<(egui::TextureId, u64)>; 2],
    render_state: &egui_wgpu::RenderState,
) {
    for (side, texture) in textures.iter_mut().enumerate() {
        let Some(display) = core.display(side) else {
            continue;
        };
        match *texture {
            Some((_, g)) if g == display.generation => {}
            Some((id, _)) => {
                render_state
                    .renderer
                    .write()
                    .update_egui_texture_from_wgpu_texture(
                        &render_state.device,
                        display.view,
                        wgpu::FilterMode::Nearest,
                        id,
                    );
                *texture = Some((id, display.generation));
            }
            None => {
                let id = render_state.renderer.write().register_native_texture(
                    &render_state.device,
                    display.view,
                    wgpu::FilterMode::Nearest,
                );
                *texture = Some((id, display.generation));
            }
        }
    }
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
