//! The bench report as markdown: Table 1, the competition as ratios to the D-buffer, frame
//! coherence, geometry scaling and the targets (what `bench.md` holds and the CLI prints).

use std::fmt::Write;

use super::{FrameSource, Report, Stat, Timing};
use crate::render::Method;

/// How a column's cells line up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    Left,
    Right,
}

/// A Markdown table written into a report row by row: a header, the rule under it, then rows,
/// each `| a | b |` with an empty cell as `| |`. Every table of the bench report is one, so they
/// all have one shape.
pub struct Table<'a> {
    out: &'a mut String,
}

impl<'a> Table<'a> {
    /// Start a table in `out` with these columns: its header and rule.
    pub fn new<S: AsRef<str>>(out: &'a mut String, columns: &[(S, Align)]) -> Table<'a> {
        let mut t = Table { out };
        t.row(columns.iter().map(|(c, _)| c.as_ref()));
        t.out.push('|');
        for (_, align) in columns {
            t.out.push_str(match align {
                Align::Left => "---|",
                Align::Right => "---:|",
            });
        }
        t.out.push('\n');
        t
    }

    /// One row of cells.
    pub fn row<S: AsRef<str>>(&mut self, cells: impl IntoIterator<Item = S>) {
        self.out.push('|');
        for cell in cells {
            let cell = cell.as_ref();
            if !cell.is_empty() {
                self.out.push(' ');
                self.out.push_str(cell);
            }
            self.out.push_str(" |");
        }
        self.out.push('\n');
    }
}

/// A column headed `name` whose cells line up left (names) or right (numbers).
fn left(name: impl Into<String>) -> (String, Align) {
    (name.into(), Align::Left)
}

fn right(name: impl Into<String>) -> (String, Align) {
    (name.into(), Align::Right)
}

fn ms(v: f64) -> String {
    if v < 1.0 {
        format!("{v:.3}")
    } else if v < 100.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.0}")
    }
}

fn ms_opt(s: Option<Stat>) -> String {
    s.map_or_else(|| "–".into(), |s| ms(s.median))
}

fn thousands(n: usize) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// How [`Method::refuses_on`](crate::render::Method::refuses_on) says the adapter lacks something.
const ADAPTER_LACKS: &str = "which the adapter";

/// Short reason for a method that did not render.
fn na(error: &Option<String>) -> String {
    match error {
        Some(e) if e.contains("not available") => "n/a (not implemented)".into(),
        Some(e) if e.contains(ADAPTER_LACKS) => "n/a (the adapter lacks what it needs)".into(),
        Some(_) => "n/a (error)".into(),
        None => "n/a".into(),
    }
}

fn source_note(t: &Timing) -> &'static str {
    match t.frame_source {
        FrameSource::GpuTimestamps => "",
        FrameSource::FencedWall => " (wall)",
    }
}

/// The whole report.
pub fn markdown(r: &Report) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Adapter **{}** ({}, {}), host {}; GPU timestamps: {}. D-buffer and shadow maps {}², \
         {} warm-up then median of {} frames{}; run took {:.0} s.\n",
        r.adapter,
        r.backend,
        r.device_type,
        r.host,
        if r.timestamps {
            "yes"
        } else {
            "no (fenced wall time instead)"
        },
        r.dbuffer_size,
        r.warmup,
        r.frames,
        if r.quick { " (--quick)" } else { "" },
        r.seconds
    );
    table1(&mut out, r);
    display(&mut out, r);
    competition(&mut out, r);
    hard_methods(&mut out, r);
    against_dbuffer_and_hard(&mut out, r);
    work_per_pixel(&mut out, r);
    coherence(&mut out, r);
    scaling(&mut out, r);
    targets(&mut out, r);
    out
}

