//! The files of `dbuffer compare`: per method its image, its visibility EXR and its error
//! heatmap, then `montage.png` (every method on one page), `report.md` and `report.json` with the
//! metrics and timings (the same table is printed to stdout).

use crate::render::truth;
use std::io;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::temporal::{self, Motion};
use super::{heatmap, montage, Against, Comparison, MethodResult, Outline};
use crate::output::{self, OutputError, Staged};
use crate::render::Method;
use crate::scene::LightKind;

pub const REPORT_MD: &str = "report.md";
pub const REPORT_JSON: &str = "report.json";

/// `report.json`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Report {
    pub scene: String,
    pub adapter: String,
    pub width: u32,
    pub height: u32,
    pub dbuffer_size: u32,
    pub vt: String,
    /// The reference's disk samples per pixel (K).
    pub samples: u32,
    pub reference_rays_per_s: f64,
    /// Which engine traced the reference's shadow rays: "cpu" (the oracle) or "gpu"
    /// (`--reference gpu`); absent in older reports, which were all the CPU's.
    #[serde(default = "cpu_engine")]
    pub reference: String,
    /// Pixels that count (a surface facing the light).
    pub pixels: usize,
    pub methods: Vec<MethodRow>,
    /// Methods that refuse the scene's light, with the reason (absent in older reports).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_applicable: Vec<NotApplicable>,
    /// `--orbit`: the run in motion (absent without it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion: Option<MotionReport>,
}

/// The engine of a report that names none: every report before `--reference` was the CPU's.
fn cpu_engine() -> String {
    "cpu".into()
}

/// `compare --orbit`'s setup and what it found (docs/method/metrics.md, "In motion").
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MotionReport {
    /// "light", "camera" or "still".
    pub orbit: String,
    pub frames: usize,
    /// The reference's K, the same sample pattern on the light in every frame.
    pub samples: u32,
    /// The mean over steps of the pixels counted in both frames.
    pub counted_pixels: f64,
    /// The reference's own motion: the mean over steps of the mean |ΔV_ref|.
    pub reference_motion: f64,
    /// The method with the largest temporal error, and the APNG of its error beside the
    /// reference's motion.
    pub worst: Option<String>,
    pub apng: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// A method `compare` did not draw: it cannot take the scene's light, or the adapter lacks
/// what it needs.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct NotApplicable {
    pub method: String,
    /// The kinds of light it takes (`"disk"`, `"line"`, `"disk, rect, polygon"`); or what the
    /// adapter lacks for it.
    pub needs: String,
    pub reason: String,
}

/// One method's row of the report.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MethodRow {
    /// The method's name; a temporal method's first frame is `NAME-first-frame`.
    pub method: String,
    /// A temporal method's frames of history before the frame scored (0: its first frame);
    /// null for every other method.
    #[serde(default)]
    pub history_frames: Option<u32>,
    pub class_mismatch_pct: f64,
    pub mae: f64,
    pub penumbra_mae: f64,
    pub p99: f64,
    /// Pixels the reference calls penumbra.
    pub penumbra_pixels: usize,
    /// GPU ms of the method's passes (timestamp queries); null without them.
    pub gpu_ms: Option<f64>,
    /// CPU ms of the method's per-frame work (geometry, or ray casting for the reference).
    pub cpu_ms: f64,
    pub wall_ms: f64,
    pub image: String,
    pub visibility: String,
    /// Null for the reference itself.
    pub heatmap: Option<String>,
    /// A hard method against `reference-hard`; null for the others.
    #[serde(default)]
    pub hard: Option<HardRow>,
    /// FLIP of its shaded image against the reference's, the mean over every pixel (0 for the
    /// reference itself).
    #[serde(default)]
    pub flip_mean: f64,
    /// The FLIP map (`METHOD-flip.png`).
    #[serde(default)]
    pub flip: String,
    /// Its work per pixel (its cost view); absent in older reports.
    #[serde(default)]
    pub cost: Option<CostRow>,
    /// `--orbit`: the mean over consecutive frames of the mean |ΔV − ΔV_ref| (null without an
    /// orbit, and for the references).
    #[serde(default)]
    pub temporal_error: Option<f64>,
    /// `--orbit`: the pixels whose class changed in the method but not in the reference, in %
    /// of the counted pixels, the mean over steps.
    #[serde(default)]
    pub popping: Option<f64>,
    /// `--orbit`: those pixels, counted over every step.
    #[serde(default)]
    pub popping_px: Option<usize>,
    /// `--orbit`: the plot of its temporal error per frame (`METHOD-temporal.png`).
    #[serde(default)]
    pub temporal_plot: Option<String>,
    /// Pixels showing a surface whose V or t is NaN, infinite, below 0 or above 1 (what the
    /// lab's range view marks; [`crate::render::Frame::out_of_range`]): 0 for a sound method,
    /// and in reports older than the count.
    #[serde(default)]
    pub invalid_px: usize,
}

