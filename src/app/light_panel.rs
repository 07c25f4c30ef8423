//! The inspector's **light as seen from this pixel** panel: the light's disk as the
//! receiver under the cursor sees it, for every method. The reference's disk samples for that
//! one pixel are cast on the CPU ([`crate::geometry::oracle`], [`PANEL_SAMPLES`] rays, when the
//! cursor moves to another surface point, against a BVH made on a worker thread: see
//! [`LightPanel`]) and marked blocked or free; for `dbuffer-fused` the
//! method's own view from its CPU twin ([`FusedTwin::light_from`]) is drawn over them: each listed
//! edge projected onto the light's plane, the chord it cuts, and the mask's samples shaded by the
//! layers between the pixel and each (lit where none). Nothing is read back from the GPU beyond the
//! one texel the inspector already reads (the position comes from the probe).

use eframe::egui::{self, Color32, Pos2, Rect, Sense, Stroke};
use std::sync::mpsc;

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

/// Which scene the panel's tools are for: `scene` changes with every edit (the light's too),
/// `geometry` only when a mesh does (an object moved, another scene opened).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Revisions {
    pub scene: u64,
    pub geometry: u64,
}

/// What the tools are made for: the scene's revision and, for `dbuffer-fused`, its setup.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ToolsKey {
    revisions: Revisions,
    /// `Some` where the fused method's twin is wanted.
    fused: Option<FusedParams>,
}

/// What the panel's pictures are made from.
struct Tools {
    key: ToolsKey,
    oracle: Oracle,
    /// The unit-disk coordinates of the oracle's samples.
    disk: Vec<Vec2>,
    twin: Option<FusedTwin>,
}

/// Tools being made on a thread of their own.
struct Job {
    key: ToolsKey,
    done: mpsc::Receiver<Tools>,
}

/// The panel's state: its tools, the job making new ones, and the last pixel it was computed
/// for.
///
/// The tools (the oracle's BVH over every triangle, and `dbuffer-fused`'s twin) are made on a
/// worker thread, never the UI thread: at a million triangles the BVH takes a second or more,
/// and an edit would stall the window that long. A light move keeps the BVH (it depends on the
/// triangles alone) and makes only the light's samples and the twin anew. Until the tools for
/// the scene shown are ready the panel says so; one job runs at a time, and one for a scene
/// already edited again is followed by one for the newest.
#[derive(Default)]
pub struct LightPanel {
    tools: Option<Tools>,
    job: Option<Job>,
    key: Option<(u64, [u32; 3], Method, FusedParams)>,
    pub shown: Option<PixelLight>,
    /// Why the last job could not run, if it could not.
    pub error: Option<String>,
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

/// The tools for `key`, the BVH taken from `reuse` where it was built on the same triangles.
fn make_tools(scene: &Scene, key: ToolsKey, reuse: Option<Oracle>) -> Tools {
    let oracle = match reuse {
        Some(o) => o.relit(scene.light, PANEL_SAMPLES),
        None => Oracle::from_scene(scene, PANEL_SAMPLES),
    };
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
    let twin = key.fused.map(|params| {
        let prepared = PreparedCasters::new(scene);
        let geometry = prepared.build(
            &scene.light.area_or_centre(),
            &VolumeParams::for_scene(scene),
        );
        FusedTwin::new(scene, &prepared, &geometry, params)
    });
    Tools {
        key,
        oracle,
        disk,
        twin,
    }
}

impl LightPanel {
    /// Computes the panel for the receiver `x` shown by `method` (no work if nothing changed).
    /// Where the tools for `revisions` are not made yet, starts making them on a worker thread
    /// (`ready` is called from it when they are) and shows nothing until they are.
    pub fn update(
        &mut self,
        scene: &Scene,
        revisions: Revisions,
        method: Method,
        x: Vec3,
        params: FusedParams,
        ready: impl Fn() + Send + 'static,
    ) {
        let key = (
            revisions.scene,
            x.to_array().map(f32::to_bits),
            method,
            params,
        );
        if self.key == Some(key) && self.shown.is_some() {
            return;
        }
        let want = ToolsKey {
            revisions,
            fused: (method == Method::DBUFFER_FUSED).then_some(params),
        };
        self.collect();
        if self.tools.as_ref().is_none_or(|t| t.key != want) {
            self.shown = None;
            self.key = None;
            if self.job.is_none() {
                self.start(scene, want, ready);
            }
            return;
        }
        let Some(tools) = self.tools.as_ref() else {
            return;
        };
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
        let fused = tools.twin.as_ref().map(|t| t.light_from(x));
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

    /// Whether tools are being made (the panel shows nothing new until they are).
    pub fn preparing(&self) -> bool {
        self.job.is_some()
    }

    /// Blocks until the job in flight, if any, is done (for tests: the window never waits).
    pub fn wait(&mut self) {
        if let Some(job) = self.job.take() {
            if let Ok(tools) = job.done.recv() {
                self.tools = Some(tools);
            }
        }
    }

    /// The oracle the panel's reference rays are cast with, once made (a test holds a clone to
    /// see whether a later one shares its BVH: [`Oracle::shares_bvh`]).
    pub fn oracle(&self) -> Option<&Oracle> {
        self.tools.as_ref().map(|t| &t.oracle)
    }

    /// Takes the job's tools where it has finished.
    fn collect(&mut self) {
        let Some(job) = self.job.as_ref() else {
            return;
        };
        match job.done.try_recv() {
            Ok(tools) => {
                self.tools = Some(tools);
                self.job = None;
            }
            Err(mpsc::TryRecvError::Empty) => {}
            Err(mpsc::TryRecvError::Disconnected) => {
                self.error = Some(format!(
                    "making the reference's rays for revision {} failed",
                    job.key.revisions.scene
                ));
                self.job = None;
            }
        }
    }

    /// Starts the job that makes the tools for `key`; the scene is copied for it only where
    /// its triangles are needed (a new BVH, or the fused twin).
    fn start(&mut self, scene: &Scene, key: ToolsKey, ready: impl Fn() + Send + 'static) {
        let reuse = self
            .tools
            .as_ref()
            .filter(|t| t.key.revisions.geometry == key.revisions.geometry)
            .map(|t| t.oracle.clone());
        let scene = if reuse.is_some() && key.fused.is_none() {
            Scene {
                name: scene.name.clone(),
                camera: scene.camera,
                light: scene.light,
                objects: Vec::new(),
            }
        } else {
            scene.clone()
        };
        let (send, done) = mpsc::channel();
        let spawned = std::thread::Builder::new()
            .name("light-panel".into())
            .spawn(move || {
                let _ = send.send(make_tools(&scene, key, reuse));
                ready();
            });
        match spawned {
            Ok(_) => {
                self.job = Some(Job { key, done });
                self.error = None;
            }
            Err(e) => self.error = Some(format!("cannot start the reference's thread: {e}")),
        }
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
