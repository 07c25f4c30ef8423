//! `dbuffer gui SCENE --study DIR`: the lab reads a study, draws its plot for the open scene and
//! switches to the method and setting of a point clicked.

use dbuffer::app::LabOptions;
use dbuffer::render::methods::pcss::{BLOCKER_TAPS, FILTER_TAPS};
use dbuffer::render::{GpuContext, Method};
use dbuffer::study::{self, Flow, StudySpec};
use egui_kittest::kittest::Queryable;

use crate::support as support_lab;

/// A small real study of `hard` and `pcss` on `table1-224` into a fresh folder named `tag`.
fn small_study(tag: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("dbuffer-lab-study-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let pcss: Method = "pcss".parse().expect("pcss is a method");
    let mut spec = StudySpec::quick();
    spec.narrow(
        Some(vec!["table1-224".into()]),
        Some(vec![Method::HARD, pcss]),
        Some((48, 48)),
    )
    .expect("narrowed");
    spec.samples = 16;
    spec.warmup = 0;
    spec.frames = 1;
    let scene = dbuffer::scene::load("table1-224").expect("a built-in");
    let ctx = GpuContext::headless().expect("an adapter");
    let study = study::run(&ctx, &spec, &[scene], &dir, &mut |_| Flow::Go).expect("the study runs");
    study::report::write(&study, &dir).expect("its files are written");
    dir
}

#[test]
fn a_study_plot_shows_the_scene_and_a_click_switches_to_its_cell() {
    let dir = small_study("click");
    let mut h = support_lab::lab_with(
        LabOptions {
            scene: Some("table1-224".into()),
            study: Some(dir.clone()),
            ..LabOptions::default()
        },
        1100.0,
        800.0,
    );
    h.run();
    let app = h.state();
    assert!(app.study.error.is_none(), "{:?}", app.study.error);
    assert!(app.study.open, "the plot opens with the lab");
    let scene = app
        .study
        .scene("table1-224")
        .expect("the study has the open scene");
    // hard at three map sizes and pcss at three settings, each drawn.
    assert_eq!(app.study.drawn.len(), 6, "every measured cell is a point");
    // The dearest pcss setting: 32 blocker and 64 filter taps.
    let (pos, cell) = app
        .study
        .drawn
        .iter()
        .map(|&(pos, i)| (pos, &scene.cells[i]))
        .find(|(_, c)| c.method == "pcss" && c.values.contains(&("blocker-taps".into(), 32)))
        .expect("pcss 32/64 is on the plot");
    assert_eq!(
        cell.values,
        vec![("blocker-taps".into(), 32), ("filter-taps".into(), 64)]
    );
    assert_ne!(
        app.settings.method, "pcss",
        "the lab starts on its own method"
    );

    let map_size = cell.map_size;
    // A knob the cell does not sweep, moved by hand: the cell is shown as measured, at its default.
    h.state_mut().settings.knobs.set("pcf-radius", 5).unwrap();
    h.drag_at(pos);
    h.drop_at(pos);
    h.run();
    let app = h.state();
    assert_eq!(app.settings.method, "pcss", "{}", app.status().0);
    assert_eq!(app.settings.knobs.get(&BLOCKER_TAPS), 32);
    assert_eq!(app.settings.knobs.get(&FILTER_TAPS), 64);
    assert_eq!(
        app.settings
            .knobs
            .get(&dbuffer::render::methods::pcf::RADIUS),
        dbuffer::render::Knobs::default().get(&dbuffer::render::methods::pcf::RADIUS)
    );
    assert_eq!(app.settings.dbuffer_size, map_size);
    assert!(
        app.status().0.contains("study: showing pcss"),
        "{}",
        app.status().0
    );
    assert_eq!(
        app.shown().map(|s| s.method.name()),
        Some("pcss"),
        "the viewport shows it"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_study_without_the_open_scene_says_so() {
    let dir = small_study("other");
    let mut h = support_lab::lab_with(
        LabOptions {
            scene: Some("fig7-concave".into()),
            study: Some(dir.clone()),
            ..LabOptions::default()
        },
        1100.0,
        800.0,
    );
    h.run();
    assert!(h.state().study.drawn.is_empty());
    h.get_by_label_contains("the study has no cells of fig7-concave");
    let _ = std::fs::remove_dir_all(&dir);
}
