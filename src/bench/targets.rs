//! The targets, judged from a finished [`Report`]: ratios of the D-buffer to the hard
//! shadow map, PCSS and the floor, the lab's display path, and the geometry stage's time.

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
    let judged = || {
        report
            .scenes
            .iter()
            .filter(move |s| !table1 || TABLE1_SCENES.contains(&s.name.as_str()))
    };
    let worst = |f: &dyn Fn(&str) -> Option<f64>| -> (Option<f64>, String) {
        let mut best: Option<(f64, &str)> = None;
        let mut all = Vec::new();
        let mut missing = Vec::new();
        for s in judged() {
            match f(&s.name) {
                Some(v) => {
                    all.push(v);
                    if best.is_none_or(|(b, _)| v > b) {
                        best = Some((v, &s.name));
                    }
                }
                None => missing.push(s.name.as_str()),
            }
        }
        let median = Stat::of(&all).map_or(f64::NAN, |s| s.median);
        match best {
            Some((v, name)) => {
                let mut detail =
                    format!("worst scene {name} at {size}² (median over scenes {median:.2})");
                if !missing.is_empty() {
                    detail += &format!("; not measured on {}", missing.join(", "));
                }
                (Some(v), detail)
            }
            None => (None, format!("not measured at {size}²")),
        }
    };
    let ratio = |a: Option<Stat>, b: Option<Stat>| {
        let (a, b) = (a?.median, b?.median);
        (b > 0.0).then(|| a / b)
    };
    let dbuffer = |s: &str| report.timing(s, size, Method::DBUFFER);
    let hard = |s: &str| report.timing(s, size, Method::HARD);
    let frame = worst(&|s| {
        let (d, h) = (dbuffer(s)?, hard(s)?);
        ratio(Some(d.frame_ms), h.frame_by(d.frame_source))
    });
    let light = worst(&|s| ratio(dbuffer(s)?.light_ms, hard(s)?.light_ms));
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
    vec![
        at_most("lab frame (light still) / readback path", lab, 0.6),
        Target {
            name: "lab frame fps, light moving, table1-960 at 600²".into(),
            measured: moving.flatten(),
            limit: Some(30.0),
            strict: false,
            at_least: true,
            unit: "fps".into(),
            detail: "wall time of geometry, light pass and camera pass (the final image), fenced"
                .into(),
        },
        at_most("D-buffer light pass / hard-shadow light pass", light, 1.5),
        at_most(
            "D-buffer camera pass / hard-shadow camera pass",
            camera_hard,
            1.05,
        ),
        at_most("D-buffer frame / hard-shadow frame", frame, 1.5),
        at_most(
            "D-buffer frame under a 16-gon light / under the disk",
            polygon,
            1.3,
        ),
        Target {
            strict: true,
            ..at_most("D-buffer camera pass / PCSS camera pass", camera_pcss, 1.0)
        },
        Target {
            limit: None,
            ..at_most("D-buffer frame / floor (flat colour + depth)", floor, 0.0)
        },
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
