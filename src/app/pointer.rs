//! Mouse input over the viewport: camera moves (orbit, pan, zoom), the split's divider, picking
//! the light or an object, and dragging the selection in a plane through it.

use eframe::egui::{self, Pos2, Rect};
use glam::Vec3;

use super::camera;
use super::doc::f3;
use super::viewport::Drag;
use super::{LabApp, Selection};
use crate::geometry::bvh::Bvh;
use crate::render::passes::view::View;
use crate::scene::Light;

impl LabApp {
    pub(super) fn interact(&mut self, ctx: &egui::Context, response: &egui::Response, rect: Rect) {
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
