//! Tests of `support/snapshot.rs` on synthetic images in a temporary directory (never in
//! `tests/snapshots/`).

use crate::support::snapshot;

use std::path::{Path, PathBuf};

use snapshot::{check_snapshot_in, load_tolerance, Outcome, Update};

const W: u32 = 32;
const H: u32 = 32;

/// A fresh temporary snapshot directory with the standard tolerance file.
fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dbuffer-snapshot-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(
        dir.join("tolerance.toml"),
        "per_channel = 8\nmax_failing_fraction = 0.005\n\n[overrides.loose]\nmax_failing_fraction = 0.1\n",
    )
    .expect("write tolerance");
    dir
}

/// A smooth gradient with some alpha, so dimming and channels are all exercised.
fn gradient() -> Vec<u8> {
    let mut px = Vec::with_capacity((W * H * 4) as usize);
    for y in 0..H {
        for x in 0..W {
            px.extend_from_slice(&[(x * 8) as u8, (y * 8) as u8, 128, 200 + (x % 8) as u8]);
        }
    }
    px
}

fn save(dir: &Path, name: &str, rgba8: &[u8]) {
    image::save_buffer(
        dir.join(format!("{name}.png")),
        rgba8,
        W,
        H,
        image::ExtendedColorType::Rgba8,
    )
    .expect("save reference");
}

fn load(path: &Path) -> image::RgbaImage {
    image::open(path).expect("open png").to_rgba8()
}

/// `image` with the block of pixels [x0, x0 + n) × [y0, y0 + n) set to white.
fn with_block(mut px: Vec<u8>, x0: u32, y0: u32, n: u32) -> Vec<u8> {
    for y in y0..y0 + n {
        for x in x0..x0 + n {
            let i = ((y * W + x) * 4) as usize;
            px[i..i + 4].copy_from_slice(&[255, 255, 255, 255]);
        }
    }
    px
}

