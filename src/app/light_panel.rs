//! The inspector's **light as seen from this pixel** panel: the light's disk as the
//! receiver under the cursor sees it, for every method. The reference's disk samples for that
//! one pixel are cast on the CPU ([`crate::geometry::oracle`], [`PANEL_SAMPLES`] rays, when the
//! cursor moves to another surface point) and marked blocked or free; for `dbuffer-fused` the
//! method's own view from its CPU twin ([`FusedTwin::light_from`]) is drawn over them: each listed
//! edge projected onto the light's plane, the chord it cuts, and the mask's samples shaded by the
//! layers between the pixel and each (lit where none). Nothing is read back from the GPU beyond the
//! one texel the inspector already reads (the position comes from the probe).

use eframe::egui::{self, Color32, Pos2, Rect, Sense, Stroke};
use glam::{Vec2, Vec3};

use crate::geometry::fused::{FusedParams, FusedPath, FusedTwin, LightFromPoint, MaskEval};
use crate::geometry::oracle::Oracle;
use crate::geometry::{PreparedCasters, VolumeParams};
use crate::render::methods::dbuffer_fused::{LIST_CAP, LIST_SIZE, MASK_SAMPLES};
use crate::render::{FrameRequest, Method};
use crate::scene::{Light, Scene};

/// Reference rays cast for the panel's one pixel.
pub const PANEL_SAMPLES: usize = 256;

/// One reference sample of the disk, in unit-disk coordinates (along the light's `basis`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiskSample {
    pub at: Vec2,
    pub blocked: bool,
}

/// What the panel shows for one pixel.
#[derive(Clone, Debug)]
pub struct PixelLight {
    /// The receiver (the probe's world position of the pixel).
    pub position: Vec3,
    pub method: Method,
    /// The light is a segment (drawn as a line, its samples along it), not a disk.
    pub line: bool,
    /// A rectangle's or polygon's corners in the same unit-disk coordinates (drawn as that
    /// polygon); empty for a disk or a line.
    pub corners: Vec<Vec2>,
    /// The reference's samples, cast from `position`.
    pub reference: Vec<DiskSample>,
    /// `dbuffer-fused`'s view of the disk from its CPU twin (only for that method).
    pub fused: Option<LightFromPoint>,
}

impl PixelLight {
    /// The share of the reference's samples that are blocked (1 − the reference's V here).
    pub fn blocked_fraction(&self) -> f64 {
        if self.reference.is_empty() {
            return 0.0;
        }
        self.reference.iter().filter(|s| s.blocked).count() as f64 / self.reference.len() as f64
    }

    /// The chords the panel draws (the fused twin's listed edges that cut the disk from here).
    pub fn chords_drawn(&self) -> usize {
        self.fused.as_ref().map_or(0, |f| f.chords.len())
    }

    /// The share of the mask's samples with no layer between the pixel and them (`None` where
    /// the method ran no mask here).
    pub fn mask_lit_fraction(&self) -> Option<f64> {
        let f = self.fused.as_ref()?;
        if f.layers.is_empty() {
            return None;
        }
        Some(f.layers.iter().filter(|&&l| l <= 0).count() as f64 / f.layers.len() as f64)
    }

    /// Rows for the inspector: the fused method's layers under the cursor.
    pub fn rows(&self) -> Vec<(String, String)> {
        let mut rows = vec![(
            format!("reference V ({} rays)", self.reference.len()),
            format!("{:.4}", 1.0 - self.blocked_fraction()),
        )];
        if let Some(f) = &self.fused {
            let path = match f.path {
                FusedPath::Outside => "outside the light view",
                FusedPath::Uniform => "empty list",
                FusedPath::Overflow => "list overflowed: every candidate edge (or dbuffer's V)",
                FusedPath::Mask => "mask over the list",
            };
            rows.push(("twin V".into(), format!("{:.4}", f.v)));
            rows.push(("path".into(), path.into()));
            rows.push(("list (light pass)".into(), f.list_count.to_string()));
            rows.push(("chords cutting".into(), f.chords.len().to_string()));
            if f.path == FusedPath::Mask {
                rows.push(("layers to c".into(), f.anchor.to_string()));
                let deepest = f.layers.iter().copied().max().unwrap_or(f.anchor);
                rows.push(("deepest layers".into(), deepest.to_string()));
                if let Some(v) = f.exact {
                    rows.push(("V exact (1 layer)".into(), format!("{v:.4}")));
                }
            }
        }
        rows
    }
}

/// What the panel's pictures are made from, per scene revision and fused setup.
struct Tools {
    revision: u64,
    params: FusedParams,
    oracle: Oracle,
    /// The unit-disk coordinates of the oracle's samples.
    disk: Vec<Vec2>,
    /// Made when the fused method is first inspected in this revision.
    twin: Option<FusedTwin>,
}

/// The panel's state: its tools and the last pixel it was computed for.
#[derive(Default)]
pub struct LightPanel {
    tools: Option<Tools>,
    key: Option<(u64, [u32; 3], Method, FusedParams)>,
    pub shown: Option<PixelLight>,
}

