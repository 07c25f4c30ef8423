//! `compare --orbit` (`dbuffer::compare::temporal`): a still scene gives every method — all of
//! them deterministic — no temporal error and no popping at all; on the paper's complex caster
//! and a Table 1 scene the D-buffer moves with the reference more closely than 16 sampled lights
//! and PCSS (`dbuffer-fused` in both numbers on both scenes; the paper's `dbuffer` pops less on
//! both, and has the lower temporal error on `table1-960` but not on `fig8c-complex`, where its
//! one-chord error where the knot overlaps itself moves with the light); the report and its
//! files hold what the run measured. Test-sized: 64² and a few
//! frames (`dbuffer compare SCENE --orbit light` runs the real thing, docs/results/motion.md).

use dbuffer::compare::temporal::{self, Motion, MotionRequest};
use dbuffer::compare::{self, report, CompareRequest};
use dbuffer::geometry::VtVariant;
use dbuffer::render::methods::reference::SAMPLES;
use dbuffer::render::offline::Offline;
use dbuffer::render::{Knobs, Method};
use dbuffer::scene::orbit::Orbit;
use dbuffer::scene::{self, Scene};

fn request(side: u32, orbit: Option<Orbit>, frames: usize) -> MotionRequest {
    MotionRequest {
        compare: CompareRequest {
            width: side,
            height: side,
            dbuffer_size: 512,
            vt: VtVariant::Exact,
            knobs: Knobs::default().with(&SAMPLES, temporal::DEFAULT_SAMPLES),
        },
        orbit,
        frames,
    }
}

fn run(offline: &mut Offline, scene: &Scene, r: &MotionRequest) -> Motion {
    temporal::run(offline, scene, r, |_, _| {}).unwrap_or_else(|e| panic!("{e}"))
}

fn row<'a>(m: &'a Motion, name: &str) -> &'a temporal::MethodMotion {
    m.methods
        .iter()
        .find(|r| r.method.name() == name)
        .unwrap_or_else(|| panic!("{name} in the run"))
}

#[test]
fn a_still_scene_has_no_temporal_error() {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let scene = scene::load("fig8c-complex").unwrap_or_else(|e| panic!("{e}"));
    let m = run(&mut offline, &scene, &request(48, None, 3));
    assert_eq!(m.orbit, "still");
    let drawn = Method::all()
        .iter()
        .filter(|x| !x.is_reference() && **x != Method::REFERENCE_HARD)
        .filter(|x| x.refuses(scene.light.kind()).is_none())
        .count();
    assert_eq!(m.methods.len(), drawn, "every method that takes the light");
    assert!(m.counted.iter().all(|&c| c > 500), "{:?}", m.counted);
    // The reference's pattern does not change: it does not move at all.
    assert!(m.reference_motion.iter().all(|&r| r == 0.0));
    for r in &m.methods {
        // A temporal method's history goes on filling with new rays on a still scene (a running
        // mean over up to `rt-history` frames): its image changes a little from frame to frame,
        // by the noise left, never by a shadow that moves.
        if r.method.spec().history.is_some() {
            let counted = m.counted.iter().copied().min().unwrap_or(0);
            println!(
                "{}: {:?} on a still scene, popping {:?}",
                r.method, r.steps, r.popping
            );
            assert!(
                r.steps.iter().all(|&e| e < 0.005),
                "{}: moved on a still scene: {:?}",
                r.method,
                r.steps
            );
            assert!(
                r.popping.iter().all(|&p| p * 100 < counted),
                "{}: popped on a still scene: {:?} of {counted}",
                r.method,
                r.popping
            );
            continue;
        }
        assert_eq!(
            r.steps,
            vec![0.0, 0.0],
            "{}: moved on a still scene",
            r.method
        );
        assert_eq!(
            r.popping,
            vec![0, 0],
            "{}: popped on a still scene",
            r.method
        );
    }
}

#[test]
fn the_dbuffer_moves_with_the_reference_more_than_sampled_and_pcss() {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    for name in ["fig8c-complex", "table1-960"] {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        let m = run(&mut offline, &scene, &request(64, Some(Orbit::Light), 6));
        assert!(
            m.reference_motion.iter().all(|&r| r > 0.0),
            "{name}: the light moved"
        );
        for r in &m.methods {
            println!(
                "{name}: {:<20} temporal {:.4}  popping {:.3} %",
                r.method.name(),
                r.temporal_error(),
                m.popping_pct(r)
            );
        }
        for (d, temporal) in [("dbuffer-fused", true), ("dbuffer", name == "table1-960")] {
            let d = row(&m, d);
            for other in ["sampled", "pcss"] {
                let o = row(&m, other);
                if temporal {
                    assert!(
                        d.temporal_error() < o.temporal_error(),
                        "{name}: {} {} against {other} {}",
                        d.method,
                        d.temporal_error(),
                        o.temporal_error()
                    );
                }
                assert!(
                    m.popping_pct(d) < m.popping_pct(o),
                    "{name}: {} popping {} against {other} {}",
                    d.method,
                    m.popping_pct(d),
                    m.popping_pct(o)
                );
            }
        }
    }
}

