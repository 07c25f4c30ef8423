//! The central panel: asks the render core for a frame when something changed (camera, light,
//! an object, method, V(t), size) or while the reference converges, turns it into the chosen
//! view, shows it (two methods split by a draggable divider if asked), and turns mouse input into
//! camera moves, selection and scene edits.

use std::time::Instant;

use eframe::egui::{
    self, Color32, ColorImage, Pos2, Rect, Sense, TextureHandle, TextureOptions, Vec2,
};
use glam::Vec3;

use super::camera::{self, Projector};
use super::doc::f3;
use super::views::{self, Mapping, View};
use super::{LabApp, Level, Selection};
use crate::geometry::bvh::Bvh;
use crate::geometry::light_view::LightView;
use crate::render::{Frame, FrameRequest, Method, MethodParams};
use crate::scene::Camera;

/// Everything that decides a frame's pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RenderKey {
    request: FrameRequest,
    camera: Camera,
    revision: u64,
}

/// Everything that decides how a frame is shown.
#[derive(Clone, Copy, Debug, PartialEq)]
struct DisplayKey {
    serial: u64,
    view: View,
    channels: [bool; 4],
    mapping: Option<Mapping>,
    reference: Option<(u32, u32)>,
}

/// A frame from the render core and the texture that shows it.
pub struct Shown {
    pub frame: Frame,
    pub method: Method,
    /// The D-buffer's light view for this frame (maps world points to texels).
    pub light_view: LightView,
    /// The light the frame was rendered with.
    pub light: crate::scene::DiskLight,
    /// Reference samples (done, total) when the frame was rendered, if a reference was running.
    pub reference: Option<(u32, u32)>,
    serial: u64,
    texture: Option<TextureHandle>,
    display: Option<DisplayKey>,
    /// Why the current view cannot be drawn from this frame (e.g. no reference yet).
    pub view_note: Option<String>,
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
    pub main: Option<Shown>,
    pub split: Option<Shown>,
    pub rect: Option<Rect>,
    pub drag: Option<Drag>,
    pub hover: Option<Hover>,
    keys: [Option<RenderKey>; 2],
    reference_key: Option<RenderKey>,
    serial: u64,
}

/// Colour of the divider and of selections.
pub const HIGHLIGHT: Color32 = Color32::from_rgb(255, 220, 60);

