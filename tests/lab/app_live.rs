//! Shaders edited while the lab runs (`dbuffer gui --shaders DIR`): the lab on a copy of
//! `shaders/` in a temporary folder, one method's file saved three times — V made a constant
//! (drawn at once, on the split view's side too), then a syntax error (shown over the viewport
//! with its file and line, the last good image kept), then the original again (the panel gone,
//! the original image back). The same for a user's method opened with File ▸ Open method…, whose
//! knob slider is driven too. Each save is waited for on the watcher's signal and then the lab's
//! reload count, never on a timer.

use std::path::{Path, PathBuf};
use std::time::Duration;

use dbuffer::app::{LabApp, LabOptions};
use dbuffer::render::methods::user;
use dbuffer::render::shaders;
use eframe::egui;
use egui_kittest::kittest::{NodeT, Queryable};
use egui_kittest::Harness;

use crate::support::{self as support_lab, step_until_gpu};

/// No other lab test draws it, so the folder set for the whole process changes no other test's
/// image while this one runs.
const METHOD: &str = "vsm";
const FILE: &str = "methods/vsm.wgsl";

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("temp folder");
    for entry in std::fs::read_dir(from).expect("shaders/") {
        let entry = entry.expect("entry");
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).expect("copy");
        }
    }
}

/// The frame's V of the main side, after the lab drew what it shows now.
fn visibility(h: &mut Harness<'_, LabApp>) -> Vec<f32> {
    h.state_mut()
        .read_shown(false)
        .expect("the shown frame")
        .visibility
}

/// Save `text` as the method's file, wait for the watcher to see it (its signal; the bound only
/// keeps a broken watcher from hanging the test), then step the lab until it has looked at it.
fn save(h: &mut Harness<'_, LabApp>, path: &Path, text: &str) {
    let seen = h.state().shader_watcher().expect("watching").changes();
    std::fs::write(path, text).expect("save");
    let now = h
        .state()
        .shader_watcher()
        .expect("watching")
        .wait_for_change(seen, Duration::from_secs(60));
    assert!(
        now > seen,
        "the watcher never saw the save of {}",
        path.display()
    );
}

/// `text` with V a constant 0.25: the method's own function renamed, a constant one after it.
fn constant_v(text: &str) -> String {
    text.replace("fn method_visibility(", "fn method_visibility_was(")
        + "\nfn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {\n    \
           return plain(0.25);\n}\n"
}

/// [`constant_v`]'s text with a syntax error, and the error's line.
fn broken(constant: &str) -> (String, usize) {
    let broken = constant.replace(
        "    return plain(0.25);",
        "    let oops = ;\n    return plain(0.25);",
    );
    let line = broken
        .lines()
        .position(|l| l.contains("let oops"))
        .expect("the broken line")
        + 1;
    (broken, line)
}

/// Whether more than a quarter of `v` is 0.25 (the constant V).
fn mostly_quarter(v: &[f32]) -> bool {
    v.iter().filter(|x| **x == 0.25).count() > v.len() / 4
}

