//! Through the binary: `dbuffer animate` (frames, the APNG, the orbit moving the shadow, bad
//! flags, all or nothing), glTF models as SCENE of `render`, `inspect` and `compare`, and a scene
//! file without `[camera]`.

use std::io::BufReader;
use std::path::{Path, PathBuf};

use crate::support::{self as cli, dbuffer};

fn temp_dir(name: &str) -> PathBuf {
    cli::temp_dir("animate-cli", name)
}

fn fox() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/Fox.glb")
}

fn run_ok(cmd: &mut std::process::Command) -> (String, String) {
    let out = cmd.output().expect("the binary runs");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{stderr}");
    (stdout, stderr)
}

/// RGB bytes of a PNG.
fn rgb(path: &Path) -> Vec<u8> {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
        .into_raw()
}

/// Pixels whose colour differs by more than 8 in any channel.
fn differing(a: &[u8], b: &[u8]) -> usize {
    a.chunks(3)
        .zip(b.chunks(3))
        .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > 8))
        .count()
}

/// The APNG's frame count as declared, after decoding every frame.
fn apng_frames(path: &Path) -> (u32, u32, u32) {
    let file = std::fs::File::open(path).expect("animation.png");
    let mut reader = png::Decoder::new(BufReader::new(file))
        .read_info()
        .expect("a PNG");
    let info = reader.info();
    let (w, h) = (info.width, info.height);
    let n = info
        .animation_control()
        .expect("an animated PNG (acTL)")
        .num_frames;
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    for k in 0..n {
        reader
            .next_frame(&mut buf)
            .unwrap_or_else(|e| panic!("frame {k} of {n}: {e}"));
    }
    (n, w, h)
}

