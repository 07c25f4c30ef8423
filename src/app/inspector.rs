//! The right panel: the pixel inspector (the exact values under the cursor, read back from the
//! GPU by the probe — a hundred bytes, a frame later — whatever the display mapping) and the
//! stats (timings, frame rate, bytes read back, counts).

use crate::render::truth;
use eframe::egui::{self, Color32, Pos2, Rect, RichText, Sense, Stroke, Vec2};

use super::{light_panel, LabApp};
use crate::geometry::GeometryStats;
use crate::render::passes::probe::PixelValues;
use crate::render::passes::view::View;
use crate::render::passes::view_twin::branch_name;

/// The values under the cursor, as the probe brought them back, per slot.
#[derive(Default)]
pub struct Inspector {
    values: [Option<Probed>; 2],
    /// Per slot, the pixels the range view marks (V or t out of range), as the probe counted
    /// them on the GPU.
    range_px: [Option<u64>; 2],
}

struct Probed {
    x: u32,
    y: u32,
    view: View,
    values: Vec<f32>,
}

impl Inspector {
    /// A probe answer for `slot` at (`x`, `y`) of `view` arrived.
    pub fn arrived(&mut self, slot: usize, x: u32, y: u32, view: View, values: Vec<f32>) {
        if let Some(v) = self.values.get_mut(slot) {
            *v = Some(Probed { x, y, view, values });
        }
    }

    /// A range count for `slot` arrived.
    pub fn range_counted(&mut self, slot: usize, count: u64) {
        if let Some(c) = self.range_px.get_mut(slot) {
            *c = Some(count);
        }
    }

    /// The last range count of `slot`.
    pub fn range_px(&self, slot: usize) -> Option<u64> {
        self.range_px.get(slot).copied().flatten()
    }

    /// The decoded values at (`x`, `y`) of `slot` in `view`, if they have arrived.
    pub fn at(&self, slot: usize, x: u32, y: u32, view: View) -> Option<PixelValues> {
        let p = self.values.get(slot)?.as_ref()?;
        (p.x == x && p.y == y && p.view == view)
            .then(|| PixelValues::decode(&p.values))
            .flatten()
    }
}

/// The inspector's width in points, margins included.
pub(super) const INSPECTOR_WIDTH: f32 = 290.0;

fn value(v: Option<f32>) -> String {
    v.map_or_else(|| "—".into(), |v| format!("{v:.5}"))
}

impl LabApp {
    pub(super) fn inspector_panel(&mut self, ui: &mut egui::Ui) {
        // A fixed width: a panel that grew with its text (the light panel's heading appears on
        // hover) would resize the viewport, and every resize starts the reference over.
        egui::Panel::right("inspector")
            .exact_size(INSPECTOR_WIDTH)
            .resizable(false)
            .show(ui, |ui| {
                // The scroll bar always shown: one that appeared only when the rows grew (a
                // branch name wrapping) widened the panel by its width for that frame.
                egui::ScrollArea::vertical()
                    .auto_shrink([false, false])
                    .scroll_bar_visibility(egui::scroll_area::ScrollBarVisibility::AlwaysVisible)
                    .show(ui, |ui| {
                        ui.heading("Pixel");
                        self.pixel_section(ui);
                        // Both fold away (the light panel is tall: folded, the stats are in view).
                        if self.viewport.hover.is_some() {
                            ui.separator();
                            egui::CollapsingHeader::new(
                                egui::RichText::new("Light as seen from this pixel").heading(),
                            )
                            .id_salt("light-from-pixel")
                            .default_open(true)
                            .show(ui, |ui| self.light_section(ui));
                        }
                        ui.separator();
                        egui::CollapsingHeader::new(egui::RichText::new("Stats").heading())
                            .id_salt("stats")
                            .default_open(true)
                            .show(ui, |ui| self.stats_section(ui));
                    });
            });
    }