/// The twin's setup for the frame `request` drew (the GPU's look-up tables: `MaskEval::Lut`).
pub fn fused_params(request: &FrameRequest) -> FusedParams {
    FusedParams {
        size: request.dbuffer_size,
        list_size: request.knobs.get(&LIST_SIZE),
        cap: request.knobs.get(&LIST_CAP) as usize,
        samples: request.knobs.get(&MASK_SAMPLES) as usize,
        eval: MaskEval::Lut,
        vt: request.vt,
    }
}

impl LightPanel {
    /// Computes the panel for the receiver `x` shown by `method` (no work if nothing changed).
    pub fn update(
        &mut self,
        scene: &Scene,
        revision: u64,
        method: Method,
        x: Vec3,
        params: FusedParams,
    ) {
        let key = (revision, x.to_array().map(f32::to_bits), method, params);
        if self.key == Some(key) && self.shown.is_some() {
            return;
        }
        let stale = self
            .tools
            .as_ref()
            .is_none_or(|t| t.revision != revision || t.params != params);
        if stale {
            let oracle = Oracle::from_scene(scene, PANEL_SAMPLES);
            // The light's own frame, scaled to the unit disk (a segment: along u, from -1 to 1).
            let (e1, e2, r) = match &scene.light {
                Light::Area(d) => {
                    let (e1, e2) = d.basis();
                    (e1, e2, d.radius)
                }
                Light::Line(l) => {
                    let along = (l.b - l.a).normalize_or_zero();
                    (along, Vec3::ZERO, 0.5 * l.length())
                }
            };
            let (c, r) = (scene.light.center(), r.max(f32::MIN_POSITIVE));
            let disk = oracle
                .sample_points()
                .iter()
                .map(|&p| Vec2::new((p - c).dot(e1), (p - c).dot(e2)) / r)
                .collect();
            self.tools = Some(Tools {
                revision,
                params,
                oracle,
                disk,
                twin: None,
            });
        }
        let Some(tools) = self.tools.as_mut() else {
            return;
        };
        if method == Method::DBUFFER_FUSED && tools.twin.is_none() {
            let prepared = PreparedCasters::new(scene);
            let geometry = prepared.build(
                &scene.light.area_or_centre(),
                &VolumeParams::for_scene(scene),
            );
            tools.twin = Some(FusedTwin::new(scene, &prepared, &geometry, params));
        }
        let reference = tools
            .oracle
            .sample_points()
            .iter()
            .zip(&tools.disk)
            .map(|(p, &at)| DiskSample {
                at,
                blocked: tools.oracle.count_visible(x, std::slice::from_ref(p)) == 0,
            })
            .collect();
        let fused = (method == Method::DBUFFER_FUSED)
            .then(|| tools.twin.as_ref().map(|t| t.light_from(x)))
            .flatten();
        let corners = scene.light.as_area().map_or(Vec::new(), |a| {
            let (e1, e2) = a.basis();
            let r = a.radius.max(f32::MIN_POSITIVE);
            a.corners().map_or(Vec::new(), |p| {
                p.vertices()
                    .iter()
                    .map(|&v| Vec2::new((v - a.center).dot(e1), (v - a.center).dot(e2)) / r)
                    .collect()
            })
        });
        self.shown = Some(PixelLight {
            position: x,
            method,
            line: scene.light.as_line().is_some(),
            corners,
            reference,
            fused,
        });
        self.key = Some(key);
    }

    /// Forget the pixel (the cursor left the viewport or shows no surface).
    pub fn clear(&mut self) {
        self.shown = None;
        self.key = None;
    }
}

const FREE: Color32 = Color32::from_rgb(255, 214, 90);
const BLOCKED: Color32 = Color32::from_rgb(230, 60, 60);
const GAIN: Color32 = Color32::from_rgb(235, 90, 70);
const LOSE: Color32 = Color32::from_rgb(80, 150, 255);

/// The points where the line `a u + b v + c = 0` leaves the unit disk, if it crosses it.
fn chord_ends([a, b, c]: [f32; 3]) -> Option<[Vec2; 2]> {
    let n2 = a * a + b * b;
    if n2 <= 0.0 || c * c >= n2 {
        return None;
    }
    let n = Vec2::new(a, b) / n2.sqrt();
    let foot = -n * (c / n2.sqrt());
    let half = (1.0 - foot.length_squared()).max(0.0).sqrt();
    let along = n.perp() * half;
    Some([foot - along, foot + along])
}

/// Where the line `a u + b v + c = 0` crosses the convex polygon `corners`, if it does.
fn chord_ends_in(corners: &[Vec2], [a, b, c]: [f32; 3]) -> Option<[Vec2; 2]> {
    let f = |p: Vec2| a * p.x + b * p.y + c;
    let mut hits = Vec::with_capacity(2);
    for i in 0..corners.len() {
        let (p, q) = (corners[i], corners[(i + 1) % corners.len()]);
        let (fp, fq) = (f(p), f(q));
        if (fp > 0.0) != (fq > 0.0) {
            hits.push(p + (q - p) * (fp / (fp - fq)));
        }
    }
    match hits[..] {
        [p, q, ..] => Some([p, q]),
        _ => None,
    }
}