#[test]
fn the_report_holds_the_motion_and_its_files() {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let name = "fig7-concave";
    let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
    let r = request(40, Some(Orbit::Camera), 3);
    let comparison = compare::run(&mut offline, name, &scene, &r.compare, |_| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let motion = run(&mut offline, &scene, &r);
    let dir = std::env::temp_dir().join(format!("dbuffer-temporal-test-{}", std::process::id()));
    let written = report::write(&dir, &comparison, Some(&motion)).unwrap_or_else(|e| panic!("{e}"));
    let text = std::fs::read_to_string(dir.join(report::REPORT_JSON)).unwrap();
    let json: report::Report = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}"));
    let summary = json.motion.as_ref().expect("the motion in report.json");
    assert_eq!((summary.orbit.as_str(), summary.frames), ("camera", 3));
    assert_eq!(summary.samples, temporal::DEFAULT_SAMPLES);
    let worst = motion.worst().unwrap();
    assert_eq!(summary.worst.as_deref(), Some(worst.method.name()));
    for m in &motion.methods {
        let row = json
            .methods
            .iter()
            .find(|r| r.method == m.method.name())
            .unwrap();
        let close = |a: Option<f64>, b: f64| a.is_some_and(|a| (a - b).abs() <= 1e-12);
        assert!(close(row.temporal_error, m.temporal_error()), "{row:?}");
        assert!(close(row.popping, motion.popping_pct(m)), "{row:?}");
        assert_eq!(row.popping_px, Some(m.popping.iter().sum()));
        let plot = row.temporal_plot.as_ref().unwrap();
        let img = image::open(dir.join(plot)).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (720, 360));
    }
    // The references are not measured in motion (they are what motion is measured against).
    let reference = json
        .methods
        .iter()
        .find(|r| r.method == "reference")
        .unwrap();
    assert_eq!(reference.temporal_error, None);
    // The APNG: one frame per step, the method's error beside the reference's motion.
    let apng = std::fs::read(dir.join(temporal::MOTION_APNG)).unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(apng));
    let reader = decoder.read_info().unwrap();
    let info = reader.info();
    assert_eq!(info.animation_control.map(|a| a.num_frames), Some(2));
    assert_eq!((info.width, info.height), (2 * 40 + 4, 40));
    let md = std::fs::read_to_string(dir.join(report::REPORT_MD)).unwrap();
    assert!(
        md.contains("## In motion: the camera orbit, 3 frames"),
        "{md}"
    );
    assert!(md.contains(temporal::MOTION_APNG));
    assert!(written.iter().any(|p| p.ends_with(temporal::MOTION_APNG)));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `compare --orbit` on every built-in, with every method that takes its light: a light orbit
/// and a camera orbit of two frames at 24², every value finite (the real runs:
/// docs/results/motion.md).
#[test]
fn every_builtin_goes_round_with_every_method() {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    for name in scene::builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        for orbit in [Orbit::Light, Orbit::Camera] {
            let mut r = request(24, Some(orbit), 2);
            r.compare.dbuffer_size = 256;
            r.compare.knobs = Knobs::default().with(&SAMPLES, 16);
            let m = temporal::run(&mut offline, &scene, &r, |_, _| {})
                .unwrap_or_else(|e| panic!("{name}, {orbit:?}: {e}"));
            let takes = Method::all()
                .iter()
                .filter(|x| !x.is_reference() && **x != Method::REFERENCE_HARD)
                .filter(|x| x.refuses(scene.light.kind()).is_none())
                .count();
            assert_eq!(m.methods.len(), takes, "{name}");
            for x in &m.methods {
                assert_eq!(x.steps.len(), 1, "{name}: {}", x.method);
                assert!(
                    x.temporal_error().is_finite() && x.temporal_error() >= 0.0,
                    "{name}, {orbit:?}: {} {}",
                    x.method,
                    x.temporal_error()
                );
            }
        }
    }
}