    /// The inspector's rows for the pixel under the cursor, once the probe brought them.
    pub fn pixel_rows(&self) -> Vec<(String, String)> {
        let Some(hover) = self.viewport.hover else {
            return Vec::new();
        };
        let slot = usize::from(hover.split);
        let Some(shown) = self.shown_at(slot) else {
            return Vec::new();
        };
        let view = self.settings.view;
        let mut rows: Vec<(String, String)> = vec![("method".into(), shown.method.name().into())];
        let what = if view == View::DBuffer {
            "texel"
        } else {
            "pixel"
        };
        rows.push((what.into(), format!("{}, {}", hover.x, hover.y)));
        let Some(p) = self.inspector.at(slot, hover.x, hover.y, view) else {
            rows.push(("values".into(), "reading…".into()));
            return rows;
        };
        let channels = self
            .core
            .as_ref()
            .and_then(|c| c.session.light_maps(shown.method))
            .map(|m| m.channels)
            .unwrap_or_default();
        let map_rows = |rows: &mut Vec<(String, String)>| {
            if let Some(((tx, ty), texel)) = p.texel {
                if view != View::DBuffer {
                    rows.push(("light-map texel".into(), format!("{tx}, {ty}")));
                }
                for c in channels {
                    rows.push((c.name.into(), value(c.value(&texel))));
                }
            }
        };
        if view == View::DBuffer {
            map_rows(&mut rows);
            return rows;
        }
        let Some(x) = p.position else {
            rows.push(("surface".into(), "none".into()));
            return rows;
        };
        rows.push((
            "position".into(),
            format!("{:.3}, {:.3}, {:.3}", x.x, x.y, x.z),
        ));
        rows.push((
            "|cx|".into(),
            format!("{:.5}", (x - shown.light.center()).length()),
        ));
        map_rows(&mut rows);
        rows.push(("branch".into(), branch_name(p.branch).into()));
        rows.push(("t".into(), value(Some(p.t))));
        rows.push(("V".into(), value(Some(p.visibility))));
        if !truth::is_soft(shown.method) {
            let samples = shown
                .reference
                .map(|(done, total)| format!(" (K {done}/{total})"))
                .unwrap_or_default();
            rows.push((format!("reference V{samples}"), value(p.reference)));
        }
        // The method's work here (its cost view), in the unit its registry entry names.
        let cost = shown.method.spec().cost;
        let [work, path] = p.cost;
        if work.is_finite() {
            rows.push((cost.unit.into(), format!("{work}")));
        }
        if !cost.paths.is_empty() && path.is_finite() {
            rows.push(("path".into(), cost.path_name(path)));
        }
        rows
    }

    fn pixel_section(&self, ui: &mut egui::Ui) {
        if self.viewport.hover.is_none() {
            ui.label(RichText::new("hover the viewport").small());
            return;
        }
        rows_grid(ui, "pixel-grid", self.pixel_rows());
    }

    /// The light as seen from the pixel under the cursor (`light_panel`): its rays cast on this
    /// thread for that one pixel when the cursor reaches another surface point, not while a
    /// mouse button is down (a drag edits the scene every frame); what they are cast against is
    /// made on a worker thread after each edit.
    fn light_section(&mut self, ui: &mut egui::Ui) {
        let Some(hover) = self.viewport.hover else {
            return;
        };
        let slot = usize::from(hover.split);
        let found = self.shown_at(slot).and_then(|shown| {
            let p = self
                .inspector
                .at(slot, hover.x, hover.y, self.settings.view)?;
            Some((
                shown.method,
                light_panel::fused_params(&shown.request),
                p.position,
            ))
        });
        let Some((method, params, position)) = found else {
            ui.label(RichText::new("reading…").small());
            return;
        };
        let Some(x) = position else {
            self.light_panel.clear();
            ui.label(RichText::new("no surface here").small());
            return;
        };
        let busy = ui.input(|i| i.pointer.any_down());
        if let (Some(core), false) = (self.core.as_ref(), busy) {
            let revisions = light_panel::Revisions {
                scene: self.revision,
                geometry: self.geometry_revision,
            };
            let ctx = ui.ctx().clone();
            self.light_panel
                .update(core.scene(), revisions, method, x, params, move || {
                    ctx.request_repaint()
                });
        }
        if let Some(e) = &self.light_panel.error {
            ui.label(RichText::new(e).small());
        }
        let Some(light) = self.light_panel.shown.as_ref() else {
            if self.light_panel.preparing() {
                ui.label(RichText::new("casting the reference's rays…").small());
            }
            return;
        };
        light_panel::draw(ui, light);
        rows_grid(ui, "light-grid", light.rows());
    }

