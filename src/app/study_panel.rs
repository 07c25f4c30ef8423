//! The study's plot for the open scene (`dbuffer gui SCENE --study DIR`): error against frame
//! time, both logarithmic, each method a line through its settings and the front in black, as
//! `study.md`'s plot draws it — and a point clicked switches the lab to that method and setting.

use std::path::{Path, PathBuf};

use eframe::egui;

use crate::render::Method;
use crate::study::front::{front, points, ErrorAxis, Point};
use crate::study::plot::{colour, LEAST_ERROR};
use crate::study::{SceneStudy, Study};

/// A cell picked on the plot: the lab shows its method with its setting.
#[derive(Clone, Debug, PartialEq)]
pub struct Pick {
    pub method: Method,
    /// The axes it sets, as `(flag name, value)` (`dbuffer-size` is the map size).
    pub values: Vec<(String, u32)>,
    /// The D-buffer / shadow-map size the cell was measured at.
    pub map_size: u32,
    pub label: String,
}

#[derive(Default)]
pub struct StudyPanel {
    /// The study folder given, and what was read from it.
    pub dir: Option<PathBuf>,
    study: Option<Study>,
    /// Why the study could not be read.
    pub error: Option<String>,
    /// The window is showing.
    pub open: bool,
    /// Where the last frame drew each point (screen points) and its cell: what a click is
    /// matched against (and tests click on).
    pub drawn: Vec<(egui::Pos2, usize)>,
}

impl StudyPanel {
    /// Read `DIR/study.json`; an unreadable study is kept as its error (shown in the window).
    pub fn load(dir: &Path) -> StudyPanel {
        let path = dir.join("study.json");
        let (study, error) = match std::fs::read_to_string(&path)
            .map_err(|e| e.to_string())
            .and_then(|text| serde_json::from_str::<Study>(&text).map_err(|e| e.to_string()))
        {
            Ok(s) => (Some(s), None),
            Err(e) => (None, Some(format!("cannot read {}: {e}", path.display()))),
        };
        StudyPanel {
            dir: Some(dir.to_path_buf()),
            study,
            error,
            open: true,
            drawn: Vec::new(),
        }
    }

    /// The study's cells of scene `name`.
    pub fn scene(&self, name: &str) -> Option<&SceneStudy> {
        self.study.as_ref()?.scenes.iter().find(|s| s.name == name)
    }

    /// The window with the plot of scene `name`; the cell clicked, if one was. `current` marks
    /// the point of what the lab shows (method and the values of its swept axes).
    pub fn ui(
        &mut self,
        ctx: &egui::Context,
        name: &str,
        current: &dyn Fn(&crate::study::Cell) -> bool,
    ) -> Option<Pick> {
        self.dir.as_ref()?;
        let mut open = self.open;
        let mut picked = None;
        let mut drawn = Vec::new();
        egui::Window::new("Study: error against cost")
            .open(&mut open)
            .default_size([520.0, 380.0])
            .show(ctx, |ui| {
                if let Some(e) = &self.error {
                    ui.colored_label(egui::Color32::LIGHT_RED, e);
                    return;
                }
                let Some(scene) = self.scene(name) else {
                    let names: Vec<&str> = self
                        .study
                        .iter()
                        .flat_map(|s| s.scenes.iter().map(|s| s.name.as_str()))
                        .collect();
                    ui.label(format!(
                        "the study has no cells of {name} (it has {})",
                        names.join(", ")
                    ));
                    return;
                };
                ui.label(
                    egui::RichText::new(format!(
                        "{name}: penumbra MAE against frame ms (log, log); noise floor {:.4}. \
                         Click a point to show it.",
                        scene.noise_floor
                    ))
                    .small(),
                );
                legend(ui, scene);
                (picked, drawn) = plot(ui, scene, current);
            });
        self.open = open;
        self.drawn = drawn;
        picked
    }
}

/// The plot's methods, each in its line's colour, in the registry's order.
fn legend(ui: &mut egui::Ui, scene: &SceneStudy) {
    let measured = |m: &Method| {
        scene
            .cells
            .iter()
            .any(|c| c.method == m.name() && c.error.is_some() && c.cost.is_some())
    };
    ui.horizontal_wrapped(|ui| {
        ui.spacing_mut().item_spacing.x = 8.0;
        for (i, m) in Method::all().iter().enumerate() {
            if measured(m) {
                let (r, g, b) = colour(i);
                ui.label(
                    egui::RichText::new(format!("— {}", m.name()))
                        .small()
                        .color(egui::Color32::from_rgb(r, g, b)),
                );
            }
        }
    });
}