/// Draws the light as seen from the pixel into `ui` (a square as wide as the panel).
pub fn draw(ui: &mut egui::Ui, light: &PixelLight) {
    let side = ui.available_width().clamp(120.0, 260.0);
    let (rect, _) = ui.allocate_exact_size(egui::vec2(side, side), Sense::hover());
    let painter = ui.painter().with_clip_rect(rect);
    painter.rect_filled(rect, 2.0, Color32::from_gray(18));
    let centre = rect.center();
    let radius = side * 0.36;
    // Unit-disk (u, v) to the screen: v up.
    let at = |p: Vec2| Pos2::new(centre.x + p.x * radius, centre.y - p.y * radius);
    if light.line {
        painter.line_segment(
            [at(Vec2::new(-1.0, 0.0)), at(Vec2::new(1.0, 0.0))],
            Stroke::new(3.0, Color32::from_gray(120)),
        );
    } else if light.corners.len() >= 3 {
        let outline: Vec<Pos2> = light.corners.iter().map(|&p| at(p)).collect();
        painter.add(egui::Shape::convex_polygon(
            outline,
            Color32::from_gray(44),
            Stroke::new(1.0, Color32::from_gray(160)),
        ));
    } else {
        painter.circle_filled(centre, radius, Color32::from_gray(44));
        painter.circle_stroke(centre, radius, Stroke::new(1.0, Color32::from_gray(160)));
    }
    if let Some(f) = &light.fused {
        // The mask's samples as cells: lit green, hidden grey, darker the more layers hide them.
        for (s, &l) in f.samples.iter().zip(&f.layers) {
            let fill = if l <= 0 {
                Color32::from_rgb(60, 120, 60)
            } else {
                Color32::from_gray((100 - 18 * l.min(4)) as u8)
            };
            painter.rect_filled(
                Rect::from_center_size(at(*s), egui::vec2(7.0, 7.0)),
                1.0,
                fill,
            );
        }
    }
    for s in &light.reference {
        let color = if s.blocked { BLOCKED } else { FREE };
        painter.circle_filled(at(s.at), 1.5, color);
    }
    if let Some(f) = &light.fused {
        for c in &f.chords {
            let color = if c.chord.delta > 0 { GAIN } else { LOSE };
            // The edge as projected from the pixel onto the light's plane ...
            painter.line_segment(
                [at(c.chord.ends[0]), at(c.chord.ends[1])],
                Stroke::new(1.5, color),
            );
            // ... and the chord its plane through the pixel cuts from the light.
            let ends = if light.corners.len() >= 3 {
                chord_ends_in(&light.corners, c.chord.chord)
            } else {
                chord_ends(c.chord.chord)
            };
            if let Some([p, q]) = ends {
                painter.add(egui::Shape::dashed_line(
                    &[at(p), at(q)],
                    Stroke::new(1.0, color.gamma_multiply(0.7)),
                    4.0,
                    3.0,
                ));
            }
        }
    }
    let legend = if light.fused.is_some() {
        "dots: reference rays, yellow free, red blocked · cells: the method's mask, green lit, grey hidden (darker: more layers) · lines: listed edges projected from the pixel (red: a layer gained beyond, blue: lost), dashed: the chord each cuts"
    } else {
        "dots: reference rays, yellow free, red blocked"
    };
    ui.label(egui::RichText::new(legend).small());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chord_ends_lie_on_the_circle_and_the_line() {
        let line = [0.6f32, -0.8, 0.3];
        let [p, q] = chord_ends(line).expect("crosses");
        for e in [p, q] {
            assert!((e.length() - 1.0).abs() < 1e-5, "{e}");
            assert!((line[0] * e.x + line[1] * e.y + line[2]).abs() < 1e-5);
        }
        assert!(chord_ends([0.0, 1.0, 1.5]).is_none(), "misses the disk");
    }

    #[test]
    fn chord_ends_in_a_polygon_lie_on_its_edges_and_the_line() {
        let square = [
            Vec2::new(-1.0, -0.5),
            Vec2::new(1.0, -0.5),
            Vec2::new(1.0, 0.5),
            Vec2::new(-1.0, 0.5),
        ];
        let [p, q] = chord_ends_in(&square, [1.0, 1.0, -0.2]).expect("crosses");
        for e in [p, q] {
            assert!((e.x + e.y - 0.2).abs() < 1e-5, "{e}");
            assert!(
                (e.x.abs() - 1.0).abs() < 1e-5 || (e.y.abs() - 0.5).abs() < 1e-5,
                "{e}"
            );
        }
        assert!(
            chord_ends_in(&square, [0.0, 1.0, 0.9]).is_none(),
            "misses it"
        );
    }
}