    fn stats_section(&self, ui: &mut egui::Ui) {
        let s = &self.stats;
        let mut rows: Vec<(String, String)> = Vec::new();
        if let Some(core) = self.core.as_ref() {
            let mut name = core.ctx.adapter.name.clone();
            if name.chars().count() > 18 {
                name = name.chars().take(17).collect::<String>() + "…";
            }
            rows.push(("adapter".into(), name));
        }
        if let Some(main) = self.shown_at(0) {
            let r = &main.request;
            rows.push((
                "frame".into(),
                format!("{}×{}, D-buffer {}²", r.width, r.height, r.dbuffer_size),
            ));
        }
        let hide = self.deterministic;
        let ms = |v: Option<f64>| match v {
            Some(_) if hide => "(hidden)".to_string(),
            Some(v) => format!("{v:.1} ms"),
            None => "—".into(),
        };
        // Median CPU time to record and submit a render, apart for renders that rebuilt the
        // geometry.
        rows.push(("render (CPU)".into(), ms(s.median_wall_ms(false))));
        rows.push(("  + new geometry".into(), ms(s.median_wall_ms(true))));
        rows.push(("CPU geometry".into(), ms(s.median_geometry_ms())));
        let gpu = s.median_gpu_ms();
        if gpu.is_empty() {
            rows.push(("GPU passes".into(), "no timestamp queries".into()));
        }
        for (pass, v) in gpu {
            let v = if hide {
                "(hidden)".into()
            } else {
                format!("{v:.2} ms")
            };
            rows.push((format!("GPU {pass}"), v));
        }
        rows.push((
            "window".into(),
            match s.fps() {
                Some(_) if hide => "(hidden)".into(),
                Some(f) => format!("{f:.0} fps"),
                None => "—".into(),
            },
        ));
        rows.push((
            "read back".into(),
            match s.read_bytes() {
                Some(_) if hide => "(hidden)".into(),
                Some((last, most)) => format!("{last} B/frame (max {most})"),
                None => "—".into(),
            },
        ));
        rows.push(("renders".into(), s.renders_total.to_string()));
        if self.settings.view == View::Range {
            // The range view's marks, counted on the GPU (the probe): NaN, infinite or out of
            // [0, 1] V or t, per side shown.
            let sides = if self.settings.split { 2 } else { 1 };
            for slot in 0..sides {
                let label = match (sides, slot) {
                    (1, _) => "V/t out of range".to_string(),
                    (_, 0) => "out of range, left".to_string(),
                    _ => "out of range, right".to_string(),
                };
                let count = self
                    .inspector
                    .range_px(slot)
                    .map_or_else(|| "counting…".to_string(), |n| format!("{n} px"));
                rows.push((label, count));
            }
        }
        if let Some(core) = self.core.as_ref() {
            let scene = core.scene();
            let method = self.settings.method();
            let total: usize = scene.objects.iter().map(|o| o.mesh.triangles.len()).sum();
            rows.push((
                "triangles".into(),
                format!("{} casting, {total} in all", scene.caster_triangle_count()),
            ));
            let gpu = core.session.gpu_geometry(method);
            // The CPU stage's counts, or the GPU stage's once they came back (a frame or more
            // after its build).
            let g = match gpu {
                Some(gpu) => gpu.last_stats(),
                None => Some(
                    core.session
                        .geometry(method)
                        .map(|g| g.stats)
                        .unwrap_or_default(),
                ),
            };
            if gpu.is_some() {
                // Its time is the GPU pass `geometry_gpu`, not the UI thread's.
                let gpu_ms = self
                    .stats
                    .median_gpu_ms()
                    .into_iter()
                    .find(|(pass, _)| pass == crate::render::passes::geometry_gpu::SPAN)
                    .map(|(_, v)| v);
                let at = match gpu_ms {
                    Some(v) if !self.deterministic => format!("on the GPU, {v:.2} ms"),
                    _ => "on the GPU".to_string(),
                };
                rows.push(("geometry stage".into(), at));
            }
            let pair = |umbra: fn(&GeometryStats) -> usize,
                        penumbra: fn(&GeometryStats) -> usize| {
                g.as_ref().map_or_else(
                    || "…".to_string(),
                    |g| format!("{} umbra, {} penumbra", umbra(g), penumbra(g)),
                )
            };
            rows.push((
                "silhouette edges".into(),
                pair(|g| g.umbra_edges, |g| g.penumbra_edges),
            ));
            rows.push((
                "volume triangles".into(),
                pair(|g| g.umbra_triangles, |g| g.penumbra_triangles),
            ));
            rows.push((
                "geometry builds".into(),
                core.session.geometry_builds(method).0.to_string(),
            ));
        }
        rows_grid(ui, "stats-grid", rows);
        ui.label(RichText::new("render CPU ms (white) · frame CPU ms (green)").small());
        if hide {
            return;
        }
        let (rect, _) = ui.allocate_exact_size(
            Vec2::new(ui.available_width().max(60.0), 60.0),
            Sense::hover(),
        );
        plot(
            ui,
            rect,
            &[
                (
                    s.renders.iter().map(|r| r.wall_ms as f32).collect(),
                    Color32::WHITE,
                ),
                (
                    s.frame_cpu_ms.iter().copied().collect(),
                    Color32::from_rgb(120, 220, 120),
                ),
            ],
        );
    }
}