fn table1(out: &mut String, r: &Report) {
    let _ = writeln!(out, "### Table 1 (Jakobsen et al. 2004), D-buffer\n");
    let mut t = Table::new(
        out,
        &[
            left("scene"),
            right("caster tris"),
            right("size"),
            right("geometry ms (CPU)"),
            right("light pass ms (GPU)"),
            right("camera pass ms (GPU)"),
            right("frame ms"),
            right("fps"),
            right("fps, geometry every frame"),
            right("wall ms (incl. readback)"),
        ],
    );
    for s in &r.scenes {
        for size in r.sizes() {
            let Some(run) = r.run(&s.name, size, Method::DBUFFER) else {
                continue;
            };
            let geo = s.geometry_ms.median;
            match &run.timing {
                Some(timing) => {
                    let frame = timing.frame_ms.median;
                    t.row([
                        format!("`{}`", s.name),
                        thousands(s.caster_triangles),
                        format!("{size}²"),
                        ms(geo),
                        ms_opt(timing.light_ms),
                        ms_opt(timing.pass("camera_pass")),
                        format!("{}{}", ms(frame), source_note(timing)),
                        format!("{:.0}", timing.fps),
                        format!("{:.0}", 1e3 / (frame + geo)),
                        ms(timing.wall_ms.median),
                    ]);
                }
                None => {
                    let mut cells = vec![
                        format!("`{}`", s.name),
                        thousands(s.caster_triangles),
                        format!("{size}²"),
                        ms(geo),
                        na(&run.error),
                    ];
                    cells.resize(10, String::new());
                    t.row(cells);
                }
            }
        }
    }
    let _ = writeln!(
        out,
        "\n*light pass* = the D-buffer's light-space passes (the centre's shadow map and the volume \
         channels), made again every timed frame; *frame* = the sum of the GPU passes with the geometry \
         cached; *fps* = 1000 / frame; *fps, geometry every frame* adds the CPU geometry stage (a light \
         that moves every frame); *wall* is `Session::frame` end to end, including the readback of the \
         camera targets.\n"
    );
}

fn display(out: &mut String, r: &Report) {
    if r.display.is_empty() {
        return;
    }
    let _ = writeln!(out, "### The lab's display path (D-buffer)\n");
    let mut t = Table::new(
        out,
        &[
            left("scene"),
            right("size"),
            right("floor GPU ms"),
            right("lab frame, light still: wall (GPU)"),
            right("light moving: wall (GPU)"),
            right("fps, light moving"),
            right("readback path: wall (GPU)"),
            right("lab / readback"),
            right("D-buffer frame / floor"),
        ],
    );
    for d in &r.display {
        let frame = r
            .timing(&d.scene, d.size, Method::DBUFFER)
            .and_then(|t| t.gpu_total_ms);
        let over_floor = match (frame, d.floor_gpu_ms) {
            (Some(f), Some(fl)) if fl.median > 0.0 => format!("{:.2}×", f.median / fl.median),
            _ => "–".into(),
        };
        let pair = |x: &super::Display| format!("{} ({})", ms(x.wall_ms.median), ms_opt(x.gpu_ms));
        let fps = if d.lab_moving.wall_ms.median > 0.0 {
            format!("{:.0}", 1e3 / d.lab_moving.wall_ms.median)
        } else {
            "–".into()
        };
        let ratio = if d.readback.wall_ms.median > 0.0 {
            format!(
                "{:.2}×",
                d.lab_still.wall_ms.median / d.readback.wall_ms.median
            )
        } else {
            "–".into()
        };
        t.row([
            format!("`{}`", d.scene),
            format!("{}²", d.size),
            ms_opt(d.floor_gpu_ms),
            pair(&d.lab_still),
            pair(&d.lab_moving),
            fps,
            pair(&d.readback),
            ratio,
            over_floor,
        ]);
    }
    let _ = writeln!(
        out,
        "\n*lab frame*: what the window does per frame, headless — the camera pass and the view pass (which \
         makes every view opaque, the final image included, so the window paints nothing under it), one submit, fenced; with a still light the D-buffer is cached, with a moving \
         one the geometry stage and the light pass run too. *readback path*: `Session::frame` as \
         `dbuffer render` calls it (camera targets and D-buffer read back), which is what the lab did every \
         frame before. *floor*: the scene in flat colour into Rgba8 + depth, the cheapest image of it.\n"
    );
}

