//! Overlays over the camera views, drawn with egui's painter from the geometry stage's output and
//! the camera the frame was rendered with: caster faces by class, umbra and penumbra volume
//! wireframes, silhouette edges, the light disk, the selection; and the legends.

use crate::render::truth;
use std::collections::HashMap;

use eframe::egui::{self, Color32, Painter, Pos2, Rect, Stroke, Vec2};
use glam::Vec3;

use super::camera::Projector;
use super::viewport::HIGHLIGHT;
use super::{LabApp, Selection};
use crate::geometry::{FaceClass, VolumeMesh};
use crate::render::passes::view::View;
use crate::render::passes::view_twin::{BRANCH_COLORS, RANGE_MARK};
use crate::render::Method;
use crate::scene::Light;

/// At most this many lines per volume overlay and triangles of class faces: volumes of big
/// meshes have hundreds of thousands, which would make the window crawl. The legend says when
/// the cap cut something.
pub const MAX_LINES: usize = 12_000;
pub const MAX_FACES: usize = 40_000;

pub const CLASS_COLORS: [(FaceClass, Color32, &str); 4] = [
    (
        FaceClass::AllFront,
        Color32::from_rgba_premultiplied(110, 100, 60, 110),
        "all-front",
    ),
    (
        FaceClass::NoneFront,
        Color32::from_rgba_premultiplied(30, 35, 60, 110),
        "none-front",
    ),
    (
        FaceClass::SilhouetteA,
        Color32::from_rgba_premultiplied(110, 25, 25, 110),
        "silhouette A",
    ),
    (
        FaceClass::SilhouetteB,
        Color32::from_rgba_premultiplied(85, 35, 100, 110),
        "silhouette B",
    ),
];

pub const UMBRA_COLOR: Color32 = Color32::from_rgb(90, 150, 255);
pub const PENUMBRA_COLOR: Color32 = Color32::from_rgb(255, 150, 40);
pub const UMBRA_SILHOUETTE: Color32 = Color32::from_rgb(0, 235, 235);
pub const PENUMBRA_SILHOUETTE: Color32 = Color32::from_rgb(255, 80, 200);
pub const LIGHT_COLOR: Color32 = Color32::from_rgb(255, 250, 200);

fn class_color(c: FaceClass) -> Color32 {
    CLASS_COLORS
        .iter()
        .find(|(k, _, _)| *k == c)
        .map_or(Color32::GRAY, |(_, col, _)| *col)
}