/// What a method's camera pass did per pixel that counts (its cost view: the unit its
/// `MethodSpec` names).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CostRow {
    pub unit: String,
    pub mean: f64,
    pub max: f64,
    /// The same work at every counted pixel it did any.
    pub constant: bool,
    /// The share of counted pixels, in %, that took each path it names (by code; a method with
    /// one path has none).
    pub paths: Vec<(String, f64)>,
    /// The heatmap (`METHOD-cost.png`).
    pub image: String,
}

/// A hard method against the exact hard shadow (`reference-hard`), classes lit iff V ≥ ½.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct HardRow {
    pub mismatch_pct: f64,
    /// Mismatched pixels next to a change of the exact class (aliasing, a boundary moved).
    pub edge_px: usize,
    /// The other mismatched pixels (acne, leaks, missing or false shadows).
    pub interior_px: usize,
    /// Darkened where the exact hard shadow is lit.
    pub false_shadow_px: usize,
    /// Lit where the exact hard shadow is dark.
    pub missed_shadow_px: usize,
    /// Where: the mismatched pixels over the method's image (red false, blue missed).
    #[serde(default)]
    pub image: String,
}

/// A hard method's mismatch against `reference-hard`, as an image.
fn hard_file(label: &str) -> String {
    format!("{label}-hard-error.png")
}

/// A method's FLIP map and cost heatmap.
fn flip_file(label: &str) -> String {
    format!("{label}-flip.png")
}

fn cost_file(label: &str) -> String {
    format!("{label}-cost.png")
}

/// A row's image, visibility EXR and error heatmap (none for the reference), by its label.
fn files(method: Method, n: &str) -> (String, String, Option<String>) {
    (
        format!("{n}.png"),
        format!("{n}-visibility.exr"),
        (!truth::is_soft(method)).then(|| format!("{n}-error.png")),
    )
}

impl Report {
    pub fn new(c: &Comparison) -> Report {
        let mask = &c.mask;
        Report::of(
            &c.outline(),
            c.results.iter().map(|r| row(r, mask)).collect(),
        )
    }

    /// The report of a comparison outlined by `o`, with one row a method drawn (in `o.drawn`'s
    /// order).
    pub fn of(o: &Outline, methods: Vec<MethodRow>) -> Report {
        Report {
            scene: o.scene.clone(),
            adapter: o.adapter.clone(),
            width: o.request.width,
            height: o.request.height,
            dbuffer_size: o.request.dbuffer_size,
            vt: o.request.vt.name().to_string(),
            samples: o.request.samples(),
            reference_rays_per_s: o.reference_rays_per_s,
            reference: o.reference_engine.name().to_string(),
            pixels: o.pixels,
            methods,
            not_applicable: o
                .not_applicable
                .iter()
                .map(|(m, needs, why)| NotApplicable {
                    method: m.name().to_string(),
                    needs: needs.clone(),
                    reason: why.clone(),
                })
                .collect(),
            motion: None,
        }
    }

    /// The report of a still comparison `c` with its run in motion.
    pub fn with_motion(c: &Comparison, motion: &Motion) -> Report {
        let mut r = Report::new(c);
        r.add_motion(motion);
        r
    }