/// Draw the plot into the rest of `ui`; the cell clicked, and where each point went.
fn plot(
    ui: &mut egui::Ui,
    scene: &SceneStudy,
    current: &dyn Fn(&crate::study::Cell) -> bool,
) -> (Option<Pick>, Vec<(egui::Pos2, usize)>) {
    let pts = points(scene, ErrorAxis::PenumbraMae);
    let size = ui.available_size().max(egui::vec2(320.0, 220.0));
    let (rect, response) = ui.allocate_exact_size(size, egui::Sense::click());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, egui::Color32::from_gray(250));
    if pts.is_empty() {
        painter.text(
            rect.center(),
            egui::Align2::CENTER_CENTER,
            "no cell measured both ways",
            egui::FontId::proportional(13.0),
            egui::Color32::DARK_GRAY,
        );
        return (None, Vec::new());
    }
    let area = rect.shrink2(egui::vec2(28.0, 18.0));
    let log = |v: f64| v.max(LEAST_ERROR).log10();
    let (mut x0, mut x1) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in &pts {
        x0 = x0.min(p.cost.log10());
        x1 = x1.max(p.cost.log10());
        y0 = y0.min(log(p.error));
        y1 = y1.max(log(p.error));
    }
    let pad = |lo: f64, hi: f64| {
        let d = (hi - lo).max(0.2) * 0.08;
        (lo - d, hi + d)
    };
    let (x0, x1) = pad(x0, x1);
    let (y0, y1) = pad(y0, y1);
    let at = |p: &Point| {
        egui::pos2(
            area.left() + ((p.cost.log10() - x0) / (x1 - x0)) as f32 * area.width(),
            area.bottom() - ((log(p.error) - y0) / (y1 - y0)) as f32 * area.height(),
        )
    };
    // Decade grid lines with labels.
    let grid = egui::Stroke::new(1.0, egui::Color32::from_gray(225));
    let font = egui::FontId::proportional(10.0);
    for d in (x0.ceil() as i32)..=(x1.floor() as i32) {
        let x = area.left() + ((f64::from(d) - x0) / (x1 - x0)) as f32 * area.width();
        painter.line_segment(
            [egui::pos2(x, area.top()), egui::pos2(x, area.bottom())],
            grid,
        );
        painter.text(
            egui::pos2(x, rect.bottom() - 2.0),
            egui::Align2::CENTER_BOTTOM,
            format!("{} ms", 10f64.powi(d)),
            font.clone(),
            egui::Color32::GRAY,
        );
    }
    for d in (y0.ceil() as i32)..=(y1.floor() as i32) {
        let y = area.bottom() - ((f64::from(d) - y0) / (y1 - y0)) as f32 * area.height();
        painter.line_segment(
            [egui::pos2(area.left(), y), egui::pos2(area.right(), y)],
            grid,
        );
        painter.text(
            egui::pos2(rect.left() + 2.0, y),
            egui::Align2::LEFT_CENTER,
            format!("{}", 10f64.powi(d)),
            font.clone(),
            egui::Color32::GRAY,
        );
    }
    // Each method's line, then the front, then the points.
    let index_of = |name: &str| Method::all().iter().position(|m| m.name() == name);
    let mut methods: Vec<&str> = Vec::new();
    for p in &pts {
        let m = scene.cells[p.cell].method.as_str();
        if !methods.contains(&m) {
            methods.push(m);
        }
    }
    for m in &methods {
        let (r, g, b) = colour(index_of(m).unwrap_or(0));
        let mut line: Vec<&Point> = pts
            .iter()
            .filter(|p| scene.cells[p.cell].method == *m)
            .collect();
        line.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        let path: Vec<egui::Pos2> = line.iter().map(|p| at(p)).collect();
        painter.add(egui::Shape::line(
            path,
            egui::Stroke::new(1.5, egui::Color32::from_rgb(r, g, b)),
        ));
    }
    let f: Vec<egui::Pos2> = front(&pts).iter().map(at).collect();
    painter.add(egui::Shape::line(
        f,
        egui::Stroke::new(1.0, egui::Color32::BLACK),
    ));
    let hover = response.hover_pos();
    let mut nearest: Option<(f32, usize, egui::Pos2)> = None;
    let mut drawn = Vec::with_capacity(pts.len());
    for p in &pts {
        let pos = at(p);
        let cell = &scene.cells[p.cell];
        let (r, g, b) = colour(index_of(&cell.method).unwrap_or(0));
        let c = egui::Color32::from_rgb(r, g, b);
        painter.circle_filled(pos, 3.5, c);
        if current(cell) {
            painter.circle_stroke(pos, 7.0, egui::Stroke::new(2.0, egui::Color32::BLACK));
        }
        drawn.push((pos, p.cell));
        if let Some(h) = hover {
            let d = h.distance(pos);
            if d < 10.0 && nearest.is_none_or(|n| d < n.0) {
                nearest = Some((d, p.cell, pos));
            }
        }
    }
    let mut picked = None;
    if let Some((_, i, pos)) = nearest {
        let cell = &scene.cells[i];
        let p = pts.iter().find(|p| p.cell == i);
        painter.circle_stroke(pos, 6.0, egui::Stroke::new(1.5, egui::Color32::DARK_GRAY));
        let text = format!(
            "{} ({})\n{:.2} ms · penumbra MAE {:.4}",
            cell.method,
            cell.setting,
            p.map_or(0.0, |p| p.cost),
            p.map_or(0.0, |p| p.error)
        );
        painter.text(
            pos + egui::vec2(8.0, -8.0),
            egui::Align2::LEFT_BOTTOM,
            text,
            egui::FontId::proportional(11.0),
            egui::Color32::BLACK,
        );
        if response.clicked() {
            if let Ok(method) = cell.method.parse::<Method>() {
                picked = Some(Pick {
                    method,
                    values: cell.values.clone(),
                    map_size: cell.map_size,
                    label: format!("{} ({})", cell.method, cell.setting),
                });
            }
        }
    }
    (picked, drawn)
}
