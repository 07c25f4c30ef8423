//! The right panel: the pixel inspector (the exact values under the cursor, read from the frame's
//! arrays, whatever the display mapping) and the stats (timings, frame rate, counts).

use eframe::egui::{self, Color32, Pos2, Rect, RichText, Sense, Stroke, Vec2};
use glam::Vec3;

use super::viewport::Shown;
use super::views::{self, View, CHANNELS};
use super::LabApp;
use crate::render::Method;

/// The D-buffer texel a world point falls in, as the camera pass finds it.
pub fn texel_of(shown: &Shown, p: Vec3) -> Option<(u32, u32)> {
    let clip = shown.light_view.view_projection() * p.extend(1.0);
    if clip.w <= 0.0 {
        return None;
    }
    let n = shown.frame.dbuffer_size as f32;
    let (x, y) = (clip.x / clip.w, clip.y / clip.w);
    let (u, v) = (x * 0.5 + 0.5, 0.5 - y * 0.5);
    let tx = (u * n).floor().clamp(0.0, n - 1.0);
    let ty = (v * n).floor().clamp(0.0, n - 1.0);
    (tx.is_finite() && ty.is_finite()).then_some((tx as u32, ty as u32))
}

fn value(v: Option<f32>) -> String {
    v.map_or_else(|| "—".into(), |v| format!("{v:.5}"))
}

impl LabApp {
    pub(super) fn inspector_panel(&mut self, ui: &mut egui::Ui) {
        egui::Panel::right("inspector")
            .default_size(230.0)
            .min_size(230.0)
            .max_size(300.0)
            .resizable(true)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    ui.heading("Pixel");
                    self.pixel_section(ui);
                    ui.separator();
                    ui.heading("Stats");
                    self.stats_section(ui);
                });
            });
    }

    fn pixel_section(&self, ui: &mut egui::Ui) {
        let Some(hover) = self.viewport.hover else {
            ui.label(RichText::new("hover the viewport").small());
            return;
        };
        let shown = if hover.split {
            self.viewport.split.as_ref()
        } else {
            self.viewport.main.as_ref()
        };
        let Some(shown) = shown else { return };
        let f = &shown.frame;
        let mut rows: Vec<(String, String)> = Vec::new();
        rows.push(("method".into(), shown.method.name().into()));
        if self.settings.view == View::DBuffer {
            rows.push(("texel".into(), format!("{}, {}", hover.x, hover.y)));
            if let Some(t) = views::texel(f, hover.x, hover.y) {
                for (c, name) in CHANNELS.iter().enumerate().take(3) {
                    rows.push(((*name).into(), value(t.channel(c))));
                }
                rows.push(("|cx_s| umbra".into(), value(t.s_umbra)));
                rows.push(("|cx_s| penumbra".into(), value(t.s_penumbra)));
            }
        } else {
            let i = (hover.y * f.width + hover.x) as usize;
            rows.push(("pixel".into(), format!("{}, {}", hover.x, hover.y)));
            let Some(p) = f.position.get(i) else { return };
            if p[3] < 0.5 {
                rows.push(("surface".into(), "none".into()));
            } else {
                let x = Vec3::new(p[0], p[1], p[2]);
                rows.push((
                    "position".into(),
                    format!("{:.3}, {:.3}, {:.3}", x.x, x.y, x.z),
                ));
                rows.push((
                    "|cx|".into(),
                    format!("{:.5}", (x - shown.light.center).length()),
                ));
                if let Some(t) = texel_of(shown, x).and_then(|(tx, ty)| views::texel(f, tx, ty)) {
                    for (c, name) in CHANNELS.iter().enumerate().take(3) {
                        rows.push(((*name).into(), value(t.channel(c))));
                    }
                    rows.push(("|cx_s| umbra".into(), value(t.s_umbra)));
                    rows.push(("|cx_s| penumbra".into(), value(t.s_penumbra)));
                }
                let branch = f.branch.get(i).copied().unwrap_or(0);
                rows.push(("branch".into(), views::branch_name(branch).into()));
                rows.push(("t".into(), value(f.t.get(i).copied())));
                rows.push(("V".into(), value(f.visibility.get(i).copied())));
                let reference = if shown.method == Method::Reference {
                    None
                } else {
                    self.core
                        .as_ref()
                        .and_then(|c| c.reference_visibility())
                        .filter(|r| r.len() == f.visibility.len())
                        .and_then(|r| r.get(i).copied())
                };
                let samples = shown
                    .reference
                    .map(|(done, total)| format!(" (K {done}/{total})"))
                    .unwrap_or_default();
                rows.push((format!("reference V{samples}"), value(reference)));
            }
        }
        rows_grid(ui, "pixel-grid", rows);
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
        if let Some(main) = &self.viewport.main {
            rows.push((
                "frame".into(),
                format!(
                    "{}×{}, D-buffer {}²",
                    main.frame.width, main.frame.height, main.frame.dbuffer_size
                ),
            ));
        }
        let hide = self.deterministic;
        let ms = |v: Option<f64>| match v {
            Some(_) if hide => "(hidden)".to_string(),
            Some(v) => format!("{v:.1} ms"),
            None => "—".into(),
        };
        // Median CPU wall time of a render, apart for renders that rebuilt the geometry.
        rows.push(("render".into(), ms(s.median_wall_ms(false))));
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
        rows.push(("renders".into(), s.renders_total.to_string()));
        if let Some(core) = self.core.as_ref() {
            let scene = core.scene();
            let g = &core.geometry().stats;
            let total: usize = scene.objects.iter().map(|o| o.mesh.triangles.len()).sum();
            rows.push((
                "triangles".into(),
                format!("{} casting, {total} in all", scene.caster_triangle_count()),
            ));
            rows.push((
                "silhouette edges".into(),
                format!("{} umbra, {} penumbra", g.umbra_edges, g.penumbra_edges),
            ));
            rows.push((
                "volume triangles".into(),
                format!(
                    "{} umbra, {} penumbra",
                    g.umbra_triangles, g.penumbra_triangles
                ),
            ));
            rows.push(("geometry builds".into(), core.geometry_builds().to_string()));
        }
        rows_grid(ui, "stats-grid", rows);
        ui.label(RichText::new("render ms (white) · frame CPU ms (green)").small());
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

/// Label / monospace value rows, two columns.
fn rows_grid(ui: &mut egui::Ui, id: &str, rows: Vec<(String, String)>) {
    egui::Grid::new(id)
        .num_columns(2)
        .max_col_width(140.0)
        .show(ui, |ui| {
            for (k, v) in rows {
                ui.label(k);
                ui.label(RichText::new(v).monospace());
                ui.end_row();
            }
        });
}
