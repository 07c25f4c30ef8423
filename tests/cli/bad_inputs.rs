//! Hostile files and extreme sizes, through the binary: every case exits with the
//! status it should, names what it should in one line on stderr, never panics, and never runs
//! long (each is killed after a minute: a FIFO that blocked or /dev/zero read to the end of
//! memory fails here instead of hanging the suite). Library-level cases follow the table.
//!
//! Each case failed before the fix; how is said next to it.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use dbuffer::budget;
use dbuffer::scene::{self, SceneFile};

use crate::support::{self as cli, dbuffer};

const CAMERA: &str =
    "[camera]\neye = [0.0, 3.0, 6.0]\ntarget = [0.0, 0.5, 0.0]\nfov_y_deg = 45.0\n";
const LIGHT: &str = "[light]\ncenter = [0.0, 4.0, 0.0]\nnormal = [0.0, -1.0, 0.0]\nradius = 0.5\n";
const GROUND: &str = "[[object]]\nmesh = \"plane\"\nscale = 10.0\ncasts_shadow = false\n";

/// A scene file: the camera, the light, a ground and `objects` (TOML `[[object]]` tables).
fn scene_with(objects: &str) -> String {
    format!("{CAMERA}\n{LIGHT}\n{GROUND}\n{objects}")
}

fn object(mesh: &str) -> String {
    format!("[[object]]\nmesh = \"{mesh}\"\ntranslate = [0, 1, 0]\n")
}

/// A fresh folder for one case, removed when the case ends.
struct CaseDir(PathBuf);

impl std::ops::Deref for CaseDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for CaseDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for CaseDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn case_dir(name: &str) -> CaseDir {
    let dir = cli::temp_dir("bad-inputs", name);
    std::fs::create_dir_all(&dir).expect("case dir");
    CaseDir(dir)
}

/// What a run of the binary left.
struct Run {
    status: ExitStatus,
    stdout: String,
    stderr: String,
}

/// Runs `cmd`, killing it after a minute (then the case fails: it hung or read without end).
fn run(mut cmd: Command) -> Run {
    cmd.stdout(Stdio::piped()).stderr(Stdio::piped());
    let child = cmd.spawn().expect("the binary starts");
    finish(child, Duration::from_secs(60))
}