fn competition(out: &mut String, r: &Report) {
    let sizes = r.sizes();
    let _ = writeln!(
        out,
        "### The competition: frame ms (ratio to the D-buffer), median over the scenes\n"
    );
    let mut columns = vec![left("method")];
    columns.extend(sizes.iter().map(|s| right(format!("{s}²"))));
    columns.push(right(format!(
        "camera pass ms at {}²",
        sizes.last().unwrap_or(&0)
    )));
    let mut t = Table::new(out, &columns);
    for (label, method) in r.labels() {
        let Ok(method) = method.parse::<Method>() else {
            continue;
        };
        let mut row = vec![label.clone()];
        for &size in &sizes {
            let cells: Vec<(f64, f64, bool)> = r
                .scenes
                .iter()
                .filter_map(|s| {
                    let run = r
                        .runs
                        .iter()
                        .find(|x| x.scene == s.name && x.size == size && x.label == label)?;
                    let t = run.timing.as_ref()?;
                    let ratio = r.ratio_to_dbuffer(&s.name, size, method)?;
                    Some((
                        t.frame_ms.median,
                        ratio,
                        t.frame_source == FrameSource::FencedWall,
                    ))
                })
                .collect();
            if cells.is_empty() {
                let err = r
                    .runs
                    .iter()
                    .find(|x| x.size == size && x.label == label)
                    .and_then(|x| x.error.clone());
                row.push(na(&err));
                continue;
            }
            let frame = median(cells.iter().map(|c| c.0).collect());
            let ratio = median(cells.iter().map(|c| c.1).collect());
            let wall = if cells.iter().any(|c| c.2) {
                " wall"
            } else {
                ""
            };
            row.push(format!("{}{wall} ({ratio:.2}×)", ms(frame)));
        }
        let last = sizes.last().copied().unwrap_or(0);
        let cams: Vec<f64> = r
            .scenes
            .iter()
            .filter_map(|s| {
                let run = r
                    .runs
                    .iter()
                    .find(|x| x.scene == s.name && x.size == last && x.label == label)?;
                Some(run.timing.as_ref()?.pass("camera_pass")?.median)
            })
            .collect();
        row.push(if cams.is_empty() {
            "–".into()
        } else {
            ms(median(cams))
        });
        t.row(row);
    }
    let _ = writeln!(
        out,
        "\nRatios are per scene and size, then the median over the scenes. *wall*: the method works on \
         the CPU (the reference casts its rays there), so its frame and the D-buffer's are compared by \
         wall time including readback."
    );
    if let Some(rps) = r.reference_rays_per_s {
        let _ = writeln!(
            out,
            "Reference throughput: {:.1} M shadow rays/s (median over the runs; one ray per hit pixel per 1-spp step of `Session::advance_reference`, the ray casting alone, on the CPU).",
            rps / 1e6
        );
    }
    let _ = writeln!(out);
}