    /// Add the run in motion: each method's temporal numbers, and the motion's summary.
    pub fn add_motion(&mut self, motion: &Motion) {
        for row in &mut self.methods {
            let Some(m) = motion
                .methods
                .iter()
                .find(|m| m.method.name() == row.method)
            else {
                continue;
            };
            row.temporal_error = Some(m.temporal_error());
            row.popping = Some(motion.popping_pct(m));
            row.popping_px = Some(m.popping.iter().sum());
            row.temporal_plot = Some(temporal::plot_file(m.method));
        }
        let worst = motion.worst();
        self.motion = Some(MotionReport {
            orbit: motion.orbit.clone(),
            frames: motion.frames,
            samples: motion.samples,
            counted_pixels: motion.counted.iter().sum::<usize>() as f64
                / motion.counted.len().max(1) as f64,
            reference_motion: motion.reference_motion.iter().sum::<f64>()
                / motion.reference_motion.len().max(1) as f64,
            worst: worst.map(|m| m.method.name().to_string()),
            apng: worst.map(|_| temporal::MOTION_APNG.to_string()),
            note: motion.note.clone(),
        });
    }

    /// The temporal table (empty without an orbit): one row a method, sorted as the registry.
    pub fn temporal_table(&self) -> String {
        if self.motion.is_none() {
            return String::new();
        }
        let mut s = String::from(
            "| method | temporal error | popping % a step | popping px | plot |\n\
             |---|---:|---:|---:|---|\n",
        );
        for m in &self.methods {
            let (Some(t), Some(p), Some(px), Some(plot)) =
                (m.temporal_error, m.popping, m.popping_px, &m.temporal_plot)
            else {
                continue;
            };
            s.push_str(&format!(
                "| {} | {t:.4} | {p:.3} | {px} | [{plot}]({plot}) |\n",
                m.method
            ));
        }
        s
    }