fn finish(mut child: Child, limit: Duration) -> Run {
    let mut out = child.stdout.take();
    let mut err = child.stderr.take();
    // Read both pipes on threads so a chatty child cannot block on a full pipe.
    let read = |p: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut s = Vec::new();
            if let Some(mut p) = p {
                let _ = p.read_to_end(&mut s);
            }
            String::from_utf8_lossy(&s).into_owned()
        })
    };
    let out_t = read(out.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    let err_t = read(err.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    // Wait for the exit on a thread of its own, so the wait itself has a time limit.
    let pid = child.id();
    let (exited, exit) = mpsc::channel();
    let waiter = std::thread::spawn(move || {
        let _ = exited.send(child.wait());
    });
    let status = match exit.recv_timeout(limit) {
        Ok(status) => status.expect("wait"),
        Err(_) => {
            // SAFETY: kill(2) only sends a signal. The child ran past the limit, so the waiter
            // has not reaped it and `pid` is still the child's (one exiting at this very moment
            // is reaped a moment before; Linux does not hand its pid out again that soon).
            unsafe { libc::kill(pid as libc::pid_t, libc::SIGKILL) };
            let _ = waiter.join();
            panic!("still running after {limit:?}: it hung (or read without end)");
        }
    };
    Run {
        status,
        stdout: out_t.join().unwrap_or_default(),
        stderr: err_t.join().unwrap_or_default(),
    }
}

/// The run failed cleanly: exit status 1, one line on stderr starting `dbuffer: ` that has
/// every part of `has` and none of `lacks`, and no panic.
fn assert_refused(what: &str, r: &Run, has: &[&str], lacks: &[&str]) {
    assert_eq!(
        r.status.code(),
        Some(1),
        "{what}: status {:?}\nstderr: {}\nstdout: {}",
        r.status,
        r.stderr,
        r.stdout
    );
    assert!(!r.stderr.contains("panicked"), "{what}: {}", r.stderr);
    let line = r
        .stderr
        .lines()
        .find(|l| l.starts_with("dbuffer: "))
        .unwrap_or_else(|| panic!("{what}: no error line in {:?}", r.stderr));
    assert_eq!(
        r.stderr
            .lines()
            .filter(|l| l.starts_with("dbuffer: "))
            .count(),
        1,
        "{what}: {}",
        r.stderr
    );
    for part in has {
        assert!(line.contains(part), "{what}: {part:?} missing from\n{line}");
    }
    for part in lacks {
        assert!(!line.contains(part), "{what}: {part:?} in\n{line}");
    }
}

fn inspect(dir: &Path, args: &[&str]) -> Run {
    let mut c = dbuffer();
    c.current_dir(dir).arg("inspect").args(args);
    run(c)
}

fn mkfifo(path: &Path) -> bool {
    Command::new("mkfifo")
        .arg(path)
        .status()
        .is_ok_and(|s| s.success())
}

// ---------------------------------------------------------------------------------------------
// 1. The budget: refused before allocating, naming the limit and the key or flag.

/// Before: 5 × sphere:2000x1000 loaded (20M triangles, ~2 GB, several seconds) and inspect
/// went on; 20 of them took 7.8 GB.
#[test]
fn shapes_over_the_triangle_budget_are_refused_from_their_parameters() {
    let dir = case_dir("shapes-budget");
    let objects: String = (0..5).map(|_| object("sphere:2000x1000")).collect();
    std::fs::write(dir.join("scene.toml"), scene_with(&objects)).unwrap();
    let r = inspect(&dir, &["scene.toml"]);
    assert_refused(
        "5 big spheres",
        &r,
        &[
            "scene.toml",
            "object[5].mesh",
            "sphere:2000x1000",
            "3996000 triangles",
            "16777216",
            "MAX_SCENE_TRIANGLES",
        ],
        &[],
    );
    // One shape past its own limit names it too.
    std::fs::write(dir.join("one.toml"), scene_with(&object("torus:2001x1000"))).unwrap();
    let r = inspect(&dir, &["one.toml"]);
    assert_refused(
        "torus 2001x1000",
        &r,
        &["object[1].mesh", "MAX_SHAPE_QUADS"],
        &[],
    );
}

/// Before: `inspect --samples 1000000000` aborted on a 12 GB allocation (signal, no message);
/// --size, --dbuffer-size and a too-long side were refused without the limit's name, or (the
/// side) not at all until the GPU failed.
#[test]
fn flags_over_the_budget_name_the_limit() {
    let dir = case_dir("flags");
    let cases: &[(&[&str], &[&str])] = &[
        (
            &["inspect", "fig7-concave", "--samples", "1000000000"],
            &["--samples", "65536", "MAX_REFERENCE_SAMPLES"],
        ),
        (
            &[
                "inspect",
                "fig7-concave",
                "--samples",
                "1",
                "--size",
                "4096x4096",
            ],
            &["--size", "MAX_INSPECT_PIXELS"],
        ),
        (
            &[
                "render",
                "fig7-concave",
                "--out",
                "o",
                "--dbuffer-size",
                "9000",
            ],
            &["--dbuffer-size", "8192", "MAX_DBUFFER_SIZE"],
        ),
        (
            &[
                "render",
                "fig7-concave",
                "--out",
                "o",
                "--size",
                "20000x100",
            ],
            &["--size", "MAX_IMAGE_SIDE"],
        ),
        (
            &[
                "render",
                "fig7-concave",
                "--out",
                "o",
                "--size",
                "16384x8192",
            ],
            &["--size", "MAX_IMAGE_PIXELS"],
        ),
        (
            &["render", "fig7-concave", "--out", "o", "--samples", "65537"],
            &["--samples", "MAX_REFERENCE_SAMPLES"],
        ),
        // What compare and animate hold a pixel: their own limits, from the flags.
        (
            &[
                "compare",
                "fig7-concave",
                "--out",
                "o",
                "--size",
                "8192x8192",
            ],
            &["--size 8192x8192", "16777216", "MAX_COMPARE_PIXELS"],
        ),
        (
            &[
                "compare",
                "fig7-concave",
                "--out",
                "o",
                "--orbit",
                "light",
                "--size",
                "4097x4096",
            ],
            &["--size 4097x4096", "MAX_COMPARE_PIXELS"],
        ),
        (
            &[
                "animate",
                "fig7-concave",
                "--out",
                "o",
                "--size",
                "5000x4000",
            ],
            &["--size 5000x4000", "16777216", "MAX_ANIMATE_PIXELS"],
        ),
    ];
    for (args, has) in cases {
        let mut c = dbuffer();
        c.current_dir(&dir).args(*args);
        let r = run(c);
        assert_refused(&args.join(" "), &r, has, &[]);
        assert!(!dir.join("o").exists(), "{args:?} created --out");
    }
}

/// Before: a scene file was read whole whatever its size.
#[test]
fn a_scene_file_over_its_budget_is_not_read() {
    let dir = case_dir("big-scene");
    let mut text = scene_with("");
    let pad = "#".repeat(1000) + "\n";
    while text.len() as u64 <= budget::MAX_SCENE_FILE_BYTES {
        text.push_str(&pad);
    }
    std::fs::write(dir.join("big.toml"), text).unwrap();
    let r = inspect(&dir, &["big.toml"]);
    assert_refused(
        "a 1 MiB scene",
        &r,
        &["big.toml", "MAX_SCENE_FILE_BYTES", "1 MiB"],
        &[],
    );
}

/// Before: the OBJ was read and parsed whole, then the scene was too large for the GPU.
/// The shapes' count is known first, so the file is refused at the face that passes what they
/// leave, before a shape is built.
#[test]
fn an_obj_over_what_the_scene_leaves_is_refused_while_read() {
    let dir = case_dir("obj-budget");
    let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n");
    for _ in 0..2000 {
        obj.push_str("f 1 2 3\nf 2 4 3\n");
    }
    std::fs::write(dir.join("mesh.obj"), obj).unwrap();
    // The ground (2), four spheres (4 × 3 996 000) and a torus (792 000) leave 1214
    // triangles: the OBJ is object[1], read first, and refused at its 1215th face.
    let objects = format!(
        "{}{}{}{}{}{}",
        object("mesh.obj"),
        object("sphere:2000x1000"),
        object("sphere:2000x1000"),
        object("sphere:2000x1000"),
        object("sphere:2000x1000"),
        object("torus:1000x396"),
    );
    std::fs::write(dir.join("scene.toml"), scene_with(&objects)).unwrap();
    let r = inspect(&dir, &["scene.toml"]);
    assert_refused(
        "an OBJ after big shapes",
        &r,
        &["object[1].mesh", "mesh.obj:", "MAX_SCENE_TRIANGLES"],
        &[],
    );
}

// ---------------------------------------------------------------------------------------------
// 2. Files are files.

/// Before: a mesh symlinked to /dev/zero was read until memory ran out; a FIFO blocked
/// forever; a scene path that was a FIFO or a device likewise.
#[cfg(unix)]
#[test]
fn devices_fifos_and_directories_are_refused_before_reading() {
    let dir = case_dir("not-files");
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.obj")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.toml")).unwrap();
    std::fs::create_dir_all(dir.join("folder.obj")).unwrap();
    let fifos = mkfifo(&dir.join("fifo.obj")) && mkfifo(&dir.join("fifo.toml"));
    let mut cases = vec![
        ("zero.obj", "character device"),
        ("folder.obj", "a directory"),
    ];
    if fifos {
        cases.push(("fifo.obj", "FIFO"));
    }
    for (mesh, kind) in &cases {
        std::fs::write(dir.join("scene.toml"), scene_with(&object(mesh))).unwrap();
        let r = inspect(&dir, &["scene.toml"]);
        assert_refused(
            mesh,
            &r,
            &["object[1].mesh", mesh, kind, "not a regular file"],
            &[],
        );
    }
    // The scene file itself, and a bare .obj.
    let mut scenes = vec![
        ("zero.toml", "character device"),
        ("zero.obj", "character device"),
    ];
    if fifos {
        scenes.push(("fifo.toml", "FIFO"));
        scenes.push(("fifo.obj", "FIFO"));
    }
    for (path, kind) in scenes {
        let r = inspect(&dir, &[path]);
        assert_refused(path, &r, &[path, kind], &[]);
    }
}