/// The methods that use the light's centre as a point light: frame as a ratio to the hard shadow
/// map and to the D-buffer (medians over the scenes), and the stencil methods' fill per scene.
fn hard_methods(out: &mut String, r: &Report) {
    let sizes = r.sizes();
    let hard: Vec<(String, Method)> = r
        .labels()
        .into_iter()
        .filter_map(|(l, m)| Some((l, m.parse::<Method>().ok()?)))
        .filter(|(_, m)| m.is_hard() && *m != Method::HARD)
        .collect();
    if hard.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "### Hard-shadow techniques: frame ms (× hard shadow map, × D-buffer), median over the scenes\n"
    );
    let mut columns = vec![left("method")];
    columns.extend(sizes.iter().map(|s| right(format!("{s}²"))));
    let mut t = Table::new(out, &columns);
    for (label, method) in &hard {
        let mut row = vec![label.clone()];
        for &size in &sizes {
            let cells: Vec<(f64, f64, f64)> = r
                .scenes
                .iter()
                .filter_map(|s| {
                    let t = r.timing(&s.name, size, *method)?;
                    Some((
                        t.frame_ms.median,
                        r.ratio_to(&s.name, size, *method, Method::HARD)?,
                        r.ratio_to(&s.name, size, *method, Method::DBUFFER)?,
                    ))
                })
                .collect();
            if cells.is_empty() {
                row.push("n/a".into());
                continue;
            }
            row.push(format!(
                "{} ({:.2}× hard, {:.2}× D)",
                ms(median(cells.iter().map(|c| c.0).collect())),
                median(cells.iter().map(|c| c.1).collect()),
                median(cells.iter().map(|c| c.2).collect())
            ));
        }
        t.row(row);
    }
    let filled: Vec<&(String, Method)> = hard
        .iter()
        .filter(|(l, _)| r.runs.iter().any(|x| x.label == *l && x.fill.is_some()))
        .collect();
    if !filled.is_empty() {
        let last = sizes.last().copied().unwrap_or(0);
        let _ = writeln!(
            out,
            "\nStencil fill at {last}²: volume fragments per pixel (every volume triangle over its \
             whole footprint, no test; what the stencil methods pay in fill rate)\n"
        );
        let mut columns = vec![left("scene")];
        columns.extend(filled.iter().map(|(label, _)| right(label.as_str())));
        let mut t = Table::new(out, &columns);
        for s in &r.scenes {
            let mut row = vec![format!("`{}`", s.name)];
            for (label, _) in &filled {
                let fill = r
                    .runs
                    .iter()
                    .find(|x| x.scene == s.name && x.size == last && x.label == *label)
                    .and_then(|x| x.fill);
                row.push(fill.map_or_else(|| "–".into(), |f| format!("{f:.2}")));
            }
            t.row(row);
        }
    }
    let _ = writeln!(out);
}

/// What each method's cost view counted per pixel at the largest size (its own unit: taps,
/// listed edges, the BVH nodes its rays visited…), the median over the scenes.
fn work_per_pixel(out: &mut String, r: &Report) {
    let Some(&size) = r.sizes().last() else {
        return;
    };
    let rows: Vec<(String, String, f64)> = r
        .labels()
        .into_iter()
        .filter_map(|(label, method)| {
            let cells: Vec<f64> = r
                .runs
                .iter()
                .filter(|x| x.label == label && x.size == size)
                .filter_map(|x| x.work)
                .collect();
            let unit = method.parse::<Method>().ok()?.spec().cost.unit.to_string();
            (!cells.is_empty()).then(|| (label, unit, median(cells)))
        })
        .collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "### Work per pixel at {size}²: what each method's cost view counts, median over the scenes
"
    );
    let mut t = Table::new(out, &[left("method"), right("per pixel"), left("unit")]);
    for (label, unit, work) in rows {
        t.row(vec![label, format!("{work:.1}"), unit]);
    }
    let _ = writeln!(out);
}