#[test]
fn a_saved_shader_redraws_and_a_broken_one_is_shown_until_fixed() {
    let dir: PathBuf = std::env::temp_dir().join(format!("dbuffer-live-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders"), &dir);
    let file = dir.join(FILE);
    let original = std::fs::read_to_string(&file).expect("the method's file");

    let mut h = support_lab::lab_with(
        LabOptions {
            shaders: Some(dir.clone()),
            ..LabOptions::default()
        },
        900.0,
        700.0,
    );
    h.state_mut().settings.method = METHOD.into();
    h.run();
    assert!(
        step_until_gpu(&mut h, 20, |h| h
            .state()
            .shown()
            .is_some_and(|s| s.method.name() == METHOD)),
        "{METHOD} was not shown"
    );
    assert!(h.state().shader_errors().is_empty());
    let before = visibility(&mut h);

    let constant = constant_v(&original);
    save(&mut h, &file, &constant);
    assert!(
        step_until_gpu(&mut h, 20, |h| h.state().shader_reloads() == 1),
        "the save was not reloaded: {:?}",
        h.state().status()
    );
    step_until_gpu(&mut h, 5, |_| false);
    let flat = visibility(&mut h);
    assert!(
        mostly_quarter(&flat) && flat != before,
        "V is not the saved constant"
    );
    // The split view's right side draws the new code too.
    h.state_mut().settings.split = true;
    h.state_mut().settings.split_method = METHOD.into();
    assert!(
        step_until_gpu(&mut h, 20, |h| h
            .state()
            .shown_split()
            .is_some_and(|s| s.method.name() == METHOD)),
        "no split view"
    );
    let right = h.state_mut().read_shown(true).expect("the right side");
    assert!(
        mostly_quarter(&right.visibility),
        "the split's side is not the saved V"
    );
    h.state_mut().settings.split = false;
    step_until_gpu(&mut h, 5, |_| false);

    // A syntax error: shown with the file, its line and the line, the constant still drawn.
    let broken = constant.replace(
        "    return plain(0.25);",
        "    let oops = ;\n    return plain(0.25);",
    );
    let line = broken
        .lines()
        .position(|l| l.contains("let oops"))
        .expect("the broken line")
        + 1;
    save(&mut h, &file, &broken);
    assert!(
        step_until_gpu(&mut h, 20, |h| !h.state().shader_errors().is_empty()),
        "no error shown: {:?}",
        h.state().status()
    );
    let errors: Vec<_> = h.state().shader_errors().into_iter().cloned().collect();
    assert_eq!(errors.len(), 1, "{errors:?}");
    let e = &errors[0];
    assert_eq!(
        (e.file.as_str(), e.line as usize),
        (file.display().to_string().as_str(), line),
        "{e}"
    );
    assert_eq!(
        e.text.as_deref().map(str::trim),
        Some("let oops = ;"),
        "{e}"
    );
    let place = format!("{}:{line}:", file.display());
    // The panel is laid out unseen in its first frame (egui sizes a new area first).
    assert!(
        step_until_gpu(&mut h, 5, |h| h.query_by_label_contains(&place).is_some()),
        "the error panel does not name {place}"
    );
    assert_eq!(h.state().shader_reloads(), 1, "a broken file was applied");
    step_until_gpu(&mut h, 5, |_| false);
    assert_eq!(
        visibility(&mut h),
        flat,
        "the last good shader stopped drawing"
    );

    // Fixed (the original again): the error goes, the original V comes back.
    save(&mut h, &file, &original);
    assert!(
        step_until_gpu(&mut h, 20, |h| h.state().shader_reloads() == 2),
        "the fix was not reloaded: {:?}",
        h.state().shader_errors()
    );
    assert!(h.state().shader_errors().is_empty());
    step_until_gpu(&mut h, 5, |_| false);
    assert!(
        h.query_by_label_contains(&place).is_none(),
        "the panel stayed"
    );
    assert_eq!(
        visibility(&mut h),
        before,
        "the original V did not come back"
    );

    shaders::set_dir(None).expect("the embedded shaders");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_opened_method_is_listed_with_its_knobs_and_its_file_watched() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("dbuffer-live-method-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp folder");
    let file = dir.join("mine.wgsl");
    let original = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/methods/pcss_variant.wgsl"),
    )
    .expect("the example");
    std::fs::write(&file, &original).expect("copy");

    let mut h = support_lab::lab_sized(None, 900.0, 700.0);
    h.run();
    // What File > Open method... does once its dialog gave the path (a .wgsl dropped on the
    // window is opened so too).
    support_lab::drop_file(&mut h, &file);
    assert!(
        step_until_gpu(&mut h, 20, |h| h
            .state()
            .shown()
            .is_some_and(|s| s.method.name() == "user-mine")),
        "the opened method was not shown: {:?}",
        h.state().status()
    );
    // Listed among the methods, its header's knobs as sliders.
    h.get_by_label("user-mine");
    for knob in ["taps", "search_depth", "softness"] {
        assert!(
            h.query_all_by_label(knob).next().is_some(),
            "no slider {knob}"
        );
    }
    let before = visibility(&mut h);

    save(&mut h, &file, &constant_v(&original));
    assert!(
        step_until_gpu(&mut h, 20, |h| h.state().shader_reloads() == 1),
        "the save was not reloaded: {:?}",
        h.state().shader_errors()
    );
    step_until_gpu(&mut h, 5, |_| false);
    let flat = visibility(&mut h);
    assert!(
        mostly_quarter(&flat) && flat != before,
        "V is not the saved constant"
    );

    let (broken, line) = broken(&constant_v(&original));
    save(&mut h, &file, &broken);
    assert!(
        step_until_gpu(&mut h, 20, |h| !h.state().shader_errors().is_empty()),
        "no error shown"
    );
    let e = h.state().shader_errors()[0].clone();
    assert_eq!(
        (e.file.as_str(), e.line as usize),
        (file.display().to_string().as_str(), line),
        "{e}"
    );
    step_until_gpu(&mut h, 5, |_| false);
    assert_eq!(
        visibility(&mut h),
        flat,
        "the last good version stopped drawing"
    );

    save(&mut h, &file, &original);
    assert!(
        step_until_gpu(&mut h, 20, |h| h.state().shader_reloads() == 2),
        "the fix was not reloaded"
    );
    assert!(h.state().shader_errors().is_empty());
    step_until_gpu(&mut h, 5, |_| false);
    assert_eq!(
        visibility(&mut h),
        before,
        "the original V did not come back"
    );

    // A knob's slider: its value reaches the shader with the next frame.
    let method = h.state().shown().expect("shown").method;
    let slider = h
        .query_all_by_label("softness")
        .find(|n| n.accesskit_node().role() == egui::accesskit::Role::Slider)
        .expect("the softness slider");
    let serial = h.state().shown().map_or(0, |s| s.serial);
    slider.set_value_accesskit(4.0);
    assert!(
        step_until_gpu(&mut h, 20, |h| user::of(method)
            .is_some_and(|u| u.values()[2] == 4.0)
            && h.state().shown().is_some_and(|s| s.serial > serial)),
        "the slider did not set the knob and draw again"
    );
    step_until_gpu(&mut h, 5, |_| false);
    assert_ne!(
        visibility(&mut h),
        before,
        "softness 4 draws what softness 1 did"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A method whose trial frame does not finish on its own device (a shader that never ends, or
/// loses its device; here a 1 ms limit stands in for one, as lavapipe ends every loop) is
/// refused: opened, the lab keeps the method it showed; saved, the panel says why and the last
/// good version keeps drawing.
#[test]
fn a_method_whose_trial_frame_does_not_finish_leaves_the_lab_on_the_last_good_one() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("dbuffer-live-trial-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp folder");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let file = dir.join("trial.wgsl");
    let original = std::fs::read_to_string(root.join("examples/methods/pcss_variant.wgsl"))
        .expect("the example");
    std::fs::write(&file, &original).expect("copy");

    let mut h = support_lab::lab_sized(None, 900.0, 700.0);
    h.run();
    let shown = h.state().settings.method.clone();
    h.state_mut().set_trial_limit(Duration::from_millis(1));
    h.state_mut()
        .open_method(&root.join("tests/methods/endless.wgsl"));
    let status = h.state().status().0.to_owned();
    assert!(
        status.contains("trial frame did not finish") && status.contains("the lab keeps"),
        "{status}"
    );
    assert_eq!(h.state().settings.method, shown, "the lab switched");
    assert!(h.query_all_by_label("user-endless").next().is_none());

    // A good method opened, then a save whose trial does not finish.
    h.state_mut().set_trial_limit(Duration::from_secs(60));
    h.state_mut().open_method(&file);
    assert!(
        step_until_gpu(&mut h, 20, |h| h
            .state()
            .shown()
            .is_some_and(|s| s.method.name() == "user-trial")),
        "the good method was not shown: {:?}",
        h.state().status()
    );
    step_until_gpu(&mut h, 5, |_| false);
    let before = visibility(&mut h);
    h.state_mut().set_trial_limit(Duration::from_millis(1));
    save(&mut h, &file, &constant_v(&original));
    assert!(
        step_until_gpu(&mut h, 20, |h| !h.state().shader_errors().is_empty()),
        "no error shown"
    );
    let e = h.state().shader_errors()[0].clone();
    assert_eq!(e.file, file.display().to_string());
    assert!(e.message.contains("trial frame did not finish"), "{e}");
    assert_eq!(
        h.state().shader_reloads(),
        0,
        "the refused save was applied"
    );
    step_until_gpu(&mut h, 5, |_| false);
    assert_eq!(
        visibility(&mut h),
        before,
        "the last good version stopped drawing"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
