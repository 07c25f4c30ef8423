//! What a study writes: `study.json` (every cell and the machine), `study.md` (per scene the
//! plot, the front, the equal-cost and equal-error tables, every cell) and the plots
//! (`plots/SCENE.png` by penumbra MAE, `plots/SCENE-flip.png` by FLIP). Each file is written
//! whole and renamed into place: an earlier study's files are replaced only by complete ones.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::front::{dbuffer_frame, equal_cost, equal_error, front, points, ErrorAxis};
use super::plot::scene_png;
use super::run::{SceneStudy, Study};
use crate::fsutil::write_atomic;

/// The plot's size.
pub const PLOT_SIZE: (u32, u32) = (1100, 720);

/// The file name a scene's plot takes (its name, safe for a file).
pub fn plot_name(scene: &str, axis: ErrorAxis) -> String {
    let safe: String = scene
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    match axis {
        ErrorAxis::PenumbraMae => format!("{safe}.png"),
        ErrorAxis::Flip => format!("{safe}-flip.png"),
    }
}

/// Write `study`'s files into `out`; the paths written.
pub fn write(study: &Study, out: &Path) -> Result<Vec<PathBuf>, String> {
    let mut written = Vec::new();
    let io = |p: &Path, e: std::io::Error| format!("cannot write {}: {e}", p.display());
    let plots = out.join("plots");
    std::fs::create_dir_all(&plots).map_err(|e| io(&plots, e))?;
    for scene in &study.scenes {
        for axis in [ErrorAxis::PenumbraMae, ErrorAxis::Flip] {
            let (w, h) = PLOT_SIZE;
            match scene_png(scene, axis, study.dbuffer_size, w, h) {
                Ok(png) => {
                    let path = plots.join(plot_name(&scene.name, axis));
                    write_atomic(&path, &png).map_err(|e| io(&path, e))?;
                    written.push(path);
                }
                // A scene with no measured cell has no plot; study.md says so.
                Err(_) if points(scene, axis).is_empty() => {}
                Err(e) => return Err(e),
            }
        }
    }
    let json = serde_json::to_string_pretty(study).map_err(|e| e.to_string())?;
    let path = out.join("study.json");
    write_atomic(&path, json.as_bytes()).map_err(|e| io(&path, e))?;
    written.push(path);
    let path = out.join("study.md");
    write_atomic(&path, markdown(study).as_bytes()).map_err(|e| io(&path, e))?;
    written.push(path);
    Ok(written)
}

fn cell_name(scene: &SceneStudy, i: usize) -> String {
    let c = &scene.cells[i];
    if c.values.is_empty() {
        format!("`{}`", c.method)
    } else {
        format!("`{}` ({})", c.method, c.setting)
    }
}