#[test]
fn identical_images_pass() {
    let dir = temp_dir("identical");
    save(&dir, "img", &gradient());
    let outcome = check_snapshot_in(&dir, "img", W, H, &gradient(), Update::No).expect("passes");
    assert_eq!(
        outcome,
        Outcome::Matched {
            failing: 0,
            max_diff: 0
        }
    );
    assert!(!dir.join("img.new.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn noise_under_tolerance_passes() {
    let dir = temp_dir("noise");
    save(&dir, "img", &gradient());
    // Every channel of every pixel off by up to 7 (a fixed pseudo-random pattern) ...
    let mut noisy = gradient();
    let mut state = 12345u32;
    for c in noisy.iter_mut() {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        let delta = (state >> 24) % 15; // 0..=14, centred on 7
        *c = (i32::from(*c) + delta as i32 - 7).clamp(0, 255) as u8;
    }
    // ... and 5 of 1024 pixels (0.49 %, under 0.5 %) completely wrong.
    for i in 0..5 {
        let p = (i * 200 * 4) as usize;
        noisy[p..p + 4].copy_from_slice(&[0, 255, 0, 0]);
    }
    match check_snapshot_in(&dir, "img", W, H, &noisy, Update::No).expect("passes") {
        Outcome::Matched { failing, max_diff } => {
            assert_eq!(failing, 5);
            assert_eq!(max_diff, 255);
        }
        other => panic!("expected a match, got {other:?}"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_changed_block_fails_and_writes_new_and_diff_images() {
    let dir = temp_dir("block");
    save(&dir, "img", &gradient());
    let changed = with_block(gradient(), 4, 8, 6);
    let report = check_snapshot_in(&dir, "img", W, H, &changed, Update::No).expect_err("fails");
    assert!(
        report.contains("36 of 1024 pixels (3.516%) differ by more than 8"),
        "{report}"
    );
    // The block is white over a gradient whose darkest red there is 32.
    assert!(report.contains("max channel difference 223"), "{report}");
    assert!(report.contains("UPDATE_SNAPSHOTS=1"), "{report}");

    assert_eq!(load(&dir.join("img.new.png")).as_raw(), &changed);
    let diff = load(&dir.join("img.diff.png"));
    assert_eq!(
        diff.get_pixel(5, 9).0,
        [255, 0, 0, 255],
        "inside the block: red"
    );
    let outside = diff.get_pixel(20, 20).0;
    assert_ne!(outside, [255, 0, 0, 255], "outside the block: not red");
    assert!(
        outside[0] < 60 && outside[3] == 255,
        "outside: dimmed, opaque: {outside:?}"
    );
    // The snapshot itself is untouched.
    assert_eq!(load(&dir.join("img.png")).as_raw(), &gradient());

    // Passing again removes the failure's leftovers.
    check_snapshot_in(&dir, "img", W, H, &gradient(), Update::No).expect("passes");
    assert!(!dir.join("img.new.png").exists() && !dir.join("img.diff.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn overrides_in_the_tolerance_file_apply_to_their_snapshot() {
    let dir = temp_dir("override");
    save(&dir, "loose", &gradient());
    let changed = with_block(gradient(), 4, 8, 6); // 3.5 % failing: under loose's 10 %
    check_snapshot_in(&dir, "loose", W, H, &changed, Update::No).expect("passes");
    let t = load_tolerance(&dir, "loose").expect("tolerance");
    assert_eq!((t.per_channel, t.max_failing_fraction), (8, 0.1));
    let t = load_tolerance(&dir, "other").expect("tolerance");
    assert_eq!((t.per_channel, t.max_failing_fraction), (8, 0.005));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_missing_snapshot_fails_with_the_hint() {
    let dir = temp_dir("missing");
    let report = check_snapshot_in(&dir, "img", W, H, &gradient(), Update::No).expect_err("fails");
    assert!(report.contains("does not exist"), "{report}");
    assert!(report.contains("UPDATE_SNAPSHOTS=1"), "{report}");
    assert!(
        !dir.join("img.png").exists(),
        "no snapshot is written without UPDATE"
    );
    assert!(
        dir.join("img.new.png").exists(),
        "the rendered image is there to look at"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn update_mode_writes_missing_and_failing_snapshots() {
    let dir = temp_dir("update");
    let out = check_snapshot_in(&dir, "img", W, H, &gradient(), Update::Failing).expect("passes");
    assert_eq!(out, Outcome::Written);
    assert_eq!(load(&dir.join("img.png")).as_raw(), &gradient());

    // A failing image is written over the snapshot, and the test passes.
    let changed = with_block(gradient(), 0, 0, 8);
    let out = check_snapshot_in(&dir, "img", W, H, &changed, Update::Failing).expect("passes");
    assert_eq!(out, Outcome::Written);
    assert_eq!(load(&dir.join("img.png")).as_raw(), &changed);
    check_snapshot_in(&dir, "img", W, H, &changed, Update::No).expect("now matches");

    // An image within tolerance leaves the snapshot alone (no churn) ...
    let mut close = changed.clone();
    close[3 * 4 * 40] ^= 1;
    let out = check_snapshot_in(&dir, "img", W, H, &close, Update::Failing).expect("passes");
    assert!(matches!(out, Outcome::Matched { .. }), "{out:?}");
    assert_eq!(load(&dir.join("img.png")).as_raw(), &changed);
    // ... unless forced.
    let out = check_snapshot_in(&dir, "img", W, H, &close, Update::Force).expect("passes");
    assert_eq!(out, Outcome::Written);
    assert_eq!(load(&dir.join("img.png")).as_raw(), &close);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_size_change_fails() {
    let dir = temp_dir("size");
    save(&dir, "img", &gradient());
    let small = vec![0u8; 16 * 16 * 4];
    let report = check_snapshot_in(&dir, "img", 16, 16, &small, Update::No).expect_err("fails");
    assert!(
        report.contains("is 32x32 but the image is 16x16"),
        "{report}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_input_and_bad_config_are_reported() {
    let dir = temp_dir("bad");
    save(&dir, "img", &gradient());
    let report = check_snapshot_in(&dir, "img", W, H, &[0; 7], Update::No).expect_err("bad len");
    assert!(
        report.contains("7 bytes is not a 32x32 RGBA8 image"),
        "{report}"
    );
    let report =
        check_snapshot_in(&dir, "../img", W, H, &gradient(), Update::No).expect_err("bad name");
    assert!(report.contains("snapshot name"), "{report}");

    std::fs::write(
        dir.join("tolerance.toml"),
        "per_channel = 8\nmax_fail = 0.1\n",
    )
    .expect("w");
    let report = check_snapshot_in(&dir, "img", W, H, &gradient(), Update::No).expect_err("toml");
    assert!(report.contains("tolerance.toml"), "{report}");
    std::fs::remove_file(dir.join("tolerance.toml")).expect("rm");
    let report = check_snapshot_in(&dir, "img", W, H, &gradient(), Update::No).expect_err("none");
    assert!(report.contains("max_failing_fraction = 0.005"), "{report}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn update_snapshots_values() {
    for (value, update) in [
        (None, Update::No),
        (Some(""), Update::No),
        (Some("0"), Update::No),
        (Some("false"), Update::No),
        (Some("1"), Update::Failing),
        (Some("yes"), Update::Failing),
        (Some("force"), Update::Force),
    ] {
        assert_eq!(Update::from_value(value), update, "{value:?}");
    }
}

#[test]
fn the_project_tolerance_file_parses() {
    let t =
        load_tolerance(&snapshot::snapshot_dir(), "any").expect("tests/snapshots/tolerance.toml");
    assert!(
        t.max_failing_fraction <= 0.01,
        "keep snapshot thresholds tight: {t:?}"
    );
}
