//! The files of `dbuffer compare`: per method its image, its visibility EXR and its error
//! heatmap, then `montage.png` (every method on one page), `report.md` and `report.json` with the
//! metrics and timings (the same table is printed to stdout).

use std::io;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

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
            methods: c.results.iter().map(row).collect(),
            not_applicable: c
                .not_applicable
                .iter()
                .map(|(m, needs, why)| NotApplicable {
                    method: m.name().to_string(),
                    needs: needs.clone(),
                    reason: why.clone(),
                })
                .collect(),
        }
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
            "\nClass mismatch: pixels whose class (lit V ≥ 0.996, umbra V ≤ 0.004, penumbra \
             otherwise) differs from the reference's. MAE and p99 of |V − V_ref| over the pixels \
             that count; penumbra MAE over the reference's penumbra. GPU ms: the method's own \
             passes; CPU ms: its per-frame CPU work (geometry for the D-buffer methods, ray \
             casting for the reference).\n",
        );
        s
    }

    /// The table alone (also printed to stdout).
    pub fn table(&self) -> String {
        let mut s = String::from(
            "| method | class mismatch % | MAE | penumbra MAE | p99 \\|ΔV\\| | GPU ms | CPU ms | heatmap |\n\
             |---|---:|---:|---:|---:|---:|---:|---|\n",
        );
        for m in &self.methods {
            let gpu = m.gpu_ms.map_or("n/a".to_string(), |g| format!("{g:.2}"));
            let heat = m
                .heatmap
                .as_ref()
                .map_or("—".to_string(), |h| format!("[{h}]({h})"));
            s.push_str(&format!(
                "| {} | {:.2} | {:.4} | {:.4} | {:.3} | {} | {:.2} | {} |\n",
                m.method, m.class_mismatch_pct, m.mae, m.penumbra_mae, m.p99, gpu, m.cpu_ms, heat
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
                "| {} | n/a — needs {needs} | | | | | | |\n",
                n.method
            ));
        }
        s
    }
}

impl Report {
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

fn row(r: &MethodResult) -> MethodRow {
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
    }
}

/// Write every file into `dir` (created if missing), each atomically; returns their paths.
pub fn write(dir: &Path, c: &Comparison) -> io::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)?;
    let report = Report::new(c);
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
        if let Some(heat) = heat {
            let img = heatmap::render(reference, &r.frame.visibility, &c.mask, w, h);
            let (iw, ih) = img.dimensions();
            put(
                &heat,
                output::png_rgb8(iw, ih, img.as_raw()).map_err(encode)?,
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
