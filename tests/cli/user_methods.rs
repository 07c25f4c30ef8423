//! `--method file:PATH.wgsl` through the binary: the shipped example renders and `compare`
//! scores it under its name; `--knob` sets a user's knob; a file that cannot be a method is
//! refused before any work, in one line that names the user's file and the line in it, without
//! the advice to change adapters; so is a broken file of `DBUFFER_SHADER_DIR`'s folder.

use std::path::{Path, PathBuf};

use crate::support::{self as cli, dbuffer};

const EXAMPLE: &str = "file:examples/methods/dbuffer_vt.wgsl";

fn temp_dir(name: &str) -> PathBuf {
    cli::temp_dir("user-methods", name)
}

/// `dbuffer ARGS --out OUT` from the crate's root (the example's path is relative to it).
fn run(args: &[&str], out: &Path) -> std::process::Output {
    dbuffer()
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .expect("the binary runs")
}

#[test]
fn the_example_renders_and_compare_scores_it() {
    let dir = temp_dir("render");
    let o = run(
        &[
            "render",
            "fig7-concave",
            "--size",
            "48x48",
            "--method",
            EXAMPLE,
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let meta = std::fs::read_to_string(dir.join("meta.json")).expect("meta.json");
    assert!(meta.contains("\"user-dbuffer_vt\""), "{meta}");
    assert!(dir.join("visibility.exr").is_file() && dir.join("image.png").is_file());
    let _ = std::fs::remove_dir_all(&dir);

    let dir = temp_dir("compare");
    let o = run(
        &[
            "compare",
            "fig7-concave",
            "--size",
            "48x48",
            "--samples",
            "32",
            "--method",
            EXAMPLE,
        ],
        &dir,
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let row = stdout
        .lines()
        .find(|l| l.starts_with("| user-dbuffer_vt |"))
        .unwrap_or_else(|| panic!("no row for the user's method in:\n{stdout}"));
    // Its MAE column is a number: the method was scored against the reference.
    let mae: f64 = row
        .split('|')
        .nth(3)
        .unwrap_or("")
        .trim()
        .parse()
        .expect(row);
    assert!((0.0..0.05).contains(&mae), "{row}");
    for file in [
        "user-dbuffer_vt.png",
        "user-dbuffer_vt-visibility.exr",
        "report.json",
    ] {
        assert!(dir.join(file).is_file(), "{file} missing");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_pcss_variant_takes_its_knobs() {
    let dir = temp_dir("pcss-variant");
    let method = "file:examples/methods/pcss_variant.wgsl";
    let args = [
        "render",
        "fig7-concave",
        "--size",
        "32x32",
        "--method",
        method,
        "--knob",
        "taps=3",
        "--knob",
        "softness=1.5",
    ];
    let o = run(&args, &dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("visibility.exr").is_file());
    let _ = std::fs::remove_dir_all(&dir);
    let o = run(
        &[
            "render",
            "fig7-concave",
            "--method",
            method,
            "--knob",
            "taps=9",
        ],
        &dir,
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("--knob taps=9: taps takes 2 to 8 (examples/methods/pcss_variant.wgsl:8)"),
        "{stderr}"
    );
    assert!(!dir.exists());
}

/// `render` with `--method file:FILE` (FILE holding `text`, or absent for `None`) and `extra`
/// fails with one line on stderr containing every needle (and, where it names a line of FILE,
/// that line under it), leaving no folder.
fn refused(case: &str, text: Option<&str>, extra: &[&str], needles: &[&str]) {
    let src = std::env::temp_dir().join(format!("dbuffer-user-src-{}-{case}", std::process::id()));
    std::fs::create_dir_all(&src).expect("temp dir");
    let file = src.join(format!("{case}.wgsl"));
    if let Some(text) = text {
        std::fs::write(&file, text).expect("write");
    }
    let method = format!("file:{}", file.display());
    let dir = temp_dir(case);
    let mut args = vec![
        "render",
        "fig7-concave",
        "--size",
        "16x16",
        "--method",
        &method,
    ];
    args.extend(extra);
    let o = run(&args, &dir);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{case}: should fail");
    // One line, and under an error at a line of the file that line itself, indented.
    let lines: Vec<&str> = stderr.lines().collect();
    let quoted = text.and_then(|t| {
        let place = lines[0].strip_prefix(&format!("dbuffer: {}:", file.display()))?;
        let n: usize = place.split(':').next()?.parse().ok()?;
        t.lines().nth(n - 1)
    });
    match quoted {
        Some(line) => {
            assert_eq!(lines.len(), 2, "{case}: the line under it: {stderr}");
            assert_eq!(lines[1], format!("    {}", line.trim_end()), "{case}");
        }
        None => assert_eq!(lines.len(), 1, "{case}: one line: {stderr}"),
    }
    for needle in needles {
        let needle = needle.replace("FILE", &file.display().to_string());
        assert!(
            stderr.contains(&needle),
            "{case}: expected '{needle}' in: {stderr}"
        );
    }
    assert!(!stderr.contains("adapter"), "{case}: {stderr}");
    assert!(!dir.exists(), "{case}: left a folder behind");
    let _ = std::fs::remove_dir_all(&src);
}

const HEAD: &str = "// #include shared/camera.wgsl\n";
const VIS: &str =
    "fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility";

#[test]
fn a_file_that_cannot_be_a_method_is_refused_naming_its_line() {
    refused("missing", None, &[], &["cannot read the method file FILE"]);
    refused(
        "bad-knob",
        Some(&format!(
            "{HEAD}\n// knob: soft 0..1\n{VIS} {{ return plain(1.0); }}\n"
        )),
        &[],
        &["FILE:3: bad knob header `// knob: soft 0..1`"],
    );
    refused(
        "no-visibility",
        Some(&format!("{HEAD}fn other() {{}}\n")),
        &[],
        &["FILE: defines no `fn method_visibility"],
    );
    // Lines 4, column 24 of the user's file, not of the expanded shader.
    refused(
        "parse",
        Some(&format!("{HEAD}\n{VIS} {{\n    return plain(1.0) +;\n}}\n")),
        &[],
        &["FILE:4:24: expected expression"],
    );
    refused(
        "types",
        Some(&format!(
            "{HEAD}\n{VIS} {{\n    let a: f32 = 1u;\n    return plain(a);\n}}\n"
        )),
        &[],
        &["FILE:4:9: the type of `a` is expected to be `f32`"],
    );
    // naga's validator, after the parse: a function that may end without its return.
    refused(
        "validation",
        Some(&format!(
            "{HEAD}\nfn helper(a: f32) -> f32 {{\n    if a > 0.0 {{ return a; }}\n}}\n{VIS} {{\n    \
             return plain(helper(x.x));\n}}\n"
        )),
        &[],
        &["FILE:3:1: Function", "'helper' is invalid"],
    );
    refused(
        "group",
        Some(&format!(
            "{HEAD}@group(1) @binding(7) var tex: texture_2d<f32>;\n{VIS} {{\n    \
             return plain(textureLoad(tex, vec2<i32>(0), 0).x);\n}}\n"
        )),
        &[],
        &["FILE:2: declares `tex` at @group(1) @binding(7)"],
    );
    let knob = format!("{HEAD}// knob: soft 0..1 = 0.5\n{VIS} {{ return plain(knob_soft()); }}\n");
    refused(
        "knob-range",
        Some(&knob),
        &["--knob", "soft=2"],
        &["--knob soft=2: soft takes 0 to 1 (FILE:2), found 2"],
    );
    refused(
        "knob-name",
        Some(&knob),
        &["--knob", "hard=0"],
        &["has no knob `hard` (its knobs: soft)"],
    );
}

#[test]
fn knob_without_a_users_method_is_refused() {
    let dir = temp_dir("knob-alone");
    let o = run(
        &[
            "render",
            "fig7-concave",
            "--size",
            "16x16",
            "--knob",
            "soft=0.5",
        ],
        &dir,
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("--knob sets the knobs of a user's method"),
        "{stderr}"
    );
    assert!(!dir.exists());
}

/// `DBUFFER_SHADER_DIR` with a broken file: refused before any GPU work, naming the file in the
/// folder, its line and column, then the offending line itself; no advice about adapters.
#[test]
fn a_broken_file_of_the_shader_folder_names_its_line() {
    let dir = temp_dir("shader-dir");
    let shaders = dir.join("shaders");
    std::fs::create_dir_all(shaders.join("methods")).expect("folder");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/methods/vsm.wgsl"),
    )
    .expect("vsm.wgsl");
    let line = text
        .lines()
        .position(|l| l.starts_with("fn method_visibility"))
        .expect("its V")
        + 2;
    let mut lines: Vec<&str> = text.lines().collect();
    lines.insert(line - 1, "    let oops = ;");
    let file = shaders.join("methods/vsm.wgsl");
    std::fs::write(&file, lines.join("\n")).expect("write");
    let o = dbuffer()
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("DBUFFER_SHADER_DIR", &shaders)
        .args([
            "render",
            "fig7-concave",
            "--size",
            "16x16",
            "--method",
            "vsm",
        ])
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    let place = format!("dbuffer: {}:{line}:16: expected expression", file.display());
    assert!(lines[0].starts_with(&place), "{stderr}");
    // The line as written (its own indent), under the headline indented by four.
    assert_eq!(
        lines.get(1).copied(),
        Some("        let oops = ;"),
        "{stderr}"
    );
    assert!(!stderr.contains("what you can do"), "{stderr}");
    assert!(!dir.join("out").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `gui --shaders` takes a folder, checked before a window opens.
#[test]
fn gui_shaders_must_be_a_folder() {
    let missing = temp_dir("no-such-folder");
    let o = dbuffer()
        .args(["gui", "--shaders"])
        .arg(&missing)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    assert_eq!(
        stderr.trim_end(),
        format!("dbuffer: --shaders {}: not a folder", missing.display()),
    );
}

/// `study --methods` takes a user's file like a registry name: the D-buffer example's cell
/// scores as `dbuffer`'s at the same map size (its images are equal), a second run takes it
/// from the cache, an edit to the file measures it again (its key holds the shader, not only
/// the name), and `--knob` without a user's method is refused before any work.
#[test]
fn study_measures_a_users_file_and_remeasures_it_when_edited() {
    let dir = temp_dir("study");
    std::fs::create_dir_all(&dir).expect("temp dir made");
    let file = dir.join("mine.wgsl");
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/methods/dbuffer_vt.wgsl");
    let text = std::fs::read_to_string(&example).expect("the example is in the repository");
    std::fs::write(&file, &text).expect("temp file written");
    let out = dir.join("out");
    let study = |extra: &[&str]| {
        let o = dbuffer()
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args([
                "study",
                "--quick",
                "--scenes",
                "fig7-concave",
                "--size",
                "48x48",
            ])
            .args(extra)
            .arg("--out")
            .arg(&out)
            .output()
            .expect("the binary runs");
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        (o.status.success(), stderr)
    };
    let methods = format!("dbuffer,file:{}", file.display());
    let read = || -> dbuffer::study::Study {
        let json = std::fs::read(out.join("study.json")).expect("study.json written");
        serde_json::from_slice(&json).expect("study.json parses")
    };
    let (ok, stderr) = study(&["--methods", &methods]);
    assert!(ok, "{stderr}");
    let first = read();
    let cells = &first.scenes[0].cells;
    let mine = cells
        .iter()
        .find(|c| c.method == "user-mine")
        .unwrap_or_else(|| panic!("no user-mine cell: {cells:?}"));
    let error = mine.error.expect("the user's cell has an error");
    assert!(mine.cost.is_some(), "and a cost: {mine:?}");
    let twin = cells
        .iter()
        .find(|c| c.method == "dbuffer" && c.map_size == mine.map_size)
        .unwrap_or_else(|| panic!("a dbuffer cell at {}²: {cells:?}", mine.map_size));
    let twin_error = twin.error.expect("dbuffer's cell has an error");
    assert_eq!(
        (
            error.mae.to_bits(),
            error.penumbra_mae.to_bits(),
            error.p99.to_bits()
        ),
        (
            twin_error.mae.to_bits(),
            twin_error.penumbra_mae.to_bits(),
            twin_error.p99.to_bits()
        ),
        "the D-buffer example scores as dbuffer: {error:?} against {twin_error:?}"
    );
    // Listed after the registry's methods.
    assert_eq!(cells.last().map(|c| c.method.as_str()), Some("user-mine"));

    let (ok, stderr) = study(&["--methods", &methods]);
    assert!(ok, "{stderr}");
    assert!(
        read().scenes[0].cells.iter().all(|c| c.cached),
        "all from the cache"
    );

    std::fs::write(&file, format!("{text}\n// edited\n")).expect("file edited");
    let (ok, stderr) = study(&["--methods", &methods]);
    assert!(ok, "{stderr}");
    for c in &read().scenes[0].cells {
        assert_eq!(
            c.cached,
            c.method != "user-mine",
            "only the edited file's cell is measured again: {c:?}"
        );
    }

    let (ok, stderr) = study(&["--methods", "dbuffer", "--knob", "k=1"]);
    assert!(!ok, "--knob without a user's method is refused");
    assert!(stderr.contains("--knob k=1"), "{stderr}");
}

/// A user's method whose loop never takes its exit: `render` does not hang. On a CPU rasteriser
/// the loop runs as long as the driver lets it (lavapipe ends an invocation's loops after about
/// 65,535 steps), so the frame takes seconds where it should take milliseconds; on a GPU the
/// driver loses the device. Either way the command ends with one message naming the method's
/// file, no advice to change adapters, and a failing status — here by the watchdog at the
/// limit `DBUFFER_GPU_TIMEOUT_S` sets.
#[test]
fn a_shader_that_does_not_end_stops_render_with_a_message() {
    let dir = temp_dir("endless");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/methods/endless.wgsl");
    let method = format!("file:{}", file.display());
    let o = dbuffer()
        .env("DBUFFER_GPU_TIMEOUT_S", "0.5")
        .args([
            "render",
            "fig7-concave",
            "--size",
            "512x512",
            "--method",
            &method,
        ])
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success(),
        "a frame that does not end fails render"
    );
    assert!(
        stderr.contains(&format!("a frame of user-endless ({})", file.display())),
        "names the method and its file: {stderr}"
    );
    assert!(
        stderr.contains("did not finish") || stderr.contains("device was lost"),
        "{stderr}"
    );
    assert!(!stderr.contains("what you can do"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// The traced example (`scene_occluded` through the scene's BVH, an 8 × 8 grid over the light)
/// scores well under PCSS on a disk and on a polygon light: rays against the real casters.
#[test]
fn the_traced_example_scores_under_pcss() {
    for scene in ["fig7-concave", "polygon-triangle"] {
        let dir = temp_dir(&format!("traced-{scene}"));
        let o = run(
            &[
                "compare",
                scene,
                "--size",
                "64x64",
                "--methods",
                "pcss,file:examples/methods/traced.wgsl",
                "--knob",
                "grid=8",
            ],
            &dir,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json = std::fs::read(dir.join("report.json")).expect("report.json written");
        let report: dbuffer::compare::report::Report =
            serde_json::from_slice(&json).expect("report.json parses");
        let mae = |m: &str| {
            report
                .methods
                .iter()
                .find(|r| r.method == m)
                .unwrap_or_else(|| panic!("{scene}: no {m} row"))
                .penumbra_mae
        };
        let (traced, pcss) = (mae("user-traced"), mae("pcss"));
        assert!(
            traced < 0.5 * pcss && traced < 0.03,
            "{scene}: traced {traced} against pcss {pcss}"
        );
    }
}
