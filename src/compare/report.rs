//! The files of `dbuffer compare`: per method its image, its visibility EXR and its error
//! heatmap, then `montage.png` (every method on one page), `report.md` and `report.json` with the
//! metrics and timings (the same table is printed to stdout).

use std::io;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::temporal::{self, Motion};
use super::{heatmap, montage, Comparison, MethodResult};
use crate::fsutil::write_atomic;
use crate::output;
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
    pub method: String,
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
fn hard_file(method: Method) -> String {
    format!("{}-hard-error.png", method.name())
}

/// A method's FLIP map and cost heatmap.
fn flip_file(method: Method) -> String {
    format!("{}-flip.png", method.name())
}

fn cost_file(method: Method) -> String {
    format!("{}-cost.png", method.name())
}

fn files(method: Method) -> (String, String, Option<String>) {
    let n = method.name();
    (
        format!("{n}.png"),
        format!("{n}-visibility.exr"),
        (!method.is_reference()).then(|| format!("{n}-error.png")),
    )
}

impl Report {
    pub fn new(c: &Comparison) -> Report {
        Report {
            scene: c.scene.clone(),
            adapter: c.adapter.clone(),
            width: c.request.width,
            height: c.request.height,
            dbuffer_size: c.request.dbuffer_size,
            vt: c.request.vt.name().to_string(),
            samples: c.request.samples(),
            reference_rays_per_s: c.reference_rays_per_s,
            pixels: c.mask.iter().filter(|&&m| m).count(),
            methods: c.results.iter().map(|r| row(r, &c.mask)).collect(),
            not_applicable: c
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
        for row in &mut r.methods {
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
        r.motion = Some(MotionReport {
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
        r
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
             ({:.1} M rays/s), D-buffer {}², V(t) {}. Adapter: {}.\n\n",
            self.scene,
            self.width,
            self.height,
            self.pixels,
            self.samples,
            self.reference_rays_per_s / 1e6,
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
        s
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

/// A method's cost over the pixels that count.
fn cost_row(r: &MethodResult, mask: &[bool]) -> Option<CostRow> {
    let spec = r.method.spec().cost;
    let counted: Vec<[f32; 2]> = r
        .frame
        .cost
        .iter()
        .zip(mask)
        .filter(|(_, &m)| m)
        .map(|(c, _)| *c)
        .collect();
    if counted.is_empty() {
        return None;
    }
    let n = counted.len() as f64;
    let mean = counted.iter().map(|c| f64::from(c[0])).sum::<f64>() / n;
    let max = counted.iter().map(|c| f64::from(c[0])).fold(0.0, f64::max);
    let working: Vec<f32> = counted.iter().map(|c| c[0]).filter(|w| *w > 0.0).collect();
    let constant = working.windows(2).all(|w| w[0] == w[1]);
    let paths = (0..spec.paths.len())
        .map(|k| {
            let on = counted
                .iter()
                .filter(|c| c[1].round() as usize == k)
                .count();
            (spec.path_name(k as f32), 100.0 * on as f64 / n)
        })
        .collect();
    Some(CostRow {
        unit: spec.unit.to_string(),
        mean,
        max,
        constant,
        paths,
        image: cost_file(r.method),
    })
}

fn row(r: &MethodResult, mask: &[bool]) -> MethodRow {
    let (image, visibility, heatmap) = files(r.method);
    MethodRow {
        method: r.method.name().to_string(),
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
            image: hard_file(r.method),
        }),
        flip_mean: r.flip_mean,
        flip: flip_file(r.method),
        cost: cost_row(r, mask),
        temporal_error: None,
        popping: None,
        popping_px: None,
        temporal_plot: None,
    }
}

/// Write every file into `dir` (created if missing), each atomically, with the run in motion's
/// (its plots and the APNG) if there is one; returns their paths.
pub fn write(dir: &Path, c: &Comparison, motion: Option<&Motion>) -> io::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)?;
    let report = match motion {
        Some(m) => Report::with_motion(c, m),
        None => Report::new(c),
    };
    let (w, h) = (c.request.width, c.request.height);
    let reference = &c.reference().frame.visibility;
    let exact = c
        .results
        .iter()
        .find(|r| r.method == Method::REFERENCE_HARD)
        .map(|r| &r.frame.visibility);
    let mut written = Vec::new();
    let mut put = |name: &str, bytes: Vec<u8>| -> io::Result<()> {
        let path = dir.join(name);
        write_atomic(&path, &bytes)?;
        written.push(path);
        Ok(())
    };
    let encode = |e: image::ImageError| io::Error::other(e.to_string());
    for r in &c.results {
        let (image, visibility, heat) = files(r.method);
        let rgb: Vec<u8> = r
            .frame
            .color
            .iter()
            .flat_map(|c| [c[0], c[1], c[2]])
            .collect();
        put(&image, output::png_rgb8(w, h, &rgb).map_err(encode)?)?;
        let exr = output::exr_rgba32f(
            w,
            h,
            r.frame
                .visibility
                .iter()
                .enumerate()
                .map(|(i, &v)| [v, v, v, if r.frame.hit(i) { 1.0 } else { 0.0 }]),
        )
        .map_err(encode)?;
        put(&visibility, exr)?;
        if let (Some(exact), Some(_)) = (exact, &r.hard) {
            let img =
                heatmap::hard_mismatch(exact, &r.frame.visibility, &c.mask, &r.frame.color, w, h);
            put(
                &hard_file(r.method),
                output::png_rgb8(w, h, img.as_raw()).map_err(encode)?,
            )?;
        }
        let flip = heatmap::flip(&r.flip, w, h);
        put(
            &flip_file(r.method),
            output::png_rgb8(w, flip.height(), flip.as_raw()).map_err(encode)?,
        )?;
        if !r.frame.cost.is_empty() {
            let max = r
                .frame
                .cost
                .iter()
                .zip(&c.mask)
                .filter(|(_, &m)| m)
                .map(|(c, _)| c[0])
                .fold(0.0f32, f32::max);
            let img = heatmap::cost(&r.frame.cost, &c.mask, w, h, max);
            put(
                &cost_file(r.method),
                output::png_rgb8(w, img.height(), img.as_raw()).map_err(encode)?,
            )?;
        }
        if let Some(heat) = heat {
            let img = heatmap::render(reference, &r.frame.visibility, &c.mask, w, h);
            let (iw, ih) = img.dimensions();
            put(
                &heat,
                output::png_rgb8(iw, ih, img.as_raw()).map_err(encode)?,
            )?;
        }
    }
    if let Some(motion) = motion {
        for m in &motion.methods {
            let png = temporal::plot_png(motion, m, 720, 360).map_err(io::Error::other)?;
            put(&temporal::plot_file(m.method), png)?;
        }
        if let Some(worst) = motion.worst() {
            put(
                temporal::MOTION_APNG,
                motion.apng(worst, 8).map_err(io::Error::other)?,
            )?;
        }
    }
    put(
        montage::MONTAGE_PNG,
        montage::encode(&montage::render(c)).map_err(encode)?,
    )?;
    put(REPORT_MD, report.markdown().into_bytes())?;
    let json = serde_json::to_string_pretty(&report).map_err(io::Error::other)?;
    put(REPORT_JSON, json.into_bytes())?;
    Ok(written)
}