/// Before: the error quoted the first line of /etc/passwd (`found `root:x:0:0:...``).
#[test]
fn an_error_never_quotes_the_file() {
    let dir = case_dir("no-echo");
    std::fs::write(
        dir.join("secret.obj"),
        "root:x:0:0:root:/root:/bin/bash\nv 0 0 0\n",
    )
    .unwrap();
    // Not an .obj by name: a path to a regular file is read as one.
    std::fs::write(dir.join("passwd"), "root:x:0:0:root:/root:/bin/bash\n").unwrap();
    for mesh in ["secret.obj", "passwd"] {
        std::fs::write(dir.join("scene.toml"), scene_with(&object(mesh))).unwrap();
        let r = inspect(&dir, &["scene.toml"]);
        assert_refused(
            mesh,
            &r,
            &[&format!("{mesh}:1:"), "OBJ statement"],
            &["root:"],
        );
    }
    // A TOML error names the line and column, not the line's text.
    std::fs::write(
        dir.join("broken.toml"),
        format!("{CAMERA}\n{LIGHT}password = hunter2 hunter2\n"),
    )
    .unwrap();
    let r = inspect(&dir, &["broken.toml"]);
    assert_refused("broken toml", &r, &["broken.toml", "line 10"], &["hunter2"]);
    // An unknown key is not quoted either.
    std::fs::write(
        dir.join("key.toml"),
        format!("{CAMERA}\n{LIGHT}hunter2 = 1\n"),
    )
    .unwrap();
    let r = inspect(&dir, &["key.toml"]);
    assert_refused(
        "unknown key",
        &r,
        &["key.toml", "line 10", "unknown field", "radius"],
        &["hunter2"],
    );
}

