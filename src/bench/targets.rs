//! The targets, judged from a finished [`Report`]: `dbuffer-fused`
//! against the D-buffer and the wedges, the D-buffer against the hard shadow map (median and
//! worst scene) and PCSS, the polygon light, and the geometry stage's time; the lab's display
//! path, the camera pass against the hard shadow's and the floor are reported, no longer targets
//! (the window itself is timed by `dbuffer gui --bench`).

use super::{Case, Report, Stat, Target, TABLE1_SCENES, TARGET_SIZE};
use crate::render::methods::pcss;
use crate::render::Method;

/// The targets, measured on the worst Table 1 scene at 1024² (or the largest size run).
pub fn targets(report: &Report) -> Vec<Target> {
    let size = if report.sizes().contains(&TARGET_SIZE) {
        TARGET_SIZE
    } else {
        report.sizes().last().copied().unwrap_or(TARGET_SIZE)
    };
    // The targets are the Table 1 scenes' where the run has any (other scenes, such as the
    // fusion ones, are in the tables but not in the targets).
    let table1 = report
        .scenes
        .iter()
        .any(|s| TABLE1_SCENES.contains(&s.name.as_str()));
    // Over the judged scenes (`every`: every scene run, the fusion ones too): the median, the
    // worst and where.
    let over = |f: &dyn Fn(&str) -> Option<f64>, every: bool| -> Spread {
        let mut worst: Option<(f64, &str)> = None;
        let mut all = Vec::new();
        let mut missing = Vec::new();
        for s in report
            .scenes
            .iter()
            .filter(|s| every || !table1 || TABLE1_SCENES.contains(&s.name.as_str()))
        {
            match f(&s.name) {
                Some(v) => {
                    all.push(v);
                    if worst.is_none_or(|(b, _)| v > b) {
                        worst = Some((v, &s.name));
                    }
                }
                None => missing.push(s.name.as_str()),
            }
        }
        let median = Stat::of(&all).map(|s| s.median);
        let mut detail = match worst {
            Some((v, name)) => format!(
                "median over {} scene{} at {size}²; worst {name} {v:.2}",
                all.len(),
                if all.len() == 1 { "" } else { "s" }
            ),
            None => format!("not measured at {size}²"),
        };
        if worst.is_some() && !missing.is_empty() {
            detail += &format!("; not measured on {}", missing.join(", "));
        }
        Spread {
            median,
            worst: worst.map(|w| w.0),
            detail,
        }
    };
    let worst = |f: &dyn Fn(&str) -> Option<f64>| {
        let s = over(f, false);
        (s.worst, s.detail)
    };
    let median = |f: &dyn Fn(&str) -> Option<f64>, every: bool| {
        let s = over(f, every);
        (s.median, s.detail)
    };
    let ratio = |a: Option<Stat>, b: Option<Stat>| {
        let (a, b) = (a?.median, b?.median);
        (b > 0.0).then(|| a / b)
    };
    let dbuffer = |s: &str| report.timing(s, size, Method::DBUFFER);
    let hard = |s: &str| report.timing(s, size, Method::HARD);
    let frame_ratio = |s: &str| {
        let (d, h) = (dbuffer(s)?, hard(s)?);
        ratio(Some(d.frame_ms), h.frame_by(d.frame_source))
    };
    let frame = median(&frame_ratio, false);
    let frame_worst = worst(&frame_ratio);
    let light = median(&|s| ratio(dbuffer(s)?.light_ms, hard(s)?.light_ms), false);
    // dbuffer-fused over the D-buffer and over the wedges, frame to frame, on every scene run
    // (Table 1 and the fusion scenes when the run has them).
    let fused_over = |other: Method| {
        median(
            &|s| {
                let f = report.timing(s, size, Method::DBUFFER_FUSED)?;
                let o = report.timing(s, size, other)?;
                ratio(Some(f.frame_ms), o.frame_by(f.frame_source))
            },
            true,
        )
    };
    let fused_dbuffer = fused_over(Method::DBUFFER);
    let wedges = Method::of(&crate::render::methods::wedges::WEDGES);
    let fused_wedges = match wedges {
        Some(w) => fused_over(w),
        None => (None, "wedges are not on the registry".into()),
    };
    let camera_hard = worst(&|s| {
        ratio(
            dbuffer(s)?.pass("camera_pass"),
            hard(s)?.pass("camera_pass"),
        )
    });
    let camera_pcss = worst(&|s| {
        let p = report.timing(s, size, Method::of(&pcss::PCSS)?)?;
        ratio(dbuffer(s)?.pass("camera_pass"), p.pass("camera_pass"))
    });
    // The D-buffer under the 16-gon inscribed in the disk (`Case::polygon_dbuffer`) over the
    // D-buffer under the disk, on the same casters.
    let polygon_label = format!("{} (polygon light)", Case::polygon_dbuffer().label);
    let polygon = worst(&|s| {
        let p = report
            .runs
            .iter()
            .find(|r| r.scene == s && r.size == size && r.label == polygon_label)?
            .timing
            .as_ref()?;
        let d = dbuffer(s)?;
        ratio(Some(p.frame_ms), d.frame_by(p.frame_source))
    });
    let display = |s: &str, sz: u32| report.display.iter().find(|d| d.scene == s && d.size == sz);
    let lab = worst(&|s| {
        let d = display(s, size)?;
        ratio(Some(d.lab_still.wall_ms), Some(d.readback.wall_ms))
    });
    let floor = worst(&|s| {
        let d = dbuffer(s)?;
        ratio(d.gpu_total_ms, display(s, size)?.floor_gpu_ms)
    });
    let moving = display("table1-960", 600).map(|d| {
        let ms = d.lab_moving.wall_ms.median;
        (ms > 0.0).then(|| 1e3 / ms)
    });
    let geometry = report
        .scenes
        .iter()
        .find(|s| s.caster_triangles == 5760)
        .map(|s| (s.geometry_ms.median, format!("{} (CPU)", s.name)));
    let at_most = |name: &str, (measured, detail): (Option<f64>, String), limit: f64| Target {
        name: name.into(),
        measured,
        limit: Some(limit),
        strict: false,
        at_least: false,
        unit: "×".into(),
        detail,
    };
    let reported = |t: Target| Target { limit: None, ..t };
    vec![
        at_most(
            "dbuffer-fused frame / D-buffer frame (median)",
            fused_dbuffer,
            2.5,
        ),
        at_most(
            "dbuffer-fused frame / wedges frame (median)",
            fused_wedges,
            1.0,
        ),
        at_most("D-buffer frame / hard-shadow frame (median)", frame, 1.3),
        at_most(
            "D-buffer frame / hard-shadow frame (worst scene)",
            frame_worst,
            1.45,
        ),
        at_most(
            "D-buffer light pass / hard-shadow light pass (median)",
            light,
            1.6,
        ),
        at_most(
            "D-buffer frame under a 16-gon light / under the disk",
            polygon,
            1.3,
        ),
        Target {
            strict: true,
            ..at_most("D-buffer camera pass / PCSS camera pass", camera_pcss, 1.0)
        },
        reported(at_most(
            "D-buffer frame / floor (flat colour + depth)",
            floor,
            0.0,
        )),
        reported(at_most(
            "D-buffer camera pass / hard-shadow camera pass",
            camera_hard,
            0.0,
        )),
        reported(at_most("lab frame (light still) / readback path", lab, 0.0)),
        reported(Target {
            name: "lab frame fps, light moving, table1-960 at 600²".into(),
            measured: moving.flatten(),
            limit: None,
            strict: false,
            at_least: true,
            unit: "fps".into(),
            detail: "wall time of geometry, light pass, camera pass and view pass, fenced".into(),
        }),
        Target {
            name: "geometry of the 5760-triangle caster".into(),
            measured: geometry.as_ref().map(|g| g.0),
            limit: Some(1.0),
            strict: true,
            at_least: false,
            unit: "ms".into(),
            detail: geometry.map_or_else(|| "table1-5760 not run".into(), |g| g.1),
        },
    ]
}

/// A ratio over the judged scenes.
struct Spread {
    median: Option<f64>,
    worst: Option<f64>,
    detail: String,
}