/// Every method's frame at the largest size as a ratio to the D-buffer's and to the hard shadow
/// map's (the two yardsticks of a soft-shadow method's cost), median over the scenes.
fn against_dbuffer_and_hard(out: &mut String, r: &Report) {
    let Some(&size) = r.sizes().last() else {
        return;
    };
    let _ = writeln!(
        out,
        "### Every method at {size}²: frame as a ratio to the D-buffer and to the hard shadow \
         map\n"
    );
    let mut t = Table::new(
        out,
        &[
            left("method"),
            right("frame ms"),
            right("× dbuffer"),
            right("× hard"),
        ],
    );
    for (label, method) in r.labels() {
        let Ok(method) = method.parse::<Method>() else {
            continue;
        };
        // Per scene: the frame, and its ratios to the D-buffer and to the hard shadow map.
        let mut frames = Vec::new();
        let (mut to_dbuffer, mut to_hard) = (Vec::new(), Vec::new());
        for s in &r.scenes {
            let Some(t) = r
                .runs
                .iter()
                .find(|x| x.scene == s.name && x.size == size && x.label == label)
                .and_then(|run| run.timing.as_ref())
            else {
                continue;
            };
            frames.push(t.frame_ms.median);
            to_dbuffer.extend(r.ratio_to(&s.name, size, method, Method::DBUFFER));
            to_hard.extend(r.ratio_to(&s.name, size, method, Method::HARD));
        }
        if frames.is_empty() {
            let err = r
                .runs
                .iter()
                .find(|x| x.size == size && x.label == label)
                .and_then(|x| x.error.clone());
            t.row([label, na(&err), String::new(), String::new()]);
            continue;
        }
        let ratio = |v: Vec<f64>| {
            if v.is_empty() {
                "–".to_string()
            } else {
                format!("{:.2}×", median(v))
            }
        };
        t.row([label, ms(median(frames)), ratio(to_dbuffer), ratio(to_hard)]);
    }
    let _ = writeln!(
        out,
        "\nA method that cannot take a scene's light (`linear-ssm` needs a line) is timed on the same \
         scene with the light converted, its label saying which (a disk's diameter as a segment: the \
         same casters, the same extent); ratios are per scene, then the median over the scenes.\n"
    );
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn coherence(out: &mut String, r: &Report) {
    let Some(c) = &r.coherence else {
        return;
    };
    let _ = writeln!(
        out,
        "### Frame coherence (Jakobsen et al. 2004, §6.1): `{}` at {}², D-buffer\n",
        c.scene, c.size
    );
    let mut t = Table::new(
        out,
        &[
            left("steady frame"),
            right("wall ms (median / min)"),
            right("GPU passes ms"),
            right("geometry ms (CPU)"),
            right("geometry builds"),
        ],
    );
    t.row([
        "geometry cached".to_string(),
        format!(
            "{} / {}",
            ms(c.cached_wall_ms.median),
            ms(c.cached_wall_ms.min)
        ),
        ms_opt(c.cached_gpu_ms),
        "0".into(),
        "0".into(),
    ]);
    t.row([
        "geometry rebuilt every frame".to_string(),
        format!(
            "{} / {}",
            ms(c.rebuilt_wall_ms.median),
            ms(c.rebuilt_wall_ms.min)
        ),
        ms_opt(c.rebuilt_gpu_ms),
        ms_opt(c.rebuilt_geometry_ms),
        format!("{} in {} frames", c.rebuilds, c.frames),
    ]);
    let _ = writeln!(
        out,
        "\nRebuilt by: {}; cached and rebuilt frames alternate. A rebuilt frame adds the geometry \
         stage, the upload of the new volumes and the light view's fit.\n",
        c.rebuild_by
    );
}

fn scaling(out: &mut String, r: &Report) {
    if r.scaling.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "### Geometry scaling (CPU): UV spheres under a tilted light\n"
    );
    let mut t = Table::new(
        out,
        &[
            right("caster triangles"),
            right("per light move ms (median / min)"),
            right("volume triangles"),
            right("adjacency ms (once per mesh)"),
            right("move to drawable, CPU path + upload ms"),
            right("move to drawable, GPU path ms"),
        ],
    );
    for p in &r.scaling {
        t.row([
            thousands(p.triangles),
            format!("{} / {}", ms(p.build_ms.median), ms(p.build_ms.min)),
            thousands(p.volume_triangles),
            ms(p.prepare_ms),
            ms_opt(p.cpu_move_ms),
            ms_opt(p.gpu_move_ms),
        ]);
    }
    let _ = writeln!(out);
}