/// Before: an OBJ with a UTF-8 byte-order mark failed on an invisible character; invalid
/// UTF-8 in a scene file had no position and repeated its text
/// ("stream did not contain valid UTF-8: stream did not contain valid UTF-8").
#[test]
fn byte_order_marks_and_invalid_utf8() {
    let dir = case_dir("utf8");
    std::fs::write(
        dir.join("bom.obj"),
        "\u{feff}v 0 0 0\nv 1 0 0\nv 0 0 1\nv 0 1 0\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("bom.toml"),
        format!("\u{feff}{}", scene_with(&object("bom.obj"))),
    )
    .unwrap();
    let r = inspect(&dir, &["bom.toml"]);
    assert!(r.status.success(), "{}", r.stderr);
    assert!(r.stdout.contains("bom.obj"), "{}", r.stdout);
    let r = inspect(&dir, &["bom.obj"]);
    assert!(r.status.success(), "{}", r.stderr);

    let mut bad = format!("{CAMERA}\n").into_bytes();
    bad.extend_from_slice(b"[light]\ncenter = [0.0, 4.0, 0.0]\nnormal = \"\xff\xfe\"\n");
    std::fs::write(dir.join("bad.toml"), bad).unwrap();
    let r = inspect(&dir, &["bad.toml"]);
    assert_refused(
        "invalid UTF-8",
        &r,
        &["bad.toml", "line 8", "column 11", "byte offset", "UTF-8"],
        &[],
    );
    assert_eq!(r.stderr.matches("UTF-8").count(), 1, "{}", r.stderr);
}