/// The outline edges of a volume mesh: triangle edges used once by their polygon (the quads'
/// diagonals share both vertex indices and are left out), umbra or penumbra kinds only.
fn volume_edges(v: &VolumeMesh, umbra: bool, out: &mut Vec<[Vec3; 2]>, cap: usize) -> usize {
    let mut count: HashMap<(u32, u32), u32> = HashMap::new();
    for t in v.indices.chunks_exact(3) {
        let kind = v.vertices[t[0] as usize].kind;
        if kind.is_umbra() != umbra {
            continue;
        }
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    // In index order, so the lines are drawn (and blended) the same way every run.
    let mut once: Vec<(u32, u32)> = count
        .into_iter()
        .filter(|&(_, n)| n == 1)
        .map(|(e, _)| e)
        .collect();
    once.sort_unstable();
    let mut total = 0;
    for (a, b) in once {
        {
            total += 1;
            if out.len() < cap {
                out.push([
                    v.vertices[a as usize].position,
                    v.vertices[b as usize].position,
                ]);
            }
        }
    }
    total
}

impl LabApp {
    pub(super) fn draw_overlays(&mut self, painter: &Painter, rect: Rect) {
        let Some(core) = self.core.as_ref() else {
            return;
        };
        let painter = painter.with_clip_rect(rect);
        let projector = Projector::new(&self.camera, rect);
        let scene = core.scene();
        let overlays = self.settings.overlays;
        self.overlay_notes.clear();
        // The shown method's geometry stage, or the paper's if it builds none.
        let shown = self.settings.method();
        let geometry = core
            .session
            .geometry(shown)
            .or_else(|| core.session.geometry(Method::DBUFFER));
        let wants_geometry = overlays.classes
            || overlays.umbra_volume
            || overlays.penumbra_volume
            || overlays.silhouettes;
        if wants_geometry {
            if let Some(note) = shown.spec().overlay_note {
                self.overlay_notes.push(note.to_string());
            }
        }
        let empty = crate::geometry::SceneGeometry::default();
        let geometry = match geometry {
            Some(g) => g,
            None => {
                if wants_geometry {
                    self.overlay_notes.push(format!(
                        "{shown} builds no volumes: switch to a D-buffer method"
                    ));
                }
                &empty
            }
        };

        if overlays.classes {
            // The casters as the session welded them for the geometry stage.
            let casters = &core.session.prepared().meshes;
            let mut mesh = egui::Mesh::default();
            let mut drawn = 0;
            let total: usize = geometry.casters.iter().map(|c| c.classes.len()).sum();
            'casters: for (caster, prepared) in geometry.casters.iter().zip(casters) {
                for (face, class) in prepared.faces.iter().zip(&caster.classes) {
                    if drawn >= MAX_FACES {
                        break 'casters;
                    }
                    let corners = face.v.map(|i| prepared.positions[i as usize]);
                    let Some(p) = corners
                        .iter()
                        .map(|&c| projector.point(c))
                        .collect::<Option<Vec<Pos2>>>()
                    else {
                        continue;
                    };
                    // Faces turned away from the camera are hidden behind the front ones.
                    let area =
                        (p[1] - p[0]).x * (p[2] - p[0]).y - (p[1] - p[0]).y * (p[2] - p[0]).x;
                    if area >= 0.0 {
                        continue;
                    }
                    let base = mesh.vertices.len() as u32;
                    let color = class_color(*class);
                    for q in p {
                        mesh.colored_vertex(q, color);
                    }
                    mesh.add_triangle(base, base + 1, base + 2);
                    drawn += 1;
                }
            }
            painter.add(egui::Shape::mesh(mesh));
            if drawn >= MAX_FACES && total > MAX_FACES {
                self.overlay_notes
                    .push(format!("classes: first {MAX_FACES} of {total} faces drawn"));
            }
        }

        for (on, umbra, color, name) in [
            (overlays.umbra_volume, true, UMBRA_COLOR, "umbra volume"),
            (
                overlays.penumbra_volume,
                false,
                PENUMBRA_COLOR,
                "penumbra volume",
            ),
        ] {
            if !on {
                continue;
            }
            let mut lines = Vec::new();
            let mut total = 0;
            for c in &geometry.casters {
                total += volume_edges(&c.volumes, umbra, &mut lines, MAX_LINES);
            }
            let stroke = Stroke::new(1.0, color.gamma_multiply(0.8));
            for [a, b] in &lines {
                if let Some(s) = projector.segment(*a, *b) {
                    painter.line_segment(s, stroke);
                }
            }
            if total > lines.len() {
                self.overlay_notes
                    .push(format!("{name}: {} of {total} edges drawn", lines.len()));
            }
        }

        if overlays.silhouettes {
            for c in &geometry.casters {
                for e in &c.silhouettes {
                    let color = if e.umbra {
                        UMBRA_SILHOUETTE
                    } else {
                        PENUMBRA_SILHOUETTE
                    };
                    if let Some(s) = projector.segment(e.v[0], e.v[1]) {
                        painter.line_segment(s, Stroke::new(2.0, color));
                    }
                }
            }
        }

        let selected_light = self.selection.is_light();
        if let (Light::Line(line), true) = (scene.light, overlays.light_outline || selected_light) {
            let color = if selected_light {
                HIGHLIGHT
            } else {
                LIGHT_COLOR
            };
            if let Some(s) = projector.segment(line.a, line.b) {
                painter.line_segment(
                    s,
                    Stroke::new(if selected_light { 3.0 } else { 2.0 }, color),
                );
            }
            // Both ends as handles (the selected one filled), and the method's sample points.
            for (k, end) in [line.a, line.b].into_iter().enumerate() {
                if let Some(p) = projector.point(end) {
                    let filled = self.selection == Selection::LightEnd(k);
                    painter.circle(
                        p,
                        5.0,
                        if filled {
                            HIGHLIGHT
                        } else {
                            Color32::TRANSPARENT
                        },
                        Stroke::new(1.5, color),
                    );
                    painter.text(
                        p + egui::vec2(7.0, -7.0),
                        egui::Align2::LEFT_BOTTOM,
                        if k == 0 { "a" } else { "b" },
                        egui::FontId::proportional(12.0),
                        color,
                    );
                }
            }
            // The points on the segment the shown method samples (its shadow maps' origins).
            let samples = self.settings.method().spec().line_samples;
            let knobs = self.base_request(1, 1).knobs;
            for q in samples.map_or_else(Vec::new, |points| points(&line, &knobs)) {
                if let Some(p) = projector.point(q) {
                    painter.circle_filled(p, 2.5, color);
                }
            }
        }
        if let (Light::Area(light), true) = (scene.light, overlays.light_outline || selected_light)
        {
            // The light's own shape: the disk's rim, the rectangle's or polygon's corners.
            let mut outline = crate::geometry::outline::boundary(&light, 64);
            outline.extend(outline.first().copied());
            let rim: Vec<Pos2> = outline.iter().filter_map(|&q| projector.point(q)).collect();
            let color = if selected_light {
                HIGHLIGHT
            } else {
                LIGHT_COLOR
            };
            if selected_light && rim.len() > 2 {
                painter.add(egui::Shape::convex_polygon(
                    rim.clone(),
                    HIGHLIGHT.gamma_multiply(0.25),
                    Stroke::NONE,
                ));
            }
            painter.add(egui::Shape::line(
                rim,
                Stroke::new(if selected_light { 2.5 } else { 1.5 }, color),
            ));
            if let Some(s) =
                projector.segment(light.center, light.center + light.normal * light.radius)
            {
                painter.arrow(s[0], s[1] - s[0], Stroke::new(1.5, color));
            }
            // A selected rectangle's or polygon's corners are handles (the one dragged filled):
            // a rectangle's resize it about its centre, a polygon's move that vertex.
            if let (Some(corners), true) = (light.corners(), selected_light) {
                for (k, &q) in corners.vertices().iter().enumerate() {
                    if let Some(p) = projector.point(q) {
                        let filled = self.selection == Selection::LightEnd(k);
                        painter.circle(
                            p,
                            4.5,
                            if filled {
                                HIGHLIGHT
                            } else {
                                Color32::TRANSPARENT
                            },
                            Stroke::new(1.5, color),
                        );
                    }
                }
            }
        }

        if let Selection::Object(i) = self.selection {
            if let Some(object) = scene.objects.get(i) {
                let stroke = Stroke::new(1.0, HIGHLIGHT.gamma_multiply(0.7));
                if object.mesh.triangles.len() <= 4000 {
                    for t in object.mesh.triangle_corners() {
                        for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                            if let Some(s) = projector.segment(t[a], t[b]) {
                                painter.line_segment(s, stroke);
                            }
                        }
                    }
                } else if let Some((lo, hi)) = object.mesh.bounds() {
                    for (a, b) in box_edges(lo, hi) {
                        if let Some(s) = projector.segment(a, b) {
                            painter.line_segment(s, Stroke::new(2.0, HIGHLIGHT));
                        }
                    }
                }
            }
        }
    }

    /// Legends of the view and the overlays, bottom left of the viewport.
    pub(super) fn draw_legends(&self, ui: &egui::Ui, rect: Rect) {
        let mut rows: Vec<(Option<Color32>, String)> = Vec::new();
        let view = self.settings.view;
        let mut bar = None;
        match view {
            View::Classes => {
                for ([r, g, b, _], name) in BRANCH_COLORS {
                    rows.push((Some(Color32::from_rgb(r, g, b)), name.to_string()));
                }
            }
            View::Range => {
                let [r, g, b, _] = RANGE_MARK;
                let count = self
                    .inspector
                    .range_px(0)
                    .map_or_else(String::new, |n| format!(": {n} px"));
                rows.push((
                    Some(Color32::from_rgb(r, g, b)),
                    format!("V or t NaN, infinite or outside [0, 1]{count}"),
                ));
            }
            View::Visibility | View::T | View::Error | View::Flip | View::DBuffer | View::Cost => {
                if let Some(m) = self.settings.mapping(view) {
                    bar = Some(*m);
                }
                let what = match view {
                    View::Visibility => "V".to_string(),
                    View::T => "t".to_string(),
                    View::Flip => {
                        "FLIP of the image against the reference's (0 … 1, 67 px a degree)"
                            .to_string()
                    }
                    View::Cost => {
                        let m = self.settings.method();
                        let c = m.spec().cost;
                        match c.constant {
                            Some(why) => format!("{m}: {} per pixel, constant ({why})", c.unit),
                            None => format!("{m}: {} per pixel", c.unit),
                        }
                    }
                    View::Error => {
                        let reference = self.shown_at(0).and_then(|s| {
                            if truth::is_soft(s.method) {
                                Some(format!(
                                    "K = {} (the shown reference)",
                                    self.settings.reference_samples
                                ))
                            } else {
                                s.reference
                                    .map(|(done, total)| format!("K = {done} of {total} samples"))
                            }
                        });
                        format!(
                            "|V − V_ref|, reference {}",
                            reference.unwrap_or_else(|| "not available".into())
                        )
                    }
                    _ => {
                        let channels = self
                            .core
                            .as_ref()
                            .and_then(|c| c.session.light_maps(self.settings.method()))
                            .map(|m| m.channels)
                            .unwrap_or_default();
                        let names: Vec<&str> = channels
                            .iter()
                            .enumerate()
                            .filter(|(c, _)| self.settings.channels.get(*c) == Some(&true))
                            .map(|(_, ch)| ch.name)
                            .collect();
                        format!("light maps {} (m from the light centre)", names.join(" "))
                    }
                };
                rows.push((None, what));
            }
            View::Final => {}
        }
        let mut o = self.settings.overlays;
        if view == View::DBuffer {
            // Overlays are drawn over the camera views only.
            o = super::Overlays {
                classes: false,
                umbra_volume: false,
                penumbra_volume: false,
                silhouettes: false,
                light_outline: false,
            };
        }
        if o.classes {
            for (_, c, name) in CLASS_COLORS {
                rows.push((Some(c.to_opaque()), format!("face: {name}")));
            }
        }
        if o.umbra_volume {
            rows.push((Some(UMBRA_COLOR), "umbra volume".into()));
        }
        if o.penumbra_volume {
            rows.push((Some(PENUMBRA_COLOR), "penumbra volume".into()));
        }
        if o.silhouettes {
            rows.push((Some(UMBRA_SILHOUETTE), "umbra silhouette".into()));
            rows.push((Some(PENUMBRA_SILHOUETTE), "penumbra silhouette".into()));
        }
        for note in &self.overlay_notes {
            rows.push((None, note.clone()));
        }
        if rows.is_empty() && bar.is_none() {
            return;
        }
        let painter = ui.painter().with_clip_rect(rect);
        let row_h = 16.0;
        let bar_h = if bar.is_some() { 22.0 } else { 0.0 };
        let height = rows.len() as f32 * row_h + bar_h + 8.0;
        let width = 250.0f32.min(rect.width());
        let frame = Rect::from_min_size(
            Pos2::new(rect.left() + 6.0, rect.bottom() - height - 6.0),
            Vec2::new(width, height),
        );
        painter.rect_filled(frame, 4.0, Color32::from_black_alpha(170));
        let mut y = frame.top() + 4.0;
        let font = egui::FontId::proportional(12.0);
        if let Some(m) = bar {
            let bar_rect = Rect::from_min_size(
                Pos2::new(frame.left() + 6.0, y),
                Vec2::new(width - 12.0, 8.0),
            );
            let steps = 48;
            for k in 0..steps {
                let x0 = bar_rect.left() + bar_rect.width() * k as f32 / steps as f32;
                let x1 = bar_rect.left() + bar_rect.width() * (k + 1) as f32 / steps as f32;
                painter.rect_filled(
                    Rect::from_min_max(
                        Pos2::new(x0, bar_rect.top()),
                        Pos2::new(x1, bar_rect.bottom()),
                    ),
                    0.0,
                    {
                        let [r, g, b, _] = m.map.color((k as f32 + 0.5) / steps as f32);
                        Color32::from_rgb(r, g, b)
                    },
                );
            }
            painter.text(
                Pos2::new(bar_rect.left(), bar_rect.bottom() + 1.0),
                egui::Align2::LEFT_TOP,
                format!("{:.4}", m.black),
                font.clone(),
                Color32::WHITE,
            );
            painter.text(
                Pos2::new(bar_rect.right(), bar_rect.bottom() + 1.0),
                egui::Align2::RIGHT_TOP,
                format!("{:.4}", m.white),
                font.clone(),
                Color32::WHITE,
            );
            y += bar_h;
        }
        for (color, text) in rows {
            let mut x = frame.left() + 6.0;
            if let Some(c) = color {
                painter.rect_filled(
                    Rect::from_min_size(Pos2::new(x, y + 3.0), Vec2::splat(10.0)),
                    2.0,
                    c,
                );
                x += 16.0;
            }
            painter.text(
                Pos2::new(x, y),
                egui::Align2::LEFT_TOP,
                text,
                font.clone(),
                Color32::WHITE,
            );
            y += row_h;
        }
    }
}