/// Sparklines of several series on one scale (0 to the largest value).
fn plot(ui: &egui::Ui, rect: Rect, series: &[(Vec<f32>, Color32)]) {
    let painter = ui.painter().with_clip_rect(rect);
    painter.rect_filled(rect, 2.0, Color32::from_black_alpha(120));
    let top = series
        .iter()
        .flat_map(|(v, _)| v.iter().copied())
        .filter(|v| v.is_finite())
        .fold(1.0f32, f32::max);
    for (values, color) in series {
        let n = values.len();
        if n < 2 {
            continue;
        }
        let points: Vec<Pos2> = values
            .iter()
            .enumerate()
            .map(|(k, v)| {
                Pos2::new(
                    rect.left() + rect.width() * k as f32 / (n - 1) as f32,
                    rect.bottom() - rect.height() * (v / top).clamp(0.0, 1.0),
                )
            })
            .collect();
        painter.add(egui::Shape::line(points, Stroke::new(1.0, *color)));
    }
    painter.text(
        rect.left_top() + Vec2::new(3.0, 1.0),
        egui::Align2::LEFT_TOP,
        format!("{top:.0} ms"),
        egui::FontId::proportional(10.0),
        Color32::GRAY,
    );
}

/// Label / monospace value rows, two columns. The columns start as wide as the longest label
/// ("listed edges visited"): egui sizes a grid's columns from its last frame, so rows that
/// arrive with a probe would otherwise be laid out over a narrower column until the next repaint.
fn rows_grid(ui: &mut egui::Ui, id: &str, rows: Vec<(String, String)>) {
    egui::Grid::new(id)
        .num_columns(2)
        .min_col_width(118.0)
        .max_col_width(140.0)
        .show(ui, |ui| {
            for (k, v) in rows {
                ui.label(k);
                ui.label(RichText::new(v).monospace());
                ui.end_row();
            }
        });
}