/// Before: every error caused by another was printed with its cause twice
/// (`…: No such file or directory (os error 2): No such file or directory (os error 2)`).
#[test]
fn a_cause_is_printed_once() {
    let dir = case_dir("once");
    std::fs::write(dir.join("scene.toml"), scene_with(&object("missing.obj"))).unwrap();
    let r = inspect(&dir, &["scene.toml"]);
    assert_refused("a missing OBJ", &r, &["object[1].mesh", "missing.obj"], &[]);
    assert_eq!(r.stderr.matches("os error 2").count(), 1, "{}", r.stderr);
}

// ---------------------------------------------------------------------------------------------
// 3. --out is checked before the work.

/// Before: `--out` naming a file, a place under a file or an unwritable place was found
/// after the whole render (compare: after every method); here the scene does not even exist,
/// so an error about --out proves it came first.
#[test]
fn out_targets_are_checked_before_the_scene_is_loaded() {
    let dir = case_dir("out");
    std::fs::write(dir.join("file.txt"), b"not a folder").unwrap();
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "render",
            "file.txt",
            &["--out", "file.txt", "not a directory"],
        ),
        (
            "compare",
            "file.txt",
            &["--out", "file.txt", "not a directory"],
        ),
        (
            "render",
            "file.txt/sub",
            &["--out", "file.txt", "not a directory"],
        ),
        (
            "render",
            "/proc/dbuffer-bad-inputs",
            &["--out", "/proc", "cannot write there"],
        ),
        (
            "compare",
            "/proc/dbuffer-bad-inputs",
            &["--out", "/proc", "cannot write there"],
        ),
    ];
    for (cmd, out, has) in cases {
        if out.starts_with("/proc") && !Path::new("/proc/self").exists() {
            continue;
        }
        let mut c = dbuffer();
        c.current_dir(&dir)
            .args([cmd, "no-such-scene.toml", "--size", "16x16", "--out", out]);
        let r = run(c);
        assert_refused(&format!("{cmd} --out {out}"), &r, has, &["no-such-scene"]);
    }
    assert_eq!(
        std::fs::read(dir.join("file.txt")).unwrap(),
        b"not a folder"
    );
}

/// Before: `inspect --out` onto a device node or FIFO renamed a PNG over it (as root,
/// /dev/null became a PNG). A FIFO stands in for the device here.
#[cfg(unix)]
#[test]
fn inspect_never_replaces_what_is_not_a_file() {
    let dir = case_dir("inspect-out");
    if !mkfifo(&dir.join("pipe.png")) {
        return;
    }
    let r = inspect(
        &dir,
        &[
            "fig7-concave",
            "--samples",
            "1",
            "--size",
            "8x8",
            "--out",
            "pipe.png",
        ],
    );
    assert_refused(
        "--out FIFO",
        &r,
        &["--out", "pipe.png", "not a regular file"],
        &[],
    );
    let meta = std::fs::symlink_metadata(dir.join("pipe.png")).unwrap();
    assert!(!meta.is_file(), "the FIFO was replaced");
    // And /dev/null is refused by its type before any work (nothing is written to find out).
    let r = inspect(
        &dir,
        &["no-such-scene", "--samples", "1", "--out", "/dev/null"],
    );
    assert_refused(
        "--out /dev/null",
        &r,
        &["--out", "/dev/null"],
        &["no-such-scene"],
    );
    // A directory is refused too; a missing folder for the file as well.
    std::fs::create_dir_all(dir.join("d.png")).unwrap();
    let r = inspect(&dir, &["fig7-concave", "--samples", "1", "--out", "d.png"]);
    assert_refused("--out dir", &r, &["--out", "d.png"], &[]);
    let r = inspect(
        &dir,
        &["fig7-concave", "--samples", "1", "--out", "nowhere/x.png"],
    );
    assert_refused("--out missing folder", &r, &["--out", "nowhere"], &[]);
}

// ---------------------------------------------------------------------------------------------
// 4. A closed standard output.