fn targets(out: &mut String, r: &Report) {
    let _ = writeln!(out, "### Targets\n");
    let mut table = Table::new(
        out,
        &[
            left("target"),
            right("measured"),
            right("limit"),
            left("result"),
            left("where"),
        ],
    );
    for t in &r.targets {
        let (measured, result) = match (t.measured, t.pass()) {
            (Some(m), Some(true)) => (format!("{m:.3} {}", t.unit), "PASS"),
            (Some(m), Some(false)) => (format!("{m:.3} {}", t.unit), "MISS"),
            (Some(m), None) => (format!("{m:.3} {}", t.unit), "(reported)"),
            (None, _) => ("–".into(), "n/a"),
        };
        let op = if t.at_least {
            "≥"
        } else if t.strict {
            "<"
        } else {
            "≤"
        };
        let limit = t
            .limit
            .map_or_else(|| "–".to_string(), |l| format!("{op} {l} {}", t.unit));
        table.row([
            t.name.clone(),
            measured,
            limit,
            result.into(),
            t.detail.clone(),
        ]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::{targets, Display, DisplayRun, PassTime, Run, SceneInfo};

    fn st(v: f64) -> Stat {
        Stat { median: v, min: v }
    }

    fn timing(gpu: f64, wall: f64, camera: f64, source: FrameSource) -> Timing {
        let frame = if source == FrameSource::FencedWall {
            wall
        } else {
            gpu
        };
        Timing {
            frame_ms: st(frame),
            frame_source: source,
            fps: 1e3 / frame,
            passes: vec![
                PassTime {
                    pass: "shadow_map".into(),
                    ms: st(gpu - camera),
                },
                PassTime {
                    pass: "camera_pass".into(),
                    ms: st(camera),
                },
            ],
            gpu_total_ms: Some(st(gpu)),
            light_ms: Some(st(gpu - camera)),
            wall_ms: st(wall),
            hit_pixels: 10,
            rays_ms: None,
            frames: 1,
        }
    }

    fn run(method: &str, timing: Option<Timing>) -> Run {
        let m: Method = method.parse().unwrap();
        Run {
            scene: "table1-5760".into(),
            size: 1024,
            label: crate::bench::Case::for_method(m).label,
            method: method.into(),
            error: timing
                .is_none()
                .then(|| "the pcf method is not available yet".into()),
            timing,
            fill: (method == "shadow-volume").then_some(2.5),
            work: Some(12.0),
        }
    }

    fn report() -> Report {
        let gpu = FrameSource::GpuTimestamps;
        let mut r = Report {
            adapter: "test adapter".into(),
            backend: "Vulkan".into(),
            device_type: "Cpu".into(),
            timestamps: true,
            host: "test".into(),
            quick: true,
            warmup: 1,
            frames: 3,
            dbuffer_size: 1024,
            unix_time: 0,
            seconds: 1.0,
            scenes: vec![SceneInfo {
                name: "table1-5760".into(),
                caster_triangles: 5760,
                prepare_ms: 0.7,
                geometry_ms: Stat {
                    median: 0.25,
                    min: 0.2,
                },
                umbra_triangles: 1,
                penumbra_triangles: 1,
            }],
            runs: vec![
                run("dbuffer", Some(timing(20.0, 50.0, 8.0, gpu))),
                run("hard", Some(timing(10.0, 40.0, 4.0, gpu))),
                run("pcf", None),
                run("pcss", Some(timing(30.0, 60.0, 16.0, gpu))),
                run(
                    "reference",
                    Some(timing(20.0, 100.0, 8.0, FrameSource::FencedWall)),
                ),
                run("shadow-volume", Some(timing(15.0, 45.0, 4.0, gpu))),
                run("dbuffer-fused", Some(timing(40.0, 70.0, 8.0, gpu))),
                run("wedges", Some(timing(30.0, 60.0, 4.0, gpu))),
            ],
            display: vec![DisplayRun {
                scene: "table1-5760".into(),
                size: 1024,
                floor_gpu_ms: Some(st(5.0)),
                lab_still: Display {
                    wall_ms: st(12.0),
                    gpu_ms: Some(st(11.0)),
                },
                lab_moving: Display {
                    wall_ms: st(25.0),
                    gpu_ms: Some(st(22.0)),
                },
                readback: Display {
                    wall_ms: st(30.0),
                    gpu_ms: Some(st(11.0)),
                },
            }],
            coherence: None,
            scaling: vec![],
            reference_rays_per_s: None,
            targets: vec![],
        };
        r.targets = targets(&r);
        r
    }

    #[test]
    fn ratios_compare_like_with_like() {
        let r = report();
        assert_eq!(
            r.ratio_to_dbuffer("table1-5760", 1024, Method::HARD),
            Some(0.5)
        );
        // The reference is measured by wall time, so it is compared with the D-buffer's wall.
        assert_eq!(
            r.ratio_to_dbuffer("table1-5760", 1024, crate::render::truth::SOFT),
            Some(2.0)
        );
        assert_eq!(
            r.ratio_to_dbuffer("table1-5760", 1024, "pcf".parse().unwrap()),
            None
        );
    }

    #[test]
    fn targets_pass_and_miss_honestly() {
        let r = report();
        let get = |name: &str| {
            r.targets
                .iter()
                .find(|t| t.name.starts_with(name))
                .unwrap_or_else(|| panic!("{name}: {:?}", r.targets))
        };
        // Reported, not targets: measured, neither passed nor missed.
        let lab = get("lab frame (light still)");
        assert_eq!(lab.measured, Some(0.4));
        assert_eq!(lab.pass(), None);
        let fps = get("lab frame fps");
        assert_eq!(fps.measured, None, "table1-960 at 600² was not run");
        let camera = get("D-buffer camera pass / hard");
        assert_eq!(camera.measured, Some(2.0));
        assert_eq!(camera.pass(), None);
        let light = get("D-buffer light pass / hard");
        assert_eq!(light.measured, Some(2.0));
        assert_eq!(light.pass(), Some(false), "2× misses ≤ 1.6×");
        let frame = get("D-buffer frame / hard-shadow frame (median)");
        assert_eq!(frame.measured, Some(2.0));
        assert_eq!(frame.pass(), Some(false), "2× misses ≤ 1.3×");
        let worst = get("D-buffer frame / hard-shadow frame (worst");
        assert_eq!(worst.measured, Some(2.0));
        assert_eq!(worst.pass(), Some(false), "2× misses ≤ 1.45×");
        let fused = get("dbuffer-fused frame / D-buffer");
        assert_eq!(fused.measured, Some(2.0));
        assert_eq!(fused.pass(), Some(true), "2× is within 2.5×");
        let fused_wedges = get("dbuffer-fused frame / wedges");
        assert!(fused_wedges
            .measured
            .is_some_and(|m| (m - 4.0 / 3.0).abs() < 1e-9));
        assert_eq!(fused_wedges.pass(), Some(false), "1.33× misses ≤ 1×");
        let pcss = get("D-buffer camera pass / PCSS");
        assert_eq!(pcss.measured, Some(0.5));
        assert_eq!(pcss.pass(), Some(true));
        let floor = get("D-buffer frame / floor");
        assert_eq!(floor.measured, Some(4.0));
        assert_eq!(floor.pass(), None, "reported, not a target");
        let geometry = get("geometry");
        assert_eq!(geometry.measured, Some(0.25));
        assert_eq!(geometry.pass(), Some(true));
    }

    #[test]
    fn markdown_has_every_table_and_row() {
        let md = markdown(&report());
        assert!(md.contains("test adapter"));
        assert!(
            md.contains("| `table1-5760` | 5,760 | 1024² | 0.250 | 12.0 | 8.0 | 20.0 | 50 |"),
            "{md}"
        );
        assert!(md.contains("| hard | 10.0 (0.50×) | 4.0 |"), "{md}");
        assert!(md.contains("| pcf | n/a (not implemented) | – |"), "{md}");
        assert!(
            md.contains("| reference 1 spp | 100 wall (2.00×) |"),
            "{md}"
        );
        assert!(md.contains("| `table1-5760` | 1024² | 5.0 | 12.0 (11.0) | 25.0 (22.0) | 40 | 30.0 (11.0) | 0.40× | 4.00× |"), "{md}");
        assert!(
            md.contains(
                "| D-buffer frame / hard-shadow frame (median) | 2.000 × | ≤ 1.3 × | MISS |"
            ),
            "{md}"
        );
        assert!(md.contains("(reported)"));
        assert!(
            md.contains("| shadow-volume | 15.0 (1.50× hard, 0.75× D) |"),
            "{md}"
        );
        assert!(md.contains("| scene | shadow-volume |"), "{md}");
        assert!(md.contains("| `table1-5760` | 2.50 |"), "{md}");
        assert!(md.contains("PASS"));
        assert_eq!(thousands(1_048_576), "1,048,576");
    }
}