/// `study.md`.
pub fn markdown(study: &Study) -> String {
    let mut md = String::new();
    let m = &study.machine;
    let _ = writeln!(md, "# Error against cost\n");
    let _ = writeln!(
        md,
        "{}×{} pixels, light-space maps {}² unless a setting says, V(t) {}, {} warm-up and {} \
         timed frames a cell (medians), {}. Machine: {} · adapter {} ({}, {}), driver {} {} · {}. \
         {} cells measured in {:.0} s, {} from the cache{}.\n",
        study.width,
        study.height,
        study.dbuffer_size,
        study.vt,
        study.warmup,
        study.frames,
        if study.quick {
            "--quick"
        } else {
            "the full study"
        },
        m.cpu,
        m.adapter,
        m.backend,
        m.device_type,
        m.driver,
        m.driver_info,
        m.build,
        study.measured,
        study.seconds,
        study.cached,
        if study.stopped {
            "; **stopped before the end**: run the same command again to finish"
        } else {
            ""
        }
    );
    let _ = writeln!(
        md,
        "Cost: the sum of a frame's GPU passes (timestamps), wall time for the CPU-side \
         methods (the reference: K samples' ray casting); a cell whose first timed frame took \
         over 2 s is timed on that frame alone. Error: against the scene's reference \
         (`compare`'s metrics); the noise floor is that reference's own penumbra MAE against one \
         of 4K samples. The front: the cells no other cell beats on both cost and penumbra MAE.\n"
    );
    for scene in &study.scenes {
        let _ = writeln!(
            md,
            "## `{}`\n\n{} light, {} caster triangles, reference K = {}, noise floor {:.4}.\n",
            scene.name,
            scene.light,
            scene.caster_triangles,
            scene.reference_samples,
            scene.noise_floor
        );
        let pts = points(scene, ErrorAxis::PenumbraMae);
        if pts.is_empty() {
            let _ = writeln!(md, "No cell was measured both ways.\n");
            continue;
        }
        let _ = writeln!(
            md,
            "![{0}](plots/{1}) ([FLIP](plots/{2}))\n",
            scene.name,
            plot_name(&scene.name, ErrorAxis::PenumbraMae),
            plot_name(&scene.name, ErrorAxis::Flip)
        );
        let f: Vec<String> = front(&pts)
            .iter()
            .map(|p| {
                format!(
                    "{} {:.1} ms · {:.4}",
                    cell_name(scene, p.cell),
                    p.cost,
                    p.error
                )
            })
            .collect();
        let _ = writeln!(md, "**Front** (cheapest first): {}.\n", f.join("; "));
        match dbuffer_frame(scene, study.dbuffer_size) {
            Some(ms) => {
                let _ = writeln!(
                    md,
                    "**Equal cost** (the D-buffer's frame: {ms:.1} ms)\n\n| budget | least \
                     penumbra MAE | by |\n|---|---:|---|"
                );
                for row in equal_cost(&pts, ms) {
                    let (e, by) =
                        row.best
                            .map_or(("—".into(), "nothing that cheap".into()), |i| {
                                let p = pts.iter().find(|p| p.cell == i).copied();
                                (
                                    p.map_or("—".into(), |p| format!("{:.4}", p.error)),
                                    format!(
                                        "{} at {:.1} ms",
                                        cell_name(scene, i),
                                        p.map_or(0.0, |p| p.cost)
                                    ),
                                )
                            });
                    let _ = writeln!(
                        md,
                        "| {}× ({:.1} ms) | {e} | {by} |",
                        row.times, row.budget_ms
                    );
                }
                let _ = writeln!(md);
            }
            None => {
                let _ = writeln!(
                    md,
                    "No D-buffer frame on this scene: no equal-cost table.\n"
                );
            }
        }
        let _ = writeln!(
            md,
            "**Equal error** (noise floor {:.4})\n\n| within | cheapest | cost |\n|---|---|---:|",
            scene.noise_floor
        );
        for row in equal_error(&pts, scene.noise_floor) {
            let (by, cost) =
                row.cheapest
                    .map_or(("no cell reaches it".into(), "—".into()), |i| {
                        let p = pts.iter().find(|p| p.cell == i).copied();
                        (
                            format!(
                                "{} ({:.4})",
                                cell_name(scene, i),
                                p.map_or(0.0, |p| p.error)
                            ),
                            format!("{:.1} ms", p.map_or(0.0, |p| p.cost)),
                        )
                    });
            let _ = writeln!(md, "| {}× ({:.4}) | {by} | {cost} |", row.times, row.target);
        }
        let _ = writeln!(
            md,
            "\n| method | setting | frame ms | penumbra MAE | p99 | class % | FLIP |\n\
             |---|---|---:|---:|---:|---:|---:|"
        );
        let mut said = None;
        for c in &scene.cells {
            if let Some(why) = &c.not_measured {
                // One row for a method the scene rules out (its settings all say the same),
                // its reason without the list of methods that would do.
                let why = why.split("; ").next().unwrap_or(why);
                let of_method = |d: &&super::run::Cell| d.method == c.method;
                let all = scene.cells.iter().filter(of_method).all(|d| {
                    d.not_measured
                        .as_deref()
                        .is_some_and(|w| w.split("; ").next() == Some(why))
                });
                if !all {
                    let _ = writeln!(
                        md,
                        "| `{}` | {} | n/a — {why} | | | | |",
                        c.method, c.setting
                    );
                } else if said != Some(&c.method) {
                    let _ = writeln!(
                        md,
                        "| `{}` | every setting | n/a — {why} | | | | |",
                        c.method
                    );
                    said = Some(&c.method);
                }
                continue;
            }
            let cost = c
                .cost
                .as_ref()
                .map_or("—".into(), |c| match c.timing.frames {
                    // Over the slow-frame guard: timed on its first frame alone.
                    1 if study.frames > 1 => format!("{:.2} (1 frame)", c.frame_ms),
                    _ => format!("{:.2}", c.frame_ms),
                });
            match c.error {
                Some(e) => {
                    let _ = writeln!(
                        md,
                        "| `{}` | {} | {cost} | {:.4} | {:.3} | {:.2} | {:.4} |",
                        c.method, c.setting, e.penumbra_mae, e.p99, e.class_mismatch_pct, e.flip
                    );
                }
                None => {
                    let _ = writeln!(
                        md,
                        "| `{}` | {} | {cost} | — | — | — | — |",
                        c.method, c.setting
                    );
                }
            }
        }
        let _ = writeln!(md);
    }
    md
}