    /// The markdown report: a header naming the setup, then the table.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "# `{}`: every method against the ray-cast reference\n\n\
             {}×{} pixels ({} facing the light), reference K = {} disk samples per pixel \
             ({:.1} M rays/s on the {}), D-buffer {}², V(t) {}. Adapter: {}.\n\n",
            self.scene,
            self.width,
            self.height,
            self.pixels,
            self.samples,
            self.reference_rays_per_s / 1e6,
            self.reference.to_uppercase(),
            self.dbuffer_size,
            self.vt,
            self.adapter
        );
        s.push_str(&format!(
            "![every method: image, |V − V_ref|, against reference-hard]({})\n\n",
            montage::MONTAGE_PNG
        ));
        s.push_str(&self.table());
        if let Some(m) = &self.motion {
            s.push_str(&format!(
                "\n## In motion: the {} orbit, {} frames\n\nEvery method at every frame of the \
                 orbit `dbuffer animate` uses, against the reference at K = {} with the same \
                 sample pattern on the light in every frame (its own noise does not count as \
                 motion). Temporal error: the mean over consecutive frames of the mean \
                 |ΔV − ΔV_ref| over the {:.0} pixels counted in both (ΔV: the change since the \
                 frame before); the reference itself moves {:.4} a step on average. Popping: \
                 pixels whose class (lit / penumbra / umbra) changes in the method but not in the \
                 reference.{}\n\n",
                m.orbit,
                m.frames,
                m.samples,
                m.counted_pixels,
                m.reference_motion,
                m.note
                    .as_ref()
                    .map_or(String::new(), |n| format!(" Note: {n}."))
            ));
            if let (Some(worst), Some(apng)) = (&m.worst, &m.apng) {
                s.push_str(&format!(
                    "![{worst}'s |ΔV − ΔV_ref| (left) beside the reference's own |ΔV| (right), \
                     a frame per step]({apng})\n\n"
                ));
            }
            s.push_str(&self.temporal_table());
        }
        let hard = self.hard_table();
        if !hard.is_empty() {
            s.push_str(
                "\n## Hard methods against `reference-hard`\n\nThe methods that use the light's \
                 centre as a point light, against the exact hard shadow (one ray per pixel to the \
                 centre). Classes: lit iff V ≥ ½. Edge px: mismatched pixels with a change of the \
                 exact class among their 8 neighbours (aliasing, staircases, a boundary moved); \
                 interior px: the others (acne, light leaks, shadows missing or false away from \
                 any true boundary). Where: red = a false shadow, blue = a missed one, over the \
                 method's image.\n\n",
            );
            s.push_str(&hard);
        }
        s.push_str(
            "\n## Where each method spends its work\n\nWhat each method's camera pass counted \
             per pixel that counts (its cost view in the lab): taps, steps, listed edges, maps \
             or rays, in the unit it names, and the share of pixels on each of its paths.\n\n",
        );
        s.push_str(&self.cost_table());
        s.push_str(
            "\nClass mismatch: pixels whose class (lit V ≥ 0.996, umbra V ≤ 0.004, penumbra \
             otherwise) differs from the reference's. MAE and p99 of |V − V_ref| over the pixels \
             that count; penumbra MAE over the reference's penumbra. GPU ms: the method's own \
             passes; CPU ms: its per-frame CPU work (geometry for the D-buffer methods, ray \
             casting for the reference). FLIP: the mean over every pixel of LDR-FLIP (Andersson et al. \
             2020, at 67 pixels per degree) of the method's shaded image against the reference's; \
             its map is METHOD-flip.png.\n",
        );
        s
    }

    /// The table alone (also printed to stdout).
    pub fn table(&self) -> String {
        let mut s = String::from(
            "| method | class mismatch % | MAE | penumbra MAE | p99 \\|ΔV\\| | FLIP | GPU ms | CPU ms | heatmap |\n\
             |---|---:|---:|---:|---:|---:|---:|---:|---|\n",
        );
        for m in &self.methods {
            let gpu = m.gpu_ms.map_or("n/a".to_string(), |g| format!("{g:.2}"));
            let heat = m
                .heatmap
                .as_ref()
                .map_or("—".to_string(), |h| format!("[{h}]({h})"));
            s.push_str(&format!(
                "| {} | {:.2} | {:.4} | {:.4} | {:.3} | {:.4} | {} | {:.2} | {} |\n",
                m.method,
                m.class_mismatch_pct,
                m.mae,
                m.penumbra_mae,
                m.p99,
                m.flip_mean,
                gpu,
                m.cpu_ms,
                heat
            ));
        }
        for n in &self.not_applicable {
            // The lights it takes ("disk", "disk, rect, polygon"), or what the adapter lacks.
            let kinds: Option<Vec<LightKind>> = n
                .needs
                .split(", ")
                .map(|k| LightKind::ALL.into_iter().find(|l| l.name() == k))
                .collect();
            let needs = match kinds {
                Some(k) => format!("a {} light", LightKind::list_in_words(&k)),
                None => n.needs.clone(),
            };
            s.push_str(&format!(
                "| {} | n/a — needs {needs} | | | | | | | |\n",
                n.method
            ));
        }
        s.push_str(&self.invalid_line());
        s
    }

    /// Under the table, only when some method returned them: the pixels whose V or t is NaN,
    /// infinite or outside [0, 1], per method (the scores count a non-finite V as the worst
    /// error, |ΔV| = 1 and the wrong class; a finite V out of range as it is).
    pub fn invalid_line(&self) -> String {
        let bad: Vec<String> = self
            .methods
            .iter()
            .filter(|m| m.invalid_px > 0)
            .map(|m| format!("{} {} px", m.method, m.invalid_px))
            .collect();
        if bad.is_empty() {
            return String::new();
        }
        format!(
            "\n**V or t out of range** (NaN, infinite, below 0 or above 1; the lab's NaN / range \
             view shows where): {}.\n",
            bad.join(", ")
        )
    }
}