impl LabApp {
    pub(super) fn viewport_ui(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "viewport"));
        self.viewport.rect = Some(rect);
        ui.painter().rect_filled(rect, 0.0, views::NO_DATA);
        let ppp = ctx.pixels_per_point();
        let scale = self.settings.render_scale;
        let w = (rect.width() * ppp * scale).round().max(0.0) as u32;
        let h = (rect.height() * ppp * scale).round().max(0.0) as u32;
        if w == 0 || h == 0 || rect.width() < 1.0 || rect.height() < 1.0 {
            // Collapsed or minimised: nothing to render (the render core refuses size 0).
            return;
        }
        self.interact(&ctx, &response, rect);
        self.render_if_needed(&ctx, w, h);
        self.update_textures(&ctx);
        let image_rect = self.image_rect(rect);
        self.paint_frames(ui, image_rect);
        self.hover(&response, image_rect);
        if self.settings.view != View::DBuffer {
            self.draw_overlays(ui.painter(), image_rect);
        }
        self.draw_legends(ui, rect);
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
    /// D-buffer (which is square).
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
        self.viewport
            .main
            .as_ref()
            .and_then(|s| s.view_note.clone())
    }

    fn base_request(&self, width: u32, height: u32) -> FrameRequest {
        FrameRequest {
            width,
            height,
            dbuffer_size: self.settings.dbuffer_size,
            method: self.settings.method(),
            vt: self.settings.vt(),
            params: MethodParams {
                reference_samples: self.settings.reference_samples,
                reference_step: self
                    .settings
                    .reference_step
                    .min(self.settings.reference_samples),
                ..MethodParams::default()
            },
            read_dbuffer: true,
        }
    }

    fn render_if_needed(&mut self, ctx: &egui::Context, width: u32, height: u32) {
        let base = self.base_request(width, height);
        let Some(core) = self.core.as_mut() else {
            return;
        };
        core.set_camera(self.camera);
        let methods = [
            Some(self.settings.method()),
            self.settings.split.then(|| self.settings.split_method()),
        ];
        if !self.settings.split {
            self.viewport.split = None;
            self.viewport.keys[1] = None;
        }
        let mut errors = Vec::new();
        for (slot, method) in methods.into_iter().enumerate() {
            let Some(method) = method else { continue };
            let request = FrameRequest { method, ..base };
            let key = RenderKey {
                request,
                camera: self.camera,
                revision: self.revision,
            };
            let converging = method == Method::Reference && core.converging();
            if self.viewport.keys[slot] == Some(key) && !converging {
                continue;
            }
            self.viewport.keys[slot] = Some(key);
            let builds = core.geometry_builds();
            let t0 = Instant::now();
            match core.frame(&request) {
                Ok(frame) => {
                    let wall_ms = t0.elapsed().as_secs_f64() * 1e3;
                    let rebuilt = core.geometry_builds() != builds;
                    let geometry_ms = rebuilt.then(|| core.geometry_ms());
                    self.stats.render(wall_ms, geometry_ms, &frame.gpu_ms);
                    self.viewport.serial += 1;
                    let shown = Shown {
                        light_view: *core.light_view(),
                        light: core.scene().light,
                        reference: core.reference_progress(),
                        frame,
                        method,
                        serial: self.viewport.serial,
                        texture: None,
                        display: None,
                        view_note: None,
                    };
                    let place = if slot == 0 {
                        &mut self.viewport.main
                    } else {
                        &mut self.viewport.split
                    };
                    // Keep the texture: `set` on it is cheaper than a new one.
                    let texture = place.take().and_then(|s| s.texture);
                    *place = Some(Shown { texture, ..shown });
                }
                Err(e) => errors.push(format!("{method}: {e}")),
            }
        }
        // The error view needs the reference even when neither side shows it.
        if self.settings.view == View::Error && !self.settings.shows_reference() {
            let request = FrameRequest {
                method: Method::Reference,
                ..base
            };
            let key = RenderKey {
                request,
                camera: self.camera,
                revision: self.revision,
            };
            if self.viewport.reference_key != Some(key) || core.converging() {
                self.viewport.reference_key = Some(key);
                if let Err(e) = core.advance_reference(&request) {
                    errors.push(format!("reference: {e}"));
                }
            }
        }
        // Every shown frame reports the reference as it stands now (legend, inspector, and the
        // error view redraws as it converges).
        let progress = core.reference_progress();
        for shown in [self.viewport.main.as_mut(), self.viewport.split.as_mut()]
            .into_iter()
            .flatten()
        {
            shown.reference = progress;
        }
        if core.converging() && self.settings.needs_reference() {
            ctx.request_repaint();
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

    fn update_textures(&mut self, ctx: &egui::Context) {
        let view = self.settings.view;
        let channels = self.settings.channels;
        let reference: Option<Vec<f32>> = if view == View::Error {
            self.core
                .as_ref()
                .and_then(|c| c.reference_visibility().map(<[f32]>::to_vec))
        } else {
            None
        };
        for slot in 0..2 {
            let mapping = self.settings.mapping(view).copied();
            let shown = if slot == 0 {
                self.viewport.main.as_mut()
            } else {
                self.viewport.split.as_mut()
            };
            let Some(shown) = shown else { continue };
            let key = DisplayKey {
                serial: shown.serial,
                view,
                channels,
                mapping,
                reference: shown.reference,
            };
            if shown.display == Some(key) && shown.texture.is_some() {
                continue;
            }
            let mut mapping = mapping.unwrap_or_else(Mapping::unit);
            let (image, note) =
                view_image(shown, view, channels, &mut mapping, reference.as_deref());
            if let Some(m) = self.settings.mapping_mut(view) {
                *m = mapping;
            }
            shown.view_note = note;
            shown.display = Some(DisplayKey {
                mapping: self.settings.mapping(view).copied(),
                ..key
            });
            match shown.texture.as_mut() {
                Some(t) => t.set(image, TextureOptions::NEAREST),
                None => {
                    shown.texture = Some(ctx.load_texture(
                        if slot == 0 { "lab-main" } else { "lab-split" },
                        image,
                        TextureOptions::NEAREST,
                    ))
                }
            }
        }
    }

    fn split_x(&self, rect: Rect) -> Option<f32> {
        (self.settings.split && self.viewport.split.is_some())
            .then(|| rect.left() + rect.width() * self.settings.split_at)
    }

    fn paint_frames(&self, ui: &egui::Ui, rect: Rect) {
        let painter = ui.painter();
        let full = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        let Some(main) = self.viewport.main.as_ref() else {
            return;
        };
        let split_x = self.split_x(rect);
        if let Some(t) = &main.texture {
            match split_x {
                None => {
                    painter.image(t.id(), rect, full, Color32::WHITE);
                }
                Some(x) => {
                    let s = self.settings.split_at;
                    let left = Rect::from_min_max(rect.min, Pos2::new(x, rect.bottom()));
                    let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(s, 1.0));
                    painter.image(t.id(), left, uv, Color32::WHITE);
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
        if let (Some(x), Some(split)) = (split_x, self.viewport.split.as_ref()) {
            if let Some(t) = &split.texture {
                let s = self.settings.split_at;
                let right = Rect::from_min_max(Pos2::new(x, rect.top()), rect.max);
                let uv = Rect::from_min_max(Pos2::new(s, 0.0), Pos2::new(1.0, 1.0));
                painter.image(t.id(), right, uv, Color32::WHITE);
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
        let shown = if split {
            self.viewport.split.as_ref()
        } else {
            self.viewport.main.as_ref()
        };
        let Some(shown) = shown else { return };
        let (w, h) = if self.settings.view == View::DBuffer {
            (shown.frame.dbuffer_size, shown.frame.dbuffer_size)
        } else {
            (shown.frame.width, shown.frame.height)
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
                            Selection::Light => e.light.center = to,
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
        if self.pick(origin, dir) != self.selection {
            return None;
        }
        let anchor = match self.selection {
            Selection::Light => self.doc.light().center,
            Selection::Object(i) => {
                let t = self.doc.file.objects.get(i)?.translate;
                Vec3::new(t[0] as f32, t[1] as f32, t[2] as f32)
            }
            Selection::None => return None,
        };
        let normal = if shift {
            Vec3::Y
        } else {
            camera::basis(&self.camera).2
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
        let light = core.scene().light;
        if let Some(p) = camera::ray_plane(origin, dir, light.center, light.normal) {
            if (p - light.center).length() <= light.radius * 1.15 {
                best = ((p - origin).length(), Selection::Light);
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
        Projector::new(&self.camera, rect).point(self.doc.light().center)
    }

    /// Where world point `p` is drawn in the viewport.
    pub fn screen_pos(&self, p: Vec3) -> Option<Pos2> {
        let rect = self.viewport.rect?;
        Projector::new(&self.camera, rect).point(p)
    }
}

/// The image of `view` for one shown frame, and a note when the view cannot be drawn.
fn view_image(
    shown: &Shown,
    view: View,
    channels: [bool; 4],
    mapping: &mut Mapping,
    reference: Option<&[f32]>,
) -> (ColorImage, Option<String>) {
    let f = &shown.frame;
    let fallback = || views::final_image(f);
    match view {
        View::Final => (views::final_image(f), None),
        View::Visibility => (views::scalar_image(f, &f.visibility, mapping), None),
        View::T => (views::scalar_image(f, &f.t, mapping), None),
        View::Classes => (views::classes_image(f), None),
        View::Error => {
            let reference = if shown.method == Method::Reference {
                Some(f.visibility.as_slice())
            } else {
                reference
            };
            match reference.and_then(|r| views::error_image(f, r, mapping)) {
                Some(img) => (img, None),
                None => (
                    fallback(),
                    Some("no reference of this size yet: the error view waits for it".into()),
                ),
            }
        }
        View::DBuffer => match views::dbuffer_image(f, channels, mapping) {
            Some(img) => (img, None),
            None => (fallback(), Some("this frame carries no D-buffer".into())),
        },
    }
}
