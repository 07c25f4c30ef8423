//! The bench report as markdown: Table 1, the competition as ratios to the D-buffer, frame
//! coherence, geometry scaling and the targets (what `bench.md` holds and the CLI prints).

use std::fmt::Write;

use super::{FrameSource, Report, Stat, Timing};
use crate::render::Method;

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

/// Short reason for a method that did not render.
fn na(error: &Option<String>) -> String {
    match error {
        Some(e) if e.contains("not available") => "n/a (not implemented)".into(),
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
    competition(&mut out, r);
    coherence(&mut out, r);
    scaling(&mut out, r);
    targets(&mut out, r);
    out
}

fn table1(out: &mut String, r: &Report) {
    let _ = writeln!(out, "### Table 1 (seed 000), D-buffer\n");
    let _ = writeln!(
        out,
        "| scene | caster tris | size | geometry ms (CPU) | light pass ms (GPU) | camera pass ms (GPU) | frame ms | fps | fps, geometry every frame | wall ms (incl. readback) |"
    );
    let _ = writeln!(out, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for s in &r.scenes {
        for size in r.sizes() {
            let Some(run) = r.run(&s.name, size, Method::DBuffer) else {
                continue;
            };
            let geo = s.geometry_ms.median;
            match &run.timing {
                Some(t) => {
                    let frame = t.frame_ms.median;
                    let _ = writeln!(
                        out,
                        "| `{}` | {} | {size}² | {} | {} | {} | {}{} | {:.0} | {:.0} | {} |",
                        s.name,
                        thousands(s.caster_triangles),
                        ms(geo),
                        ms_opt(t.pass("light_pass")),
                        ms_opt(t.pass("camera_pass")),
                        ms(frame),
                        source_note(t),
                        t.fps,
                        1e3 / (frame + geo),
                        ms(t.wall_ms.median)
                    );
                }
                None => {
                    let _ = writeln!(
                        out,
                        "| `{}` | {} | {size}² | {} | {} | | | | | |",
                        s.name,
                        thousands(s.caster_triangles),
                        ms(geo),
                        na(&run.error)
                    );
                }
            }
        }
    }
    let _ = writeln!(
        out,
        "\n*frame* = the sum of the GPU passes (geometry cached, as in a steady view); *fps* = 1000 / frame; \
         *fps, geometry every frame* adds the CPU geometry stage (a light that moves every frame); \
         *wall* is `Session::frame` end to end, including the readback of the camera targets.\n"
    );
}

fn competition(out: &mut String, r: &Report) {
    let sizes = r.sizes();
    let _ = writeln!(
        out,
        "### The competition: frame ms (ratio to the D-buffer), median over the scenes\n"
    );
    let mut header = "| method |".to_string();
    let mut rule = "|---|".to_string();
    for s in &sizes {
        let _ = write!(header, " {s}² |");
        rule.push_str("---:|");
    }
    let _ = write!(
        header,
        " camera pass ms at {}² |",
        sizes.last().unwrap_or(&0)
    );
    rule.push_str("---:|");
    let _ = writeln!(out, "{header}\n{rule}");
    for (label, method) in r.labels() {
        let Ok(method) = method.parse::<Method>() else {
            continue;
        };
        let mut row = format!("| {label} |");
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
                let _ = write!(row, " {} |", na(&err));
                continue;
            }
            let frame = median(cells.iter().map(|c| c.0).collect());
            let ratio = median(cells.iter().map(|c| c.1).collect());
            let wall = if cells.iter().any(|c| c.2) {
                " wall"
            } else {
                ""
            };
            let _ = write!(row, " {}{wall} ({ratio:.2}×) |", ms(frame));
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
        if cams.is_empty() {
            row.push_str(" – |");
        } else {
            let _ = write!(row, " {} |", ms(median(cams)));
        }
        let _ = writeln!(out, "{row}");
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
        "### Frame coherence (seed 000 §6.1): `{}` at {}², D-buffer\n",
        c.scene, c.size
    );
    let _ = writeln!(
        out,
        "| steady frame | wall ms (median / min) | GPU passes ms | geometry ms (CPU) | geometry builds |"
    );
    let _ = writeln!(out, "|---|---:|---:|---:|---:|");
    let _ = writeln!(
        out,
        "| geometry cached | {} / {} | {} | 0 | 0 |",
        ms(c.cached_wall_ms.median),
        ms(c.cached_wall_ms.min),
        ms_opt(c.cached_gpu_ms)
    );
    let _ = writeln!(
        out,
        "| geometry rebuilt every frame | {} / {} | {} | {} | {} in {} frames |",
        ms(c.rebuilt_wall_ms.median),
        ms(c.rebuilt_wall_ms.min),
        ms_opt(c.rebuilt_gpu_ms),
        ms_opt(c.rebuilt_geometry_ms),
        c.rebuilds,
        c.frames
    );
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
    let _ = writeln!(
        out,
        "| caster triangles | per light move ms (median / min) | volume triangles | adjacency ms (once per mesh) |"
    );
    let _ = writeln!(out, "|---:|---:|---:|---:|");
    for p in &r.scaling {
        let _ = writeln!(
            out,
            "| {} | {} / {} | {} | {} |",
            thousands(p.triangles),
            ms(p.build_ms.median),
            ms(p.build_ms.min),
            thousands(p.volume_triangles),
            ms(p.prepare_ms)
        );
    }
    let _ = writeln!(out);
}

fn targets(out: &mut String, r: &Report) {
    let _ = writeln!(out, "### Targets\n");
    let _ = writeln!(out, "| target | measured | limit | result | where |");
    let _ = writeln!(out, "|---|---:|---:|---|---|");
    for t in &r.targets {
        let (measured, result) = match (t.measured, t.pass()) {
            (Some(m), Some(true)) => (format!("{m:.3} {}", t.unit), "PASS"),
            (Some(m), _) => (format!("{m:.3} {}", t.unit), "MISS"),
            (None, _) => ("–".into(), "n/a"),
        };
        let op = if t.strict { "<" } else { "≤" };
        let _ = writeln!(
            out,
            "| {} | {measured} | {op} {} {} | {result} | {} |",
            t.name, t.limit, t.unit, t.detail
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::{targets, PassTime, Run, SceneInfo};

    fn timing(gpu: f64, wall: f64, camera: f64, source: FrameSource) -> Timing {
        let s = |v: f64| Stat { median: v, min: v };
        let frame = if source == FrameSource::FencedWall {
            wall
        } else {
            gpu
        };
        Timing {
            frame_ms: s(frame),
            frame_source: source,
            fps: 1e3 / frame,
            passes: vec![
                PassTime {
                    pass: "light_pass".into(),
                    ms: s(gpu - camera),
                },
                PassTime {
                    pass: "camera_pass".into(),
                    ms: s(camera),
                },
            ],
            gpu_total_ms: Some(s(gpu)),
            wall_ms: s(wall),
            hit_pixels: 10,
            rays_ms: None,
        }
    }

    fn run(method: Method, timing: Option<Timing>) -> Run {
        Run {
            scene: "table1-5760".into(),
            size: 1024,
            label: crate::bench::Case::for_method(method).label,
            method: method.name().into(),
            error: timing
                .is_none()
                .then(|| "the pcf method is not available yet".into()),
            timing,
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
                run(Method::DBuffer, Some(timing(20.0, 50.0, 8.0, gpu))),
                run(Method::Hard, Some(timing(10.0, 40.0, 4.0, gpu))),
                run(Method::Pcf, None),
                run(Method::Pcss, Some(timing(30.0, 60.0, 16.0, gpu))),
                run(
                    Method::Reference,
                    Some(timing(20.0, 100.0, 8.0, FrameSource::FencedWall)),
                ),
            ],
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
            r.ratio_to_dbuffer("table1-5760", 1024, Method::Hard),
            Some(0.5)
        );
        // The reference is measured by wall time, so it is compared with the D-buffer's wall.
        assert_eq!(
            r.ratio_to_dbuffer("table1-5760", 1024, Method::Reference),
            Some(2.0)
        );
        assert_eq!(r.ratio_to_dbuffer("table1-5760", 1024, Method::Pcf), None);
    }

    #[test]
    fn targets_pass_and_miss_honestly() {
        let r = report();
        let [frame, camera, geometry] = &r.targets[..] else {
            panic!("three targets: {:?}", r.targets);
        };
        assert_eq!(frame.measured, Some(2.0));
        assert_eq!(frame.pass(), Some(false), "2× the hard frame misses ≤ 1.5×");
        assert_eq!(camera.measured, Some(0.5));
        assert_eq!(camera.pass(), Some(true));
        assert_eq!(geometry.measured, Some(0.25));
        assert_eq!(geometry.pass(), Some(true));
    }

    #[test]
    fn markdown_has_every_table_and_row() {
        let md = markdown(&report());
        assert!(md.contains("test adapter"));
        assert!(md.contains("| `table1-5760` | 5,760 | 1024² | 0.250 | 12.0 | 8.0 | 20.0 | 50 |"));
        assert!(md.contains("| hard | 10.0 (0.50×) | 4.0 |"), "{md}");
        assert!(md.contains("| pcf | n/a (not implemented) | – |"), "{md}");
        assert!(
            md.contains("| reference 1 spp | 100 wall (2.00×) |"),
            "{md}"
        );
        assert!(md.contains("| D-buffer frame / hard-shadow frame | 2.000 × | ≤ 1.5 × | MISS |"));
        assert!(md.contains("PASS"));
        assert_eq!(thousands(1_048_576), "1,048,576");
    }
}