impl Report {
    /// Each method's work per pixel (its cost view), one row a method.
    pub fn cost_table(&self) -> String {
        let mut s = String::from(
            "| method | unit | mean | max | paths (% of counted pixels) | heatmap |\n\
             |---|---|---:|---:|---|---|\n",
        );
        for m in &self.methods {
            let Some(c) = &m.cost else { continue };
            let paths: Vec<String> = c
                .paths
                .iter()
                .filter(|(_, pct)| *pct > 0.0)
                .map(|(name, pct)| format!("{name} {pct:.1}"))
                .collect();
            let unit = if c.constant {
                format!("{} (constant)", c.unit)
            } else {
                c.unit.clone()
            };
            s.push_str(&format!(
                "| {} | {unit} | {:.2} | {:.0} | {} | [{}]({}) |\n",
                m.method,
                c.mean,
                c.max,
                if paths.is_empty() {
                    "—".to_string()
                } else {
                    paths.join("; ")
                },
                c.image,
                c.image
            ));
        }
        s
    }

    /// The hard methods against `reference-hard` (empty when none was measured).
    pub fn hard_table(&self) -> String {
        let rows: Vec<(&str, &HardRow)> = self
            .methods
            .iter()
            .filter_map(|m| m.hard.as_ref().map(|h| (m.method.as_str(), h)))
            .collect();
        if rows.is_empty() {
            return String::new();
        }
        let mut s = String::from(
            "| method | mismatch % | edge px | interior px | false shadow px | missed shadow px | where |\n\
             |---|---:|---:|---:|---:|---:|---|\n",
        );
        for (name, h) in rows {
            s.push_str(&format!(
                "| {name} | {:.3} | {} | {} | {} | {} | [{}]({}) |\n",
                h.mismatch_pct,
                h.edge_px,
                h.interior_px,
                h.false_shadow_px,
                h.missed_shadow_px,
                h.image,
                h.image
            ));
        }
        s
    }
}

/// A method's cost over the pixels that count, in one pass (nothing held per pixel).
fn cost_row(r: &MethodResult, mask: &[bool]) -> Option<CostRow> {
    let spec = r.method.spec().cost;
    let (mut n, mut sum, mut max) = (0usize, 0.0f64, 0.0f64);
    // The work of the first pixel that did any, and whether every other one did the same.
    let (mut first, mut constant) = (None, true);
    let mut on_path = vec![0usize; spec.paths.len()];
    for (c, _) in r.frame.cost.iter().zip(mask).filter(|(_, &m)| m) {
        n += 1;
        sum += f64::from(c[0]);
        max = max.max(f64::from(c[0]));
        if c[0] > 0.0 {
            constant &= *first.get_or_insert(c[0]) == c[0];
        }
        if let Some(count) = on_path.get_mut(c[1].round() as usize) {
            *count += 1;
        }
    }
    if n == 0 {
        return None;
    }
    let n = n as f64;
    let paths = on_path
        .iter()
        .enumerate()
        .map(|(k, &on)| (spec.path_name(k as f32), 100.0 * on as f64 / n))
        .collect();
    Some(CostRow {
        unit: spec.unit.to_string(),
        mean: sum / n,
        max,
        constant,
        paths,
        image: cost_file(&r.label()),
    })
}

fn row(r: &MethodResult, mask: &[bool]) -> MethodRow {
    let label = r.label();
    let (image, visibility, heatmap) = files(r.method, &label);
    MethodRow {
        method: label.clone(),
        history_frames: r.history,
        class_mismatch_pct: r.metrics.class_mismatch_pct,
        mae: r.metrics.mae,
        penumbra_mae: r.metrics.penumbra_mae,
        p99: r.metrics.p99,
        penumbra_pixels: r.metrics.penumbra_pixels,
        gpu_ms: r.gpu_ms,
        cpu_ms: r.cpu_ms,
        wall_ms: r.wall_ms,
        image,
        visibility,
        heatmap,
        hard: r.hard.map(|h| HardRow {
            mismatch_pct: h.mismatch_pct,
            edge_px: h.edge_px,
            interior_px: h.interior_px,
            false_shadow_px: h.false_shadow_px,
            missed_shadow_px: h.missed_shadow_px,
            image: hard_file(&label),
        }),
        flip_mean: r.flip_mean,
        flip: flip_file(&label),
        cost: cost_row(r, mask),
        temporal_error: None,
        popping: None,
        popping_px: None,
        temporal_plot: None,
        invalid_px: r.frame.out_of_range_pixels(),
    }
}