fn box_edges(lo: Vec3, hi: Vec3) -> Vec<(Vec3, Vec3)> {
    let corner = |i: u32| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let mut edges = Vec::new();
    for i in 0..8u32 {
        for bit in [1, 2, 4] {
            if i & bit == 0 {
                edges.push((corner(i), corner(i | bit)));
            }
        }
    }
    edges
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{PreparedCasters, VolumeParams};

    #[test]
    fn volume_outlines_leave_out_quad_diagonals() {
        let scene = crate::scene::load("table1-224").unwrap();
        let geometry = PreparedCasters::new(&scene).build(
            scene.light.as_area().expect("a disk light"),
            &VolumeParams::for_scene(&scene),
        );
        let c = &geometry.casters[0];
        let mut umbra = Vec::new();
        let n = volume_edges(&c.volumes, true, &mut umbra, usize::MAX);
        let mut penumbra = Vec::new();
        let m = volume_edges(&c.volumes, false, &mut penumbra, usize::MAX);
        assert_eq!(n, umbra.len());
        assert!(n > 0 && m > 0);
        // Fewer outline edges than triangle edges: the diagonals (and shared fan edges) are gone.
        let tris = c.volumes.count(|k| !k.is_umbra());
        assert!(m < 3 * tris, "{m} edges for {tris} penumbra triangles");
        let mut capped = Vec::new();
        assert_eq!(volume_edges(&c.volumes, false, &mut capped, 10), m);
        assert_eq!(capped.len(), 10);
    }

    #[test]
    fn a_box_has_twelve_edges() {
        assert_eq!(box_edges(Vec3::ZERO, Vec3::ONE).len(), 12);
    }
}