/// Before: `dbuffer inspect fig7-concave --samples 2 | head -1` panicked ("failed printing to
/// stdout: Broken pipe", exit 101). Now the output is dropped quietly, the work goes on (the
/// PNG asked for is written) and the exit status is 0.
#[test]
fn a_closed_stdout_is_not_a_panic() {
    let dir = case_dir("epipe");
    for args in [
        vec![
            "inspect",
            "fig7-concave",
            "--samples",
            "2",
            "--size",
            "8x8",
            "--out",
            "x.png",
        ],
        vec!["scenes"],
        vec!["--help"],
    ] {
        let _ = std::fs::remove_file(dir.join("x.png"));
        let mut c = dbuffer();
        c.current_dir(&dir)
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = c.spawn().expect("starts");
        // Close the reading end before the child writes: its first line meets EPIPE.
        drop(child.stdout.take());
        let r = finish(child, Duration::from_secs(60));
        assert!(r.status.success(), "{args:?}: {:?}\n{}", r.status, r.stderr);
        assert!(!r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
        assert!(!r.stderr.contains("Broken pipe"), "{args:?}: {}", r.stderr);
        if args[0] == "inspect" {
            assert!(dir.join("x.png").is_file(), "the PNG was not written");
        }
    }
}

/// Before: a full disk behind standard output was a panic too. Now: one line, exit status 1.
#[cfg(target_os = "linux")]
#[test]
fn a_failing_stdout_is_one_line_and_status_1() {
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        return;
    };
    let mut c = dbuffer();
    c.arg("scenes").stdout(full).stderr(Stdio::piped());
    let child = c.spawn().expect("starts");
    let r = finish(child, Duration::from_secs(60));
    assert_refused(
        "scenes > /dev/full",
        &r,
        &["standard output", "No space left"],
        &[],
    );
}

// ---------------------------------------------------------------------------------------------
// 5. Warnings for pictures that will be wrong, and messages that do not mislead.

/// Before: these rendered black or wrong without a word.
#[test]
fn pictures_that_will_be_wrong_are_warned_about() {
    let dir = case_dir("warnings");
    let cases: &[(&str, String, &[&str])] = &[
        (
            "eye next to target",
            format!(
                "{}\n{LIGHT}\n{GROUND}\n{}",
                CAMERA.replace("[0.0, 3.0, 6.0]", "[3e-7, 0.5000004, 0.0]"),
                object("cube")
            ),
            &["camera", "too close for single precision"],
        ),
        (
            "fov near 180",
            format!(
                "{}\n{LIGHT}\n{GROUND}\n{}",
                CAMERA.replace("45.0", "179.9999"),
                object("cube")
            ),
            &["camera", "fov_y_deg", "179.9999"],
        ),
        (
            "scale 1e30",
            scene_with("[[object]]\nmesh = \"cube\"\nscale = 1e30\n"),
            &["1.0e30 across", "render core draws right"],
        ),
        (
            "nothing left",
            scene_with("[[object]]\nname = \"speck\"\nmesh = \"cube\"\nscale = 1e-30\n"),
            &["object[1] 'speck'", "nothing is left of it"],
        ),
    ];
    for (what, text, has) in cases {
        std::fs::write(dir.join("scene.toml"), text).unwrap();
        let r = inspect(&dir, &["scene.toml"]);
        assert!(r.status.success(), "{what}: {}", r.stderr);
        let warnings: Vec<&str> = r
            .stdout
            .lines()
            .filter(|l| l.starts_with("warning"))
            .collect();
        for part in *has {
            assert!(
                warnings.iter().any(|w| w.contains(part)),
                "{what}: no warning with {part:?} in\n{}",
                r.stdout
            );
        }
    }
    // A built-in scene gets no such warning.
    let r = inspect(&dir, &["fig7-concave"]);
    assert!(!r.stdout.contains("warning"), "{}", r.stdout);
}