/// Write every file of `c` into `dir` (created if missing), all or nothing, with the run in
/// motion's (its plots and the APNG) if there is one; returns their paths.
pub fn write(
    dir: &Path,
    c: &Comparison,
    motion: Option<&Motion>,
) -> Result<Vec<PathBuf>, OutputError> {
    let outline = c.outline();
    let size = (c.request.width, c.request.height);
    let mut writer = Writer::new(dir, size, &outline.drawn)?;
    let against = c.against();
    for (i, r) in c.results.iter().enumerate() {
        writer.method(i, &against, r)?;
    }
    writer.finish(&outline, motion).map(|(_, files)| files)
}

/// A comparison's files written as its methods finish ([`super::run_each`]): each method's
/// image, visibility EXR and heatmaps streamed into the output's hidden folder, its row of the
/// report and its tile of the montage kept; [`Writer::finish`] adds the montage and the reports
/// and moves everything into place, all or nothing. What it holds between methods is the
/// montage page (its size is the layout's, not the images') and the rows.
pub struct Writer {
    staged: Staged,
    page: montage::Page,
    rows: Vec<(usize, MethodRow)>,
}

impl Writer {
    /// Start writing a comparison of `drawn` (its [`Plan`](super::Plan)'s, the report's order)
    /// at `width`×`height` into `dir`, checked and prepared now.
    pub fn new(dir: &Path, (w, h): (u32, u32), drawn: &[Method]) -> Result<Writer, OutputError> {
        Ok(Writer {
            staged: Staged::new(dir)?,
            page: montage::Page::new(montage::Layout::planned(w, h, drawn)),
            rows: Vec::new(),
        })
    }

    /// A folder for work kept on disk until the files are committed (`compare --orbit`'s),
    /// removed with the writer's hidden folder.
    pub fn scratch(&self) -> Option<&Path> {
        self.staged.scratch_dir()
    }

    /// Write `r`'s files, measured `against` its yardsticks, as tile `tile` of the report.
    pub fn method(
        &mut self,
        tile: usize,
        against: &Against<'_>,
        r: &MethodResult,
    ) -> Result<(), OutputError> {
        let (w, h) = (r.frame.width, r.frame.height);
        let width = w as usize;
        let label = r.label();
        let (image, visibility, heat) = files(r.method, &label);
        let color = &r.frame.color;
        self.staged.write_with(&image, |out, target| {
            output::png_file(out, target, w, h, |y, row| {
                for (px, c) in row.chunks_exact_mut(3).zip(&color[y * width..]) {
                    px.copy_from_slice(&c[..3]);
                }
            })
        })?;
        let frame = &r.frame;
        self.staged.write_with(&visibility, |out, target| {
            output::exr_file(out, target, w, h, |x, y| {
                let i = y * width + x;
                let v = frame.visibility.get(i).copied().unwrap_or(0.0);
                [v, v, v, if frame.hit(i) { 1.0 } else { 0.0 }]
            })
        })?;
        if let (Some(exact), Some(_)) = (against.exact, &r.hard) {
            let img = heatmap::hard_mismatch(exact, &frame.visibility, against.mask, color, w, h);
            self.stage_image(&hard_file(&label), &img)?;
        }
        self.stage_image(&flip_file(&label), &heatmap::flip(&r.flip, w, h))?;
        if !frame.cost.is_empty() {
            let max = frame
                .cost
                .iter()
                .zip(against.mask)
                .filter(|(_, &m)| m)
                .map(|(c, _)| c[0])
                .fold(0.0f32, f32::max);
            let img = heatmap::cost(&frame.cost, against.mask, w, h, max);
            self.stage_image(&cost_file(&label), &img)?;
        }
        if let Some(heat) = heat {
            let img = heatmap::render(against.reference, &frame.visibility, against.mask, w, h);
            self.stage_image(&heat, &img)?;
        }
        self.page.tile(tile as u32, r, against);
        self.rows.push((tile, row(r, against.mask)));
        Ok(())
    }

