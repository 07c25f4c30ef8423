//! `dbuffer render` end to end, through the binary: every output written and readable; bad input
//! exits non-zero with a one-line reason and leaves no half-written folder.

use std::path::{Path, PathBuf};

use dbuffer::output::{self, read_exr_rgba};

use crate::support::{self as cli, dbuffer};

fn temp_dir(name: &str) -> PathBuf {
    cli::temp_dir("render-cli", name)
}

#[test]
fn compare_writes_the_report_and_prints_the_table() {
    let dir = temp_dir("compare");
    let out = dbuffer()
        .args([
            "compare",
            "table1-224",
            "--size",
            "48x40",
            "--samples",
            "16",
            "--lights",
            "4",
        ])
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("the binary runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for method in dbuffer::render::Method::all() {
        assert!(
            stdout.contains(&format!("| {method} |")),
            "{method} row: {stdout}"
        );
        // A method that needs the other kind of light is listed, not drawn.
        let drawn = method.takes(dbuffer::scene::LightKind::Disk);
        assert_eq!(
            dir.join(format!("{method}.png")).is_file(),
            drawn,
            "{method}"
        );
        assert_eq!(
            dir.join(format!("{method}-visibility.exr")).is_file(),
            drawn,
            "{method}"
        );
        if !drawn {
            assert!(
                stdout.contains(&format!("| {method} | n/a — needs a line light |")),
                "{stdout}"
            );
        }
    }
    assert!(dir.join("pcss-error.png").is_file());
    assert!(dir.join("report.md").is_file() && dir.join("report.json").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `compare --orbit`: the temporal table printed, a plot per method and the APNG written, K
/// 256 by default; a bad `--orbit` or `--frames` refused in one line before any work.
#[test]
fn compare_orbit_writes_the_motion_and_refuses_bad_flags() {
    let dir = temp_dir("compare-orbit");
    let out = dbuffer()
        .args([
            "compare",
            "table1-224",
            "--size",
            "32x24",
            "--orbit",
            "light",
            "--frames",
            "3",
        ])
        .arg("--out")
        .arg(&dir)
        .output()
        .expect("the binary runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("in motion (light orbit, 3 frames, reference K = 256)"),
        "{stdout}"
    );
    assert!(stdout.contains("| dbuffer | 0."), "{stdout}");
    assert!(dir.join("dbuffer-temporal.png").is_file());
    assert!(dir.join("motion.png").is_file());
    assert!(dir.join("dbuffer-flip.png").is_file() && dir.join("pcss-cost.png").is_file());
    let _ = std::fs::remove_dir_all(&dir);
    for (flags, says) in [
        (
            ["--orbit", "wobble", "--frames", "4"],
            "--orbit expects light or camera",
        ),
        (
            ["--orbit", "light", "--frames", "1"],
            "--frames expects 2 to",
        ),
        (
            ["--orbit", "light", "--frames", "100000"],
            "MAX_ORBIT_FRAMES",
        ),
    ] {
        let bad = temp_dir("compare-orbit-bad");
        let out = dbuffer()
            .args(["compare", "table1-224"])
            .args(flags)
            .arg("--out")
            .arg(&bad)
            .output()
            .expect("the binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{flags:?}");
        assert!(stderr.contains(says), "{flags:?}: {stderr}");
        assert!(!bad.exists(), "{flags:?}: nothing written");
    }
}

#[test]
fn every_method_renders_from_the_command_line() {
    for method in dbuffer::render::Method::all() {
        let dir = temp_dir(&format!("method-{method}"));
        // Each on a scene with a light it takes.
        let scene = if method.takes(dbuffer::scene::LightKind::Disk) {
            "table1-224"
        } else {
            "line-fig2"
        };
        let out = dbuffer()
            .args(["render", scene, "--size", "40x32", "--samples", "8"])
            .args(["--method", method.name(), "--out"])
            .arg(&dir)
            .output()
            .expect("the binary runs");
        assert!(
            out.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let meta: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("meta.json")).expect("meta.json"))
                .expect("json");
        assert_eq!(meta["method"], method.name());
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// Without `--method` a scene gets the method made for its light: the D-buffer under a disk,
/// `linear-ssm` under a line (a named disk-only method is still refused there).
#[test]
fn the_default_method_follows_the_light() {
    for (scene, expected) in [("table1-224", "dbuffer"), ("line-fig2", "linear-ssm")] {
        let dir = temp_dir(&format!("default-{scene}"));
        let out = dbuffer()
            .args(["render", scene, "--size", "40x32", "--out"])
            .arg(&dir)
            .output()
            .expect("the binary runs");
        assert!(
            out.status.success(),
            "{scene}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let meta: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("meta.json")).expect("meta.json"))
                .expect("json");
        assert_eq!(meta["method"], expected, "{scene}");
        let _ = std::fs::remove_dir_all(&dir);
    }
    let dir = temp_dir("default-refused");
    fails_with(
        &[
            "render",
            "line-fig2",
            "--size",
            "40x32",
            "--method",
            "dbuffer",
        ],
        &dir,
        "needs a disk, rect or polygon light",
    );
}

#[test]
fn render_writes_every_output() {
    let dir = temp_dir("ok");
    let out = dbuffer()
        .args([
            "render",
            "fig7-concave",
            "--size",
            "96x64",
            "--dbuffer-size",
            "256",
            "--vt",
            "exact",
            "-v",
            "--out",
        ])
        .arg(&dir)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("adapter"),
        "-v prints the adapter: {stderr}"
    );
    for name in output::FILE_NAMES {
        assert!(dir.join(name).is_file(), "{name} missing");
    }
    let image = image::open(dir.join("image.png")).expect("image.png reads");
    assert_eq!((image.width(), image.height()), (96, 64));
    let (w, h, v) = read_exr_rgba(&dir.join("visibility.exr")).expect("visibility.exr reads");
    assert_eq!((w, h), (96, 64));
    let hit = v.iter().filter(|p| p[3] == 1.0).count();
    let shadow = v.iter().filter(|p| p[3] == 1.0 && p[0] < 0.5).count();
    assert!(
        hit > 3000 && shadow > 50,
        "{hit} pixels hit, {shadow} in shadow"
    );
    assert!(v.iter().all(|p| (0.0..=1.0).contains(&p[0])));
    let (dw, dh, d) = read_exr_rgba(&dir.join("dbuffer.exr")).expect("dbuffer.exr reads");
    assert_eq!((dw, dh), (256, 256));
    assert!(
        d.iter().any(|t| t[1] > 0.0) && d.iter().any(|t| t[2] > 0.0),
        "the volumes reached the D-buffer"
    );
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("meta.json")).expect("meta.json"))
            .expect("json");
    assert_eq!(meta["scene"], "fig7-concave");
    assert_eq!(meta["variant"], "exact");
    assert!(meta["adapter"].as_str().is_some_and(|a| !a.is_empty()));
    assert!(meta["cpu_ms"]["geometry_volumes"].as_f64().is_some());
    let _ = std::fs::remove_dir_all(&dir);
}

fn fails_with(args: &[&str], dir: &Path, needle: &str) {
    let out = dbuffer()
        .args(args)
        .arg("--out")
        .arg(dir)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} should fail");
    assert!(
        stderr.contains(needle),
        "{args:?}: expected '{needle}' in: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    assert!(!dir.exists(), "{args:?} left a folder behind");
}

#[test]
fn bad_input_is_refused_with_a_reason() {
    let dir = temp_dir("bad");
    fails_with(&["render", "no-such-scene"], &dir, "no-such-scene");
    fails_with(
        &["render", "fig7-concave", "--size", "0x10"],
        &dir,
        "--size",
    );
    fails_with(
        &["render", "fig7-concave", "--size", "banana"],
        &dir,
        "--size",
    );
    fails_with(
        &["render", "fig7-concave", "--method", "magic"],
        &dir,
        "unknown method 'magic'",
    );
    fails_with(
        &["render", "fig7-concave", "--vt", "cubic"],
        &dir,
        "unknown V(t) variant 'cubic'",
    );
    fails_with(
        &["render", "fig7-concave", "--dbuffer-size", "0"],
        &dir,
        "--dbuffer-size",
    );
    // The knobs of the comparison methods, on both commands that take them.
    for command in ["render", "compare"] {
        for (flag, value) in [
            ("--pcf-radius", "9"),
            ("--blocker-taps", "0"),
            ("--filter-taps", "65"),
            ("--lights", "0"),
            ("--lights", "65"),
            ("--samples", "0"),
        ] {
            fails_with(&[command, "fig7-concave", flag, value], &dir, flag);
        }
        fails_with(
            &[command, "fig7-concave", "--lights", "many"],
            &dir,
            "--lights",
        );
    }
    fails_with(
        &["compare", "fig7-concave", "--size", "0x0"],
        &dir,
        "--size",
    );
    fails_with(&["compare", "fig7-concave", "--vt", "cubic"], &dir, "cubic");
    fails_with(&["compare", "no-such-scene"], &dir, "no-such-scene");
    let bad_scene = std::env::temp_dir().join(format!("dbuffer-bad-{}.toml", std::process::id()));
    let text = "[camera]\neye = [0, 3, 6]\ntarget = [0, 0, 0]\nfov_y_deg = 45\n\n\
                [light]\ncenter = [0, 4, 0]\nnormal = [0, -1, 0]\nradius = 0\n\n\
                [[object]]\nmesh = \"cube\"\n";
    std::fs::write(&bad_scene, text).expect("write");
    fails_with(
        &["render", bad_scene.to_str().expect("utf-8")],
        &dir,
        "radius",
    );
    let _ = std::fs::remove_file(&bad_scene);
}

/// A method that cannot take the scene's light exits non-zero with one line naming the method
/// and the light kind, and writes nothing.
#[test]
fn a_disk_method_refuses_a_line_light_in_one_line() {
    for (scene, method, needs) in [
        (
            "line-fig2",
            "dbuffer",
            "needs a disk, rect or polygon light",
        ),
        ("line-fig2", "wedges", "needs a disk, rect or polygon light"),
        ("line-fig2", "pcss", "needs a disk, rect or polygon light"),
        ("table1-224", "linear-ssm", "needs a line light"),
        // A polygon or rectangle is no line: linear-ssm refuses it in the same one line.
        (
            "polygon-triangle",
            "linear-ssm",
            "a polygon (kind = \"polygon\")",
        ),
        ("rect-strip", "linear-ssm", "a rect (kind = \"rect\")"),
    ] {
        let dir = temp_dir(&format!("refused-{method}"));
        let out = dbuffer()
            .args([
                "render", scene, "--size", "40x32", "--method", method, "--out",
            ])
            .arg(&dir)
            .output()
            .expect("the binary runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{method} on {scene} must fail");
        assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
        assert!(
            err.contains(&format!("method '{method}'")) && err.contains(needs),
            "{err}"
        );
        assert!(
            !dir.join("image.png").exists(),
            "nothing written for a refused method"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