/// Before: a bare OBJ 1.4e-45 or 6e38 across was refused as `object[1].translate ... [NaN,
/// NaN, NaN]` or `object[1].scale ... found 0`: keys the user never wrote.
#[test]
fn a_bare_obj_too_small_or_too_large_names_the_obj() {
    let dir = case_dir("bare-obj");
    std::fs::write(
        dir.join("tiny.obj"),
        "v 0 0 0\nv 1e-45 0 0\nv 0 1e-45 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("huge.obj"),
        "v -3e38 0 0\nv 3e38 0 0\nv 0 3e38 0\nf 1 2 3\n",
    )
    .unwrap();
    for (obj, size) in [("tiny.obj", "too small"), ("huge.obj", "too large")] {
        let r = inspect(&dir, &[obj]);
        assert_refused(obj, &r, &[obj, size, "extent"], &["object[1]", "NaN"]);
    }
}

// ---------------------------------------------------------------------------------------------
// The library: the same limits where the CLI is not in between (the lab loads through these).

fn load_err(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    scene::load(&path.display().to_string())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_else(|| panic!("{name} loaded"))
}

/// `SceneFile::parse` refuses shapes over the budget (the lab calls it, then `validate` after
/// edits) before `load_meshes` builds anything; the vertex budget likewise.
#[test]
fn the_library_refuses_shapes_over_the_budget_in_validate() {
    let objects: String = (0..5).map(|_| object("sphere:2000x1000")).collect();
    let e = SceneFile::parse(&scene_with(&objects), "s.toml").unwrap_err();
    assert!(e.to_string().contains("MAX_SCENE_TRIANGLES"), "{e}");
}

/// Error messages are one line even when a name holds a newline, and do not grow with a long
/// name (the fuzzer found both).
#[test]
fn names_in_messages_are_one_line_and_short() {
    let dir = case_dir("names");
    let e = load_err(&dir, "nl.toml", &scene_with(&object("a\\nb.obj")));
    assert!(!e.contains('\n') && e.contains("a\\nb.obj"), "{e}");
    let long = "x".repeat(3000);
    let e = load_err(&dir, "long.toml", &scene_with(&object(&long)));
    assert!(e.len() < 1000, "{} bytes", e.len());
}

/// Models as gltf-transform and gltfpack ship them (tests/models/shipped/): `inspect` draws the
/// quantized and meshopt ones with their warnings on stderr, refuses the Draco one naming the
/// extension, and `--scene N` is checked against the file's scenes and refused on a built-in.
#[test]
fn shipped_gltf_models_as_a_user_opens_them() {
    let dir = case_dir("shipped-gltf");
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/models/shipped");
    for file in [
        "fox-quant.glb",
        "fox-meshopt.glb",
        "fox-pack.glb",
        "fox-webp.glb",
    ] {
        let path = shipped.join(file);
        let r = inspect(&dir, &[path.to_str().unwrap()]);
        assert!(r.status.success(), "{file}: {}", r.stderr);
        assert!(r.stdout.contains("576"), "{file}: {}", r.stdout);
        assert!(
            r.stderr
                .lines()
                .any(|l| l.starts_with("warning") && l.contains("rest pose")),
            "{file}: {}",
            r.stderr
        );
    }
    let draco = shipped.join("fox-draco.glb");
    let r = inspect(&dir, &[draco.to_str().unwrap()]);
    assert_refused(
        "draco",
        &r,
        &["requires KHR_draco_mesh_compression, which dbuffer cannot decode"],
        &[],
    );
    let quant = shipped.join("fox-quant.glb");
    let r = inspect(&dir, &[quant.to_str().unwrap(), "--scene", "3"]);
    assert_refused(
        "scene 3",
        &r,
        &["--scene 3: the file has 1 scene (0 to 0)"],
        &[],
    );
    let r = inspect(&dir, &[quant.to_str().unwrap(), "--scene", "0"]);
    assert!(r.status.success(), "{}", r.stderr);
    let r = inspect(&dir, &["fig7-concave", "--scene", "1"]);
    assert_refused("a built-in", &r, &["--scene 1", ".gltf or .glb"], &[]);
}