    fn stage_image(&mut self, name: &str, img: &image::RgbImage) -> Result<(), OutputError> {
        self.staged
            .write_with(name, |out, target| output::png_image(out, target, img))
    }

    /// Add the run in motion's files (if any), the montage and the reports, and move every
    /// file into place; returns the report and the files' paths.
    pub fn finish(
        mut self,
        outline: &Outline,
        motion: Option<&Motion>,
    ) -> Result<(Report, Vec<PathBuf>), OutputError> {
        self.rows.sort_by_key(|(tile, _)| *tile);
        let mut report = Report::of(outline, self.rows.into_iter().map(|(_, r)| r).collect());
        let encode = |name: &str, e: String| OutputError::Encode {
            path: PathBuf::from(name),
            error: image::ImageError::IoError(io::Error::other(e)),
        };
        if let Some(motion) = motion {
            report.add_motion(motion);
            for m in &motion.methods {
                let name = temporal::plot_file(m.method);
                let png = temporal::plot_png(motion, m, 720, 360).map_err(|e| encode(&name, e))?;
                self.staged.add(&name, &png)?;
            }
            if let Some(worst) = motion.worst() {
                self.staged
                    .write_with(temporal::MOTION_APNG, |out, target| {
                        motion
                            .write_apng(worst, out)
                            .map_err(|e| encode_error(target, e))
                    })?;
            }
        }
        let page = montage::encode(&self.page.finish())
            .map_err(|e| encode(montage::MONTAGE_PNG, e.to_string()))?;
        self.staged.add(montage::MONTAGE_PNG, &page)?;
        self.staged.add(REPORT_MD, report.markdown().as_bytes())?;
        let json = serde_json::to_string_pretty(&report).map_err(|error| OutputError::Json {
            path: PathBuf::from(REPORT_JSON),
            error,
        })?;
        self.staged.add(REPORT_JSON, json.as_bytes())?;
        Ok((report, self.staged.commit()?))
    }
}

fn encode_error(target: &Path, message: String) -> OutputError {
    OutputError::Encode {
        path: target.to_path_buf(),
        error: image::ImageError::IoError(io::Error::other(message)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A report as written before `invalid_px`: two method rows without it.
    const OLDER: &str = r#"{
        "scene": "s", "adapter": "a", "width": 4, "height": 4, "dbuffer_size": 64,
        "vt": "exact", "samples": 8, "reference_rays_per_s": 1.0, "pixels": 16,
        "methods": [
            {"method": "reference", "class_mismatch_pct": 0.0, "mae": 0.0,
             "penumbra_mae": 0.0, "p99": 0.0, "penumbra_pixels": 2, "gpu_ms": null,
             "cpu_ms": 1.0, "wall_ms": 1.0, "image": "reference.png",
             "visibility": "reference.exr", "heatmap": null},
            {"method": "pcss", "class_mismatch_pct": 1.0, "mae": 0.1,
             "penumbra_mae": 0.2, "p99": 0.3, "penumbra_pixels": 2, "gpu_ms": 0.5,
             "cpu_ms": 0.0, "wall_ms": 1.0, "image": "pcss.png",
             "visibility": "pcss.exr", "heatmap": "pcss-error.png"}
        ]
    }"#;

    #[test]
    fn older_reports_read_no_invalid_pixels_and_the_table_names_only_methods_with_some() {
        let mut r: Report = serde_json::from_str(OLDER).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            r.methods.iter().map(|m| m.invalid_px).collect::<Vec<_>>(),
            [0, 0]
        );
        assert!(r.invalid_line().is_empty());
        assert!(!r.table().contains("out of range"));
        r.methods[1].invalid_px = 3;
        let line = r.invalid_line();
        assert!(
            line.contains("pcss 3 px") && !line.contains("reference"),
            "{line}"
        );
        assert!(r.table().ends_with(&line) && r.markdown().contains(&line));
        let json = serde_json::to_string(&r).unwrap_or_else(|e| panic!("{e}"));
        assert!(json.contains("\"invalid_px\":3"), "{json}");
    }
}