#[test]
fn animate_writes_the_frames_and_a_looping_apng() {
    let dir = temp_dir("light");
    let (_, stderr) = run_ok(
        dbuffer()
            .args([
                "animate",
                "fig7-concave",
                "--frames",
                "6",
                "--size",
                "64x48",
            ])
            .args(["--dbuffer-size", "256", "--out"])
            .arg(&dir),
    );
    assert!(
        stderr.contains("wrote") && stderr.contains("6 frames"),
        "{stderr}"
    );
    for k in 0..6 {
        let frame = dir.join(format!("frame-{k:04}.png"));
        let img = image::open(&frame).expect("a frame");
        assert_eq!((img.width(), img.height()), (64, 48));
    }
    assert!(!dir.join("frame-0006.png").exists());
    assert_eq!(apng_frames(&dir.join("animation.png")), (6, 64, 48));
    // The light moves: the shadow on the ground moves with it.
    let f0 = rgb(&dir.join("frame-0000.png"));
    let f3 = rgb(&dir.join("frame-0003.png"));
    assert!(
        differing(&f0, &f3) > 40,
        "{} pixels differ",
        differing(&f0, &f3)
    );
    // Nothing else is left in the folder (no temporary folder).
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 7, "{names:?}");

    // A shorter run into the same folder replaces the animation and drops the extra frames.
    run_ok(
        dbuffer()
            .args([
                "animate",
                "fig7-concave",
                "--frames",
                "3",
                "--size",
                "32x24",
            ])
            .args(["--dbuffer-size", "128", "--orbit", "camera", "--out"])
            .arg(&dir),
    );
    assert!(dir.join("frame-0002.png").is_file());
    assert!(
        !dir.join("frame-0003.png").exists(),
        "stale frames are removed"
    );
    assert_eq!(apng_frames(&dir.join("animation.png")), (3, 32, 24));
    // The camera moves: the whole view changes.
    let c0 = rgb(&dir.join("frame-0000.png"));
    let c1 = rgb(&dir.join("frame-0001.png"));
    assert!(differing(&c0, &c1) > 100, "{}", differing(&c0, &c1));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn animate_refuses_bad_flags_with_a_reason_and_writes_nothing() {
    let dir = temp_dir("bad");
    for (args, needle) in [
        (
            vec!["--orbit", "sun"],
            "--orbit expects light or camera, found 'sun'",
        ),
        (vec!["--frames", "0"], "--frames expects 1 to 3600, found 0"),
        (vec!["--frames", "100000"], "--frames expects 1 to 3600"),
        (vec!["--fps", "0"], "--fps expects 1 to 60"),
        (vec!["--size", "0x10"], "--size expects WxH"),
        (
            vec!["--frames", "3000", "--size", "1024x1024"],
            "the limit is",
        ),
        (vec!["--method", "magic"], "magic"),
        (vec!["--vt", "cubic"], "cubic"),
        (vec!["--dbuffer-size", "0"], "--dbuffer-size"),
    ] {
        let out = dbuffer()
            .args(["animate", "fig7-concave", "--out"])
            .arg(&dir)
            .args(&args)
            .output()
            .expect("the binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} should fail");
        assert!(
            stderr.contains(needle),
            "{args:?}: expected '{needle}' in: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!dir.exists(), "{args:?} left a folder");
    }
    // A scene that does not load: the reason, and no folder.
    let out = dbuffer()
        .args(["animate", "no-such-scene", "--out"])
        .arg(&dir)
        .output()
        .expect("runs");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no-such-scene"));
    assert!(!dir.exists());
    // --out naming a file.
    let file = temp_dir("a-file");
    std::fs::write(&file, b"keep").unwrap();
    let out = dbuffer()
        .args([
            "animate",
            "fig7-concave",
            "--frames",
            "2",
            "--size",
            "16x16",
            "--out",
        ])
        .arg(&file)
        .output()
        .expect("runs");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a directory"));
    assert_eq!(std::fs::read(&file).unwrap(), b"keep");
    let _ = std::fs::remove_file(&file);
}

#[test]
fn a_gltf_model_through_render_inspect_and_compare() {
    let fox = fox();
    let dir = temp_dir("fox-render");
    run_ok(
        dbuffer()
            .arg("render")
            .arg(&fox)
            .args(["--size", "64x48", "--dbuffer-size", "256", "--out"])
            .arg(&dir),
    );
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("meta.json")).unwrap()).unwrap();
    assert_eq!(meta["scene"], "Fox");
    let casters = meta["caster_triangles"].as_u64().unwrap();
    assert!((500..=576).contains(&casters), "{casters}");
    // The fox casts a shadow onto the ground: some pixels are not lit.
    let classes = rgb(&dir.join("classes.png"));
    let lit = dbuffer::output::LIT_RGB;
    let shadowed = classes
        .chunks(3)
        .filter(|p| p != &lit && p != &dbuffer::output::NOT_HIT_RGB)
        .count();
    assert!(shadowed > 20, "{shadowed} shadowed pixels");
    let _ = std::fs::remove_dir_all(&dir);

    let (stdout, _) = run_ok(dbuffer().arg("inspect").arg(&fox));
    assert!(stdout.contains("scene     Fox"), "{stdout}");
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("Fox ") && l.contains(&casters.to_string())),
        "{stdout}"
    );
    // The volumes' fill as drawn and whole: four numbers, the drawn ones the smaller.
    let fill: Vec<f64> = stdout
        .lines()
        .find(|l| l.starts_with("fill "))
        .map(|l| {
            l.split(|c: char| !(c.is_ascii_digit() || c == '.'))
                .filter(|w| w.contains('.'))
                .filter_map(|w| w.trim_end_matches('.').parse().ok())
                .collect()
        })
        .unwrap_or_default();
    assert!(
        fill.len() == 4 && fill[0] <= fill[2] && fill[1] <= fill[3] && fill[1] > 0.0,
        "{fill:?} in {stdout}"
    );

    let dir = temp_dir("fox-compare");
    let (stdout, _) = run_ok(
        dbuffer()
            .arg("compare")
            .arg(&fox)
            .args([
                "--size",
                "32x24",
                "--samples",
                "8",
                "--lights",
                "2",
                "--dbuffer-size",
                "128",
            ])
            .arg("--out")
            .arg(&dir),
    );
    assert!(stdout.contains("| dbuffer |"), "{stdout}");
    assert!(dir.join("report.json").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_broken_glb_is_refused_in_one_line() {
    let dir = temp_dir("broken");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("broken.glb");
    let mut bytes = std::fs::read(fox()).unwrap();
    bytes.truncate(1000);
    std::fs::write(&path, &bytes).unwrap();
    let out_dir = dir.join("out");
    for command in ["render", "inspect", "animate"] {
        let mut cmd = dbuffer();
        cmd.arg(command).arg(&path);
        if command != "inspect" {
            cmd.arg("--out").arg(&out_dir);
        }
        let out = cmd.output().expect("runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{command}");
        assert!(
            stderr.contains("broken.glb") && stderr.contains("truncated"),
            "{command}: {stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{command}: {stderr}");
        assert!(!out_dir.exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_scene_file_without_camera_renders_the_framed_view() {
    let dir = temp_dir("nocam");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("nocam.toml");
    std::fs::write(
        &scene,
        "[light]\ncenter = [0, 4, 0]\nnormal = [0, -1, 0]\nradius = 0.5\n\n\
         [[object]]\nmesh = \"plane\"\nscale = 10\ncasts_shadow = false\n\n\
         [[object]]\nmesh = \"cube\"\ntranslate = [0, 0.5, 0]\n",
    )
    .unwrap();
    let out_dir = dir.join("out");
    run_ok(
        dbuffer()
            .arg("render")
            .arg(&scene)
            .args(["--size", "48x48", "--dbuffer-size", "256", "--out"])
            .arg(&out_dir),
    );
    // Framed: the cube is in the middle of the picture, the ground all around it.
    let classes = rgb(&out_dir.join("classes.png"));
    let at = |x: usize, y: usize| &classes[(y * 48 + x) * 3..(y * 48 + x) * 3 + 3];
    assert_ne!(
        at(24, 24),
        dbuffer::output::NOT_HIT_RGB,
        "the centre sees the cube"
    );
    let hit = classes
        .chunks(3)
        .filter(|p| p != &dbuffer::output::NOT_HIT_RGB)
        .count();
    assert!(
        hit > 48 * 48 / 2,
        "{hit} of {} pixels hit a surface",
        48 * 48
    );
    let _ = std::fs::remove_dir_all(&dir);
}
