//! `dbuffer render`'s files (docs/guide/outputs.md): every file written from a small synthetic render reads
//! back exactly; bad input is refused with a message naming the file and the field, before anything
//! on disk changes; a failing call leaves the output folder as it was, with no temporary folder.

use dbuffer::output::{
    read_exr_rgba, write_render, OutputError, RenderMeta, RenderOutputs, FILE_NAMES, LIT_RGB,
    NOT_HIT_RGB, PENUMBRA_RGB, TEMP_PREFIX, UMBRA_RGB,
};
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh, not yet existing path under the system temp dir, unique to this process and call.
fn fresh_path(tag: &str) -> PathBuf {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let path = std::env::temp_dir().join(format!(
        "dbuffer-output-test-{}-{}-{tag}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = fs::remove_dir_all(&path);
    let _ = fs::remove_file(&path);
    path
}

const W: u32 = 7;
const H: u32 = 5;
const DS: u32 = 4;
const LEVELS: [f32; 3] = [0.0, 0.5, 1.0];
/// sRGB 8-bit of LEVELS.
const LEVELS_SRGB: [u8; 3] = [0, 188, 255];

fn meta() -> RenderMeta {
    RenderMeta {
        scene: "synthetic".into(),
        method: "dbuffer".into(),
        variant: "smoothstep".into(),
        width: W,
        height: H,
        dbuffer_size: DS,
        adapter: "test adapter".into(),
        backend: "vulkan".into(),
        cpu_ms: vec![("geometry".into(), 0.4), ("readback".into(), 1.25)],
        gpu_ms: vec![("dbuffer".into(), 0.125)],
        triangles: 12,
        caster_triangles: 10,
        umbra_silhouette_edges: 4,
        penumbra_silhouette_edges: 5,
        umbra_volume_triangles: 16,
        penumbra_volume_triangles: 20,
        warnings: vec!["a warning".into()],
    }
}

/// A 7×5 render with a 4² D-buffer; every value depends on its index so that a swapped row,
/// column or channel shows. Includes infinities, zeros, -0.0 and a subnormal.
fn synthetic() -> RenderOutputs {
    let n = (W * H) as usize;
    let nd = (DS * DS) as usize;
    let f = |i: usize| i as f32;
    RenderOutputs {
        width: W,
        height: H,
        color: (0..n)
            .map(|i| [LEVELS[i % 3], LEVELS[(i + 1) % 3], LEVELS[(i / 3) % 3]])
            .collect(),
        visibility: (0..n).map(|i| f(i) / 34.0).collect(),
        hit: (0..n).map(|i| i % 4 != 3).collect(),
        position: (0..n)
            .map(|i| {
                [
                    f(i) * 0.1,
                    -f(i) - 0.5,
                    if i == 0 { -0.0 } else { 1e-40 * f(i) },
                ]
            })
            .collect(),
        class: (0..n).map(|i| (i % 3) as u8).collect(),
        dbuffer_size: DS,
        d_o: (0..nd)
            .map(|i| {
                if i % 5 == 0 {
                    f32::INFINITY
                } else {
                    f(i) * 0.37
                }
            })
            .collect(),
        d_u: (0..nd)
            .map(|i| if i % 2 == 0 { 0.0 } else { f(i) * 1.5 })
            .collect(),
        d_p: (0..nd)
            .map(|i| if i % 3 == 0 { 0.0 } else { f(i) + 0.25 })
            .collect(),
        s_u: (0..nd).map(|i| f(i) * 3.0e5).collect(),
        s_p: (0..nd)
            .map(|i| if i == 7 { 0.0 } else { 1.0 / (f(i) + 1.0) })
            .collect(),
        meta: meta(),
    }
}

fn bits(p: [f32; 4]) -> [u32; 4] {
    p.map(f32::to_bits)
}

/// Read an EXR and assert it is `w`×`h` and bit for bit `expected`.
fn assert_exr(path: &Path, w: u32, h: u32, expected: impl Iterator<Item = [f32; 4]>) {
    let (rw, rh, pixels) = read_exr_rgba(path).unwrap();
    assert_eq!((rw, rh), (w, h), "{}", path.display());
    let expected: Vec<[u32; 4]> = expected.map(bits).collect();
    let got: Vec<[u32; 4]> = pixels.into_iter().map(bits).collect();
    assert_eq!(got, expected, "{}", path.display());
}

fn png_rgb8(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let img = image::open(path).unwrap();
    assert_eq!(img.color(), image::ColorType::Rgb8, "{}", path.display());
    let img = img.to_rgb8();
    let (w, h) = img.dimensions();
    (w, h, img.pixels().map(|p| p.0).collect())
}

/// The names in `dir` that start like the temporary folder.
fn temp_leftovers(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(TEMP_PREFIX))
        .collect()
}

#[test]
fn every_exr_reads_back_bit_for_bit() {
    let dir = fresh_path("exr");
    let out = synthetic();
    write_render(&dir, &out).unwrap();
    let n = (W * H) as usize;
    let nd = (DS * DS) as usize;
    let alpha = |i: usize| if out.hit[i] { 1.0 } else { 0.0 };
    assert_exr(
        &dir.join("visibility.exr"),
        W,
        H,
        (0..n).map(|i| {
            let v = out.visibility[i];
            [v, v, v, alpha(i)]
        }),
    );
    assert_exr(
        &dir.join("position.exr"),
        W,
        H,
        (0..n).map(|i| {
            let p = out.position[i];
            [p[0], p[1], p[2], alpha(i)]
        }),
    );
    assert_exr(
        &dir.join("dbuffer.exr"),
        DS,
        DS,
        (0..nd).map(|i| [out.d_o[i], out.d_u[i], out.d_p[i], out.s_u[i]]),
    );
    assert_exr(
        &dir.join("dbuffer_s.exr"),
        DS,
        DS,
        (0..nd).map(|i| [out.s_u[i], out.s_p[i], 0.0, 1.0]),
    );
    // Infinity is kept as infinity (not a large finite stand-in), at the texel it was given.
    let (_, _, d) = read_exr_rgba(&dir.join("dbuffer.exr")).unwrap();
    assert_eq!(d[0][0], f32::INFINITY);
    assert_eq!(d[5][0], f32::INFINITY);
    assert_eq!(d[1][0], 0.37);
    // -0.0 keeps its sign.
    let (_, _, p) = read_exr_rgba(&dir.join("position.exr")).unwrap();
    assert!(p[0][2] == 0.0 && p[0][2].is_sign_negative());
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn image_png_is_srgb_8_bit() {
    let dir = fresh_path("png");
    let out = synthetic();
    write_render(&dir, &out).unwrap();
    let (w, h, pixels) = png_rgb8(&dir.join("image.png"));
    assert_eq!((w, h), (W, H));
    let srgb = |c: f32| LEVELS_SRGB[LEVELS.iter().position(|&l| l == c).unwrap()];
    let expected: Vec<[u8; 3]> = out.color.iter().map(|c| c.map(srgb)).collect();
    assert_eq!(pixels, expected);
    // The pattern covers all three levels in every channel, and non-hit pixels keep their colour.
    for ch in 0..3 {
        for level in LEVELS_SRGB {
            assert!(pixels.iter().any(|p| p[ch] == level));
        }
    }
    assert_eq!(pixels[3], expected[3]);
    assert!(!out.hit[3]);
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn classes_png_has_the_documented_colours() {
    let dir = fresh_path("classes");
    let out = synthetic();
    write_render(&dir, &out).unwrap();
    let (w, h, pixels) = png_rgb8(&dir.join("classes.png"));
    assert_eq!((w, h), (W, H));
    for (i, px) in pixels.iter().enumerate() {
        let expected = match (out.hit[i], out.class[i]) {
            (false, _) => NOT_HIT_RGB,
            (true, 0) => LIT_RGB,
            (true, 1) => PENUMBRA_RGB,
            (true, _) => UMBRA_RGB,
        };
        assert_eq!(*px, expected, "pixel {i}");
    }
    // The contract's colours, as the docs list them.
    assert_eq!(LIT_RGB, [224, 218, 204]);
    assert_eq!(PENUMBRA_RGB, [230, 140, 40]);
    assert_eq!(UMBRA_RGB, [30, 50, 130]);
    assert_eq!(NOT_HIT_RGB, [0, 0, 0]);
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn meta_json_has_every_key() {
    let dir = fresh_path("meta");
    write_render(&dir, &synthetic()).unwrap();
    let text = fs::read_to_string(dir.join("meta.json")).unwrap();
    assert!(
        text.contains("\n  \"scene\""),
        "not pretty-printed:\n{text}"
    );
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let keys = [
        "scene",
        "method",
        "variant",
        "width",
        "height",
        "dbuffer_size",
        "adapter",
        "backend",
        "cpu_ms",
        "gpu_ms",
        "triangles",
        "caster_triangles",
        "umbra_silhouette_edges",
        "penumbra_silhouette_edges",
        "umbra_volume_triangles",
        "penumbra_volume_triangles",
        "warnings",
    ];
    let obj = v.as_object().unwrap();
    for key in keys {
        assert!(obj.contains_key(key), "meta.json lacks {key}:\n{text}");
    }
    assert_eq!(obj.len(), keys.len(), "{text}");
    assert_eq!(v["scene"], "synthetic");
    assert_eq!(v["width"], W);
    assert_eq!(v["dbuffer_size"], DS);
    assert_eq!(v["cpu_ms"]["geometry"], 0.4);
    assert_eq!(v["cpu_ms"]["readback"], 1.25);
    assert_eq!(v["gpu_ms"]["dbuffer"], 0.125);
    assert_eq!(v["penumbra_volume_triangles"], 20);
    assert_eq!(v["warnings"][0], "a warning");
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn returns_the_paths_creates_parents_and_replaces_a_previous_render() {
    let dir = fresh_path("parents").join("a").join("b");
    let paths = write_render(&dir, &synthetic()).unwrap();
    let expected: Vec<PathBuf> = FILE_NAMES.iter().map(|n| dir.join(n)).collect();
    assert_eq!(paths, expected);
    for p in &paths {
        assert!(p.is_file(), "{}", p.display());
    }
    fs::write(dir.join("notes.txt"), "unrelated").unwrap();
    let mut second = synthetic();
    second.visibility.iter_mut().for_each(|v| *v = 0.625);
    write_render(&dir, &second).unwrap();
    let (_, _, v) = read_exr_rgba(&dir.join("visibility.exr")).unwrap();
    assert!(v.iter().all(|p| p[0] == 0.625));
    let mut names: Vec<String> = fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut expected: Vec<String> = FILE_NAMES.iter().map(|s| s.to_string()).collect();
    expected.push("notes.txt".into());
    expected.sort();
    assert_eq!(names, expected);
    let _ = fs::remove_dir_all(dir.parent().unwrap().parent().unwrap());
}

/// Each list too short (and too long) is refused with the file and the field named; the output
/// folder is not even created.
#[test]
fn mismatched_lengths_name_the_file_and_the_field() {
    type Case = (&'static str, &'static str, fn(&mut RenderOutputs, bool));
    let cases: [Case; 10] = [
        ("image.png", "color", |o, s| resize(&mut o.color, s)),
        ("visibility.exr", "visibility", |o, s| {
            resize(&mut o.visibility, s)
        }),
        ("visibility.exr", "hit", |o, s| resize(&mut o.hit, s)),
        ("position.exr", "position", |o, s| {
            resize(&mut o.position, s)
        }),
        ("classes.png", "class", |o, s| resize(&mut o.class, s)),
        ("dbuffer.exr", "d_o", |o, s| resize(&mut o.d_o, s)),
        ("dbuffer.exr", "d_u", |o, s| resize(&mut o.d_u, s)),
        ("dbuffer.exr", "d_p", |o, s| resize(&mut o.d_p, s)),
        ("dbuffer.exr", "s_u", |o, s| resize(&mut o.s_u, s)),
        ("dbuffer_s.exr", "s_p", |o, s| resize(&mut o.s_p, s)),
    ];
    fn resize<T: Clone + Default>(v: &mut Vec<T>, shorter: bool) {
        if shorter {
            v.pop();
        } else {
            v.push(T::default());
        }
    }
    for (file, field, break_it) in cases {
        for shorter in [true, false] {
            let dir = fresh_path("lengths");
            let mut out = synthetic();
            break_it(&mut out, shorter);
            let err = write_render(&dir, &out).unwrap_err();
            let msg = err.to_string();
            assert!(matches!(err, OutputError::Length { .. }), "{msg}");
            assert!(msg.starts_with(&format!("{file}: {field} has ")), "{msg}");
            assert!(!dir.exists(), "{msg}: {} was created", dir.display());
        }
    }
}

#[test]
fn zero_sizes_meta_mismatch_and_bad_classes_are_refused() {
    type Case = (fn(&mut RenderOutputs), &'static str);
    let cases: [Case; 6] = [
        (|o| o.width = 0, "image.png: width is 0"),
        (|o| o.height = 0, "image.png: height is 0"),
        (|o| o.dbuffer_size = 0, "dbuffer.exr: dbuffer_size is 0"),
        (
            |o| o.meta.width = 8,
            "meta.json: meta.width is 8 but the render outputs have 7",
        ),
        (
            |o| o.meta.dbuffer_size = 3,
            "meta.json: meta.dbuffer_size is 3",
        ),
        (|o| o.class[9] = 3, "classes.png: pixel (2, 1) has class 3"),
    ];
    for (break_it, expected) in cases {
        let dir = fresh_path("refused");
        let mut out = synthetic();
        break_it(&mut out);
        let msg = write_render(&dir, &out).unwrap_err().to_string();
        assert!(msg.starts_with(expected), "{msg}");
        assert!(!dir.exists());
    }
    // A class outside 0..=2 where nothing was hit is not looked at.
    let dir = fresh_path("class-not-hit");
    let mut out = synthetic();
    assert!(!out.hit[3]);
    out.class[3] = 200;
    write_render(&dir, &out).unwrap();
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn a_file_in_place_of_the_folder_is_an_error_and_nothing_is_created() {
    let base = fresh_path("file-not-dir");
    fs::create_dir_all(&base).unwrap();
    let file = base.join("out");
    fs::write(&file, "a file").unwrap();
    let err = write_render(&file, &synthetic()).unwrap_err();
    assert!(matches!(err, OutputError::NotADirectory { .. }), "{err:?}");
    assert!(err.to_string().contains("not a directory"), "{err}");
    assert_eq!(fs::read(&file).unwrap(), b"a file");
    // Below a file: the folder cannot be created.
    let below = file.join("sub");
    let err = write_render(&below, &synthetic()).unwrap_err();
    assert!(err.to_string().contains("out"), "{err}");
    assert_eq!(fs::read(&file).unwrap(), b"a file");
    let names: Vec<_> = fs::read_dir(&base).unwrap().collect();
    assert_eq!(names.len(), 1);
    let _ = fs::remove_dir_all(&base);
}

/// A previous `image.png` (a sentinel) survives calls that fail, and no temporary folder is left.
/// (A failure at every single step of writing is injected by the unit tests in `src/output/tests.rs`.)
#[test]
fn a_failing_call_leaves_the_previous_contents() {
    let dir = fresh_path("sentinel");
    fs::create_dir_all(&dir).unwrap();
    fs::write(dir.join("image.png"), b"sentinel").unwrap();

    // Bad input: refused before anything is written.
    let mut bad = synthetic();
    bad.d_o.truncate(3);
    assert!(write_render(&dir, &bad).is_err());
    assert_eq!(fs::read(dir.join("image.png")).unwrap(), b"sentinel");
    assert!(temp_leftovers(&dir).is_empty());

    // A directory where the last file should go: refused; no other file is replaced.
    fs::create_dir(dir.join("meta.json")).unwrap();
    fs::write(dir.join("meta.json").join("inside"), b"x").unwrap();
    let err = write_render(&dir, &synthetic()).unwrap_err();
    assert!(
        matches!(err, OutputError::TargetIsDirectory { .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("meta.json"), "{err}");
    assert_eq!(fs::read(dir.join("image.png")).unwrap(), b"sentinel");
    assert!(temp_leftovers(&dir).is_empty());
    let mut names: Vec<String> = fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["image.png", "meta.json"]);

    // Once the way is clear, the sentinel is replaced.
    fs::remove_dir_all(dir.join("meta.json")).unwrap();
    write_render(&dir, &synthetic()).unwrap();
    assert_ne!(fs::read(dir.join("image.png")).unwrap(), b"sentinel");
    assert!(temp_leftovers(&dir).is_empty());
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn read_exr_rgba_errors_name_the_file() {
    let dir = fresh_path("read-errors");
    write_render(&dir, &synthetic()).unwrap();
    let png = dir.join("image.png");
    let err = read_exr_rgba(&png).unwrap_err();
    assert!(matches!(err, OutputError::Decode { .. }), "{err:?}");
    assert!(err.to_string().contains("image.png"), "{err}");
    let missing = dir.join("missing.exr");
    let err = read_exr_rgba(&missing).unwrap_err();
    assert!(err.to_string().contains("missing.exr"), "{err}");
    let _ = fs::remove_dir_all(&dir);
}
