//! Scene files and OBJ meshes: what loads, and for every kind of bad input, that the error
//! message names the file, the key or line, and what was expected.

use dbuffer::scene::obj::{load_obj, parse_obj_str};
use dbuffer::scene::{builtin, load, load_file, SceneError, SceneFile};
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh directory under the system temp dir, unique to this process and call.
fn temp_dir(tag: &str) -> PathBuf {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "dbuffer-scene-test-{}-{}-{tag}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const CAMERA: &str =
    "[camera]\neye = [0.0, 3.0, 6.0]\ntarget = [0.0, 0.5, 0.0]\nfov_y_deg = 45.0\n";
const LIGHT: &str = "[light]\ncenter = [0.0, 4.0, 0.0]\nnormal = [0.0, -1.0, 0.0]\nradius = 0.5\n";
const GROUND: &str =
    "[[object]]\nname = \"ground\"\nmesh = \"plane\"\nscale = 10.0\ncasts_shadow = false\n";

/// A scene with `object` as its second object (`object[1]`).
fn scene_with(object: &str) -> String {
    format!("{CAMERA}\n{LIGHT}\n{GROUND}\n[[object]]\n{object}\n")
}

/// Writes `text` as `scene.toml` (plus `files`) into a fresh dir and loads it through
/// [`load`]; returns the error message and the scene path.
fn load_err(text: &str, files: &[(&str, &str)]) -> (String, String) {
    let dir = temp_dir("scene");
    for (name, content) in files {
        std::fs::write(dir.join(name), content).unwrap();
    }
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let path = path.display().to_string();
    match load(&path) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => (e.to_string(), path),
    }
}

fn parse_err(text: &str) -> String {
    SceneFile::parse(text, "my.toml").unwrap_err().to_string()
}

fn assert_has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "message lacks {p:?}:\n{msg}");
    }
}

#[test]
fn a_good_file_loads_with_defaults() {
    let text = scene_with("mesh = \"sphere:16x8\"\ntranslate = [0, 1, 0]\nscale = [1, 2, 1]");
    let f = SceneFile::parse(&text, "good.toml").unwrap();
    let s = f.build(Path::new("."), "good.toml").unwrap();
    assert_eq!(s.name, "good");
    assert_eq!(s.objects.len(), 2);
    assert_eq!(s.objects[1].name, "sphere:16x8");
    assert!(s.objects[1].casts_shadow);
    assert_eq!(s.light.intensity(), 1.0);
    assert_eq!(s.caster_triangle_count(), 224);
    let (lo, hi) = s.objects[1].mesh.bounds().unwrap();
    assert!((hi.y - lo.y - 2.0).abs() < 1e-5 && (lo.y - 0.0).abs() < 1e-5);
}

#[test]
fn unknown_key() {
    // The unknown key is not quoted (nothing of the file is): its line and column are.
    let msg = parse_err(&format!("{CAMERA}\n{LIGHT}radius2 = 1.0\n"));
    assert_has(
        &msg,
        &["my.toml", "line 10", "column 1", "unknown field", "radius"],
    );
    assert!(!msg.contains("radius2"), "{msg}");
    let msg = parse_err(&format!(
        "{CAMERA}\n{LIGHT}\n[[object]]\nmesh = \"cube\"\ncast_shadow = true\n"
    ));
    assert_has(
        &msg,
        &["my.toml", "line 13", "unknown field", "casts_shadow"],
    );
    assert!(!msg.contains("cast_shadow "), "{msg}");
    let msg = parse_err(&format!("{CAMERA}\n{LIGHT}\n[lights]\nradius = 1\n"));
    assert_has(&msg, &["my.toml", "line 11", "unknown field"]);
    assert!(!msg.contains("lights"), "{msg}");
}

#[test]
fn missing_required_key() {
    let light = LIGHT.replace("radius = 0.5\n", "");
    let msg = parse_err(&format!("{CAMERA}\n{light}"));
    // The light's keys depend on its kind, so the scene checks them (not toml).
    assert_has(&msg, &["my.toml", "light.radius", "found nothing"]);
    let msg = parse_err(CAMERA);
    assert_has(&msg, &["my.toml", "missing field `light`"]);
    let msg = parse_err(&format!("{CAMERA}\n{LIGHT}\n[[object]]\nname = \"x\"\n"));
    assert_has(&msg, &["my.toml", "missing field `mesh`"]);
}

/// A file without `[camera]` loads, sees the casters and the light, and saves without one.
#[test]
fn a_scene_without_camera_is_framed_on_the_casters_and_the_light() {
    let body =
        format!("{LIGHT}\n{GROUND}\n[[object]]\nmesh = \"sphere:16x8\"\ntranslate = [2, 1, -1]\n");
    let f = SceneFile::parse(&body, "nocam.toml").unwrap();
    assert!(f.camera.is_none());
    assert!(!f.to_toml().contains("[camera]"), "{}", f.to_toml());
    let s = f.build(Path::new("."), "nocam.toml").unwrap();
    let cam = s.camera;
    let view = glam::Mat4::look_at_rh(cam.eye, cam.target, glam::Vec3::Y);
    let proj = glam::Mat4::perspective_rh(cam.fov_y_deg.to_radians(), 1.0, 0.05, 100.0);
    let inside = |p: glam::Vec3| {
        let c = proj * view * p.extend(1.0);
        c.w > 0.0 && (c.x / c.w).abs() <= 1.0 && (c.y / c.w).abs() <= 1.0
    };
    let (lo, hi) = s.objects[1].mesh.bounds().unwrap();
    for i in 0..8 {
        let corner = glam::Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        assert!(inside(corner), "caster corner {corner} outside {cam:?}");
    }
    // And the middle of the shadow below the caster (the light is straight above it).
    assert!(
        inside(glam::Vec3::new(2.0, 0.0, -1.0)),
        "the shadow is in view"
    );
    // Looking down at the scene from the front.
    assert!(
        cam.eye.y > cam.target.y && cam.eye.z > cam.target.z,
        "{cam:?}"
    );
    // Not absurdly far: the caster box fills a good part of the view.
    let d = (cam.eye - cam.target).length();
    assert!(d < 20.0, "{d}");
    // The same file with the camera it computed written out renders the same view.
    let with = format!(
        "[camera]\neye = [{}, {}, {}]\ntarget = [{}, {}, {}]\nfov_y_deg = {}\n{body}",
        cam.eye.x, cam.eye.y, cam.eye.z, cam.target.x, cam.target.y, cam.target.z, cam.fov_y_deg
    );
    let again = SceneFile::parse(&with, "cam.toml")
        .unwrap()
        .build(Path::new("."), "cam.toml")
        .unwrap();
    assert_eq!(again.camera, cam);
}

/// A bare `.obj` and a scene file without `[camera]` holding the same placed mesh get the same
/// view.
#[test]
fn a_bare_obj_and_a_camera_less_file_get_the_same_view() {
    let dir = temp_dir("samecam");
    let obj = dir.join("tet.obj");
    std::fs::write(
        &obj,
        format!("{TRI}v 0 1 0\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n"),
    )
    .unwrap();
    let bare = load(&obj.display().to_string()).unwrap();
    let (file, _) = load_file(&obj.display().to_string()).unwrap();
    assert!(file.camera.is_none());
    let toml = dir.join("tet.toml");
    std::fs::write(&toml, file.to_toml()).unwrap();
    let from_file = load(&toml.display().to_string()).unwrap();
    assert_eq!(bare.camera, from_file.camera);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn toml_syntax_errors_keep_line_and_column() {
    let msg = parse_err(&format!("{CAMERA}\n{LIGHT}radius = = 2\n"));
    assert_has(&msg, &["my.toml", "line 10", "column"]);
}

#[test]
fn wrong_types_say_what_was_expected() {
    let msg = parse_err(&scene_with("mesh = \"cube\"\nscale = \"big\""));
    assert_has(&msg, &["my.toml", "a number or an array of three numbers"]);
    let msg = parse_err(&scene_with("mesh = \"cube\"\nscale = [1, 2]"));
    assert_has(&msg, &["my.toml", "line", "three numbers"]);
    let msg = parse_err(&format!("{CAMERA}\n{}", LIGHT.replace("0.5", "\"wide\"")));
    assert_has(&msg, &["my.toml", "line 9", "radius"]);
}

#[test]
fn non_positive_radius() {
    for r in ["0.0", "0", "-0.5", "-0.0"] {
        let msg = parse_err(&format!("{CAMERA}\n{}", LIGHT.replace("0.5", r)));
        assert_has(&msg, &["my.toml", "light.radius", "positive"]);
    }
}

#[test]
fn zero_normal_and_normalisation() {
    let msg = parse_err(&format!(
        "{CAMERA}\n{}",
        LIGHT.replace("[0.0, -1.0, 0.0]", "[0, 0, 0]")
    ));
    assert_has(&msg, &["my.toml", "light.normal", "non-zero", "[0, 0, 0]"]);
    let f = SceneFile::parse(
        &format!(
            "{CAMERA}\n{}",
            LIGHT.replace("[0.0, -1.0, 0.0]", "[0, -3, 4]")
        ),
        "ok.toml",
    )
    .unwrap();
    let s = f.build(Path::new("."), "ok.toml").unwrap();
    let normal = s.light.as_area().unwrap().normal;
    assert!((normal - glam::Vec3::new(0.0, -0.6, 0.8)).length() < 1e-6);
}

#[test]
fn nan_and_inf() {
    let msg = parse_err(&format!("{CAMERA}\n{}", LIGHT.replace("0.5", "nan")));
    assert_has(&msg, &["my.toml", "light.radius", "finite"]);
    let msg = parse_err(&format!(
        "{CAMERA}\n{}",
        LIGHT.replace("[0.0, 4.0, 0.0]", "[0.0, inf, 0.0]")
    ));
    assert_has(&msg, &["my.toml", "light.center", "finite", "inf"]);
    let msg = parse_err(&format!("{}\n{LIGHT}", CAMERA.replace("45.0", "-inf")));
    assert_has(&msg, &["my.toml", "camera.fov_y_deg", "finite"]);
    let msg = parse_err(&scene_with("mesh = \"cube\"\ntranslate = [0, nan, 0]"));
    assert_has(&msg, &["my.toml", "object[1].translate", "finite"]);
    let msg = parse_err(&scene_with("mesh = \"cube\"\nrotate_deg = [0, 0, +inf]"));
    assert_has(&msg, &["my.toml", "object[1].rotate_deg", "finite"]);
    let msg = parse_err(&scene_with("mesh = \"cube\"\nscale = nan"));
    assert_has(&msg, &["my.toml", "object[1].scale", "finite"]);
    // Finite in f64 but infinite as the f32 the meshes use.
    let msg = parse_err(&scene_with("mesh = \"cube\"\ntranslate = [1e300, 0, 0]"));
    assert_has(&msg, &["my.toml", "object[1].translate", "finite"]);
    let msg = parse_err(&format!(
        "{CAMERA}\n{}",
        LIGHT.replace("[0.0, -1.0, 0.0]", "[0.0, -1.0, nan]")
    ));
    assert_has(&msg, &["my.toml", "light.normal", "finite"]);
    let msg = parse_err(&format!("{CAMERA}\n{}intensity = nan\n", LIGHT));
    assert_has(&msg, &["my.toml", "light.intensity"]);
}

#[test]
fn zero_scale() {
    let msg = parse_err(&scene_with("mesh = \"cube\"\nscale = 0"));
    assert_has(&msg, &["my.toml", "object[1].scale", "non-zero", "found 0"]);
    let msg = parse_err(&scene_with("mesh = \"cube\"\nscale = [1.0, 0.0, 1.0]"));
    assert_has(&msg, &["my.toml", "object[1].scale", "[1, 0, 1]"]);
}

#[test]
fn camera_checks() {
    for fov in ["0.0", "180.0", "-10.0", "200.0"] {
        let msg = parse_err(&format!("{}\n{LIGHT}", CAMERA.replace("45.0", fov)));
        assert_has(&msg, &["my.toml", "camera.fov_y_deg", "between 0 and 180"]);
    }
    let msg = parse_err(&format!(
        "{}\n{LIGHT}",
        CAMERA.replace("[0.0, 0.5, 0.0]", "[0.0, 3.0, 6.0]")
    ));
    assert_has(
        &msg,
        &["my.toml", "camera.target", "different from camera.eye"],
    );
}

#[test]
fn negative_intensity() {
    let msg = parse_err(&format!("{CAMERA}\n{LIGHT}intensity = -1\n"));
    assert_has(&msg, &["my.toml", "light.intensity", "non-negative"]);
}

#[test]
fn unknown_shape_name_lists_the_known_ones() {
    let (msg, path) = load_err(&scene_with("mesh = \"blob\""), &[]);
    assert_has(
        &msg,
        &[
            &path,
            "object[1].mesh",
            "\"blob\"",
            "sphere",
            "torus-knot",
            "rounded-box",
            ".obj",
        ],
    );
}

#[test]
fn bad_shape_parameters() {
    let (msg, path) = load_err(&scene_with("mesh = \"sphere:2x1\""), &[]);
    assert_has(&msg, &[&path, "object[1].mesh", "sphere:AxB", "2x1"]);
    let (msg, _) = load_err(&scene_with("mesh = \"cube:4\""), &[]);
    assert_has(&msg, &["object[1].mesh", "no parameters"]);
}

#[test]
fn missing_obj() {
    let (msg, path) = load_err(&scene_with("mesh = \"meshes/nothing.obj\""), &[]);
    assert_has(
        &msg,
        &[&path, "object[1].mesh", "nothing.obj", "cannot read"],
    );
}

const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 0 1\n";

#[test]
fn malformed_obj_names_file_and_line() {
    let cases: &[(&str, &str, &[&str])] = &[
        // truncated mid-line
        (
            "cut.obj",
            "v 0 0 0\nv 1 0 0\nv 0 0",
            &["cut.obj:3:", "truncated", "2 numbers"],
        ),
        (
            "cutface.obj",
            "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2",
            &["cutface.obj:4:", "at least 3", "truncated"],
        ),
        (
            "range.obj",
            &format!("{TRI}f 1 2 7\n"),
            &["range.obj:4:", "index 7", "out of range", "1..=3"],
        ),
        (
            "neg.obj",
            &format!("{TRI}f -1 -2 -4\n"),
            &["neg.obj:4:", "-4", "out of range"],
        ),
        (
            "zero.obj",
            &format!("{TRI}f 0 1 2\n"),
            &["zero.obj:4:", "start at 1"],
        ),
        (
            "nanv.obj",
            "v 0 0 0\nv 1 nan 0\nv 0 0 1\nf 1 2 3\n",
            &["nanv.obj:2:", "finite", "nan"],
        ),
        (
            "infv.obj",
            "v 0 0 0\nv 1 inf 0\nv 0 0 1\nf 1 2 3\n",
            &["infv.obj:2:", "finite"],
        ),
        (
            "text.obj",
            "v 0 0 zero\n",
            &["text.obj:1:", "not a number (number 3)"],
        ),
        ("shortv.obj", "v 0 0\n", &["shortv.obj:1:", "2 numbers"]),
        (
            "face2.obj",
            &format!("{TRI}\n\nf 1 2\n"),
            &["face2.obj:6:", "at least 3 vertices, found 2"],
        ),
        ("empty.obj", "", &["empty.obj", "contains no triangles"]),
        (
            "points.obj",
            &format!("{TRI}p 1 2 3\nl 1 2\n"),
            &["points.obj", "contains no triangles"],
        ),
        (
            "syntax.obj",
            &format!("{TRI}f 1/2/3/4 2 3\n"),
            &["syntax.obj:4:", "like `7`"],
        ),
        (
            "vt.obj",
            &format!("{TRI}f 1/1 2 3\n"),
            &["vt.obj:4:", "texture coordinate index 1"],
        ),
        (
            "junk.obj",
            &format!("{TRI}hello\n"),
            &["junk.obj:4:", "expected an OBJ statement"],
        ),
    ];
    for (name, content, parts) in cases {
        // Directly...
        let dir = temp_dir("obj");
        let path = dir.join(name);
        std::fs::write(&path, content).unwrap();
        let msg = load_obj(&path).unwrap_err().to_string();
        assert_has(&msg, parts);
        assert!(msg.starts_with(&path.display().to_string()), "{msg}");
        // Nothing of the file's text is quoted.
        let text = &msg[path.display().to_string().len()..];
        for word in ["zero", "hello"] {
            assert!(!text.contains(word), "{name} quotes {word:?}: {msg}");
        }
        // ...and through a scene file, which adds the scene file and the key.
        let (msg, scene) = load_err(
            &scene_with(&format!("mesh = \"{name}\"")),
            &[(name, content)],
        );
        assert_has(&msg, &[&scene, "object[1].mesh"]);
        assert_has(&msg, parts);
    }
}

#[test]
fn non_utf8_obj_names_the_line() {
    let dir = temp_dir("utf8");
    let path = dir.join("bin.obj");
    std::fs::write(&path, b"v 0 0 0\nv 1 0 0\n\xff\xfe\n").unwrap();
    let msg = load_obj(&path).unwrap_err().to_string();
    assert_has(&msg, &["bin.obj:3:", "UTF-8"]);
}

#[test]
fn obj_models_merge_and_weld() {
    // Two objects sharing an edge through duplicated positions (also -0.0 vs 0.0), a quad, slashes.
    let text = "o a\nv 0 0 0\nv 1 0 0\nv 1 0 1\nvn 0 1 0\nf 1//1 3//1 2//1\n\
                o b\nv -0.0 0 0\nv 1 0 1\nv 0 0 1\nv 0 0 2\nf 4 6 5\ng c\nf -4 -1 -2\n";
    let m = parse_obj_str(text, "merge.obj").unwrap();
    assert_eq!(m.triangles.len(), 3);
    assert_eq!(m.positions.len(), 5, "duplicated positions welded");
    // The shared edge (0,0,0)-(1,0,1) is used in opposite directions by the two triangles.
    let a = m.triangles[0];
    let b = m.triangles[1];
    let edges = |t: [u32; 3]| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])];
    assert!(edges(a).iter().any(|&(x, y)| edges(b).contains(&(y, x))));
}

#[test]
fn obj_scene_paths_are_relative_to_the_scene_file() {
    let dir = temp_dir("rel");
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(
        dir.join("meshes/tet.obj"),
        format!("{TRI}v 0 1 0\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n"),
    )
    .unwrap();
    let path = dir.join("tet.toml");
    std::fs::write(
        &path,
        scene_with("name = \"tet\"\nmesh = \"meshes/tet.obj\"\ntranslate = [0, 1, 0]"),
    )
    .unwrap();
    let s = load(&path.display().to_string()).unwrap();
    assert_eq!(s.name, "tet");
    assert_eq!(s.objects[1].name, "tet");
    assert_eq!(s.caster_triangle_count(), 4);
    let (f, p) = load_file(&path.display().to_string()).unwrap();
    assert_eq!(p.as_deref(), Some(path.as_path()));
    assert_eq!(f.objects[1].mesh, "meshes/tet.obj");
}

#[test]
fn a_bare_obj_gets_a_default_scene() {
    let dir = temp_dir("bare");
    let path = dir.join("tet.obj");
    std::fs::write(
        &path,
        format!("{TRI}v 0 1 0\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n"),
    )
    .unwrap();
    let s = load(&path.display().to_string()).unwrap();
    assert_eq!(s.objects.len(), 2);
    assert_eq!(s.caster_triangle_count(), 4);
    assert!(!s.objects[0].casts_shadow);
    let (lo, hi) = s.objects[1].mesh.bounds().unwrap();
    assert!(lo.y.abs() < 1e-5, "stands on the ground");
    assert!(((hi - lo).max_element() - 1.5).abs() < 1e-4);
    assert!(s.light.as_area().unwrap().height_of(hi) > 0.0);
    // The generated file is saveable: it round-trips and builds from another directory.
    let (f, p) = load_file(&path.display().to_string()).unwrap();
    assert_eq!(p.as_deref(), Some(path.as_path()));
    let again = SceneFile::parse(&f.to_toml(), "saved.toml").unwrap();
    assert_eq!(
        again
            .build(Path::new("/"), "saved.toml")
            .unwrap()
            .caster_triangle_count(),
        4
    );
    // A broken .obj reports the obj's file and line.
    std::fs::write(&path, "v 0 0\n").unwrap();
    let msg = load(&path.display().to_string()).unwrap_err().to_string();
    assert_has(&msg, &["tet.obj:1:"]);
}

#[test]
fn unknown_scene_and_missing_file() {
    let msg = load("no-such-scene").unwrap_err().to_string();
    assert_has(
        &msg,
        &["no-such-scene", "fig1-large-light", "acute-corner", ".toml"],
    );
    let err = load("/nonexistent/dir/scene.toml").unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }));
    assert_has(
        &err.to_string(),
        &["/nonexistent/dir/scene.toml", "cannot read"],
    );
}

#[test]
fn builtin_scenes_round_trip_through_to_toml() {
    for &name in builtin::names() {
        let f = builtin::file(name).unwrap().unwrap();
        let text = f.to_toml();
        let again = SceneFile::parse(&text, name).unwrap_or_else(|e| panic!("{name}: {e}\n{text}"));
        assert_eq!(again, f, "{name}");
    }
}

#[test]
fn mirroring_keeps_triangles_facing_outward() {
    let text = scene_with("mesh = \"sphere:8x4\"\nscale = [-1, 1, 1]");
    let s = SceneFile::parse(&text, "m.toml")
        .unwrap()
        .build(Path::new("."), "m.toml")
        .unwrap();
    let vol: f32 = s.objects[1]
        .mesh
        .triangle_corners()
        .map(|[a, b, c]| a.dot(b.cross(c)))
        .sum();
    assert!(vol > 0.0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Arbitrary OBJ-ish text never panics the loader.
    #[test]
    fn obj_parser_never_panics(lines in prop::collection::vec(
        prop_oneof![
            "v( -?[0-9]{1,3}(\\.[0-9]{0,3})?| nan| inf| x){0,5}",
            "f( -?[0-9]{1,2}(/-?[0-9]?){0,3}){0,5}",
            "(vt|vn)( -?[0-9]\\.?[0-9]?){0,4}",
            "[a-z#/ ]{0,8}",
            "o [a-z]{0,3}",
        ],
        0..12,
    ), tail in any::<bool>()) {
        let mut text = lines.join("\n");
        if tail { text.push('\n'); }
        let _ = parse_obj_str(&text, "fuzz.obj");
    }

    /// Arbitrary text never panics the scene parser, and valid-looking numbers never panic build.
    #[test]
    fn scene_parser_never_panics(text in "\\PC{0,200}", r in any::<f64>(), s in any::<f64>()) {
        let _ = SceneFile::parse(&text, "fuzz.toml");
        let doc = format!("{CAMERA}\n[light]\ncenter = [0, 4, 0]\nnormal = [0, -1, {s:?}]\nradius = {r:?}\n{GROUND}");
        if let Ok(f) = SceneFile::parse(&doc, "fuzz.toml") {
            let _ = f.build(Path::new("."), "fuzz.toml");
        }
    }
}

// Line lights (docs/guide/scene-format.md): `kind = "line"` with end points `a` and `b`.

const LINE: &str = "[light]\nkind = \"line\"\na = [-1.0, 4.0, 0.0]\nb = [1.0, 4.0, 0.5]\n";

fn line_scene(light: &str) -> String {
    format!("{CAMERA}\n{light}\n{GROUND}\n[[object]]\nmesh = \"cube\"\ntranslate = [0, 1, 0]\n")
}

#[test]
fn a_line_light_loads_and_round_trips() {
    use dbuffer::scene::{Light, LightKind};
    let f = SceneFile::parse(&line_scene(LINE), "line.toml").unwrap();
    assert_eq!(f.light.kind(), LightKind::Line);
    let s = f.build(Path::new("."), "line.toml").unwrap();
    let Light::Line(l) = s.light else {
        panic!("a line light, got {:?}", s.light)
    };
    assert_eq!(l.a, glam::Vec3::new(-1.0, 4.0, 0.0));
    assert_eq!(l.b, glam::Vec3::new(1.0, 4.0, 0.5));
    assert_eq!(l.intensity, 1.0, "intensity defaults to 1");
    assert_eq!(s.light.center(), glam::Vec3::new(0.0, 4.0, 0.25));
    let text = f.to_toml();
    assert!(
        text.contains("kind = \"line\"") && !text.contains("center") && !text.contains("radius"),
        "{text}"
    );
    assert_eq!(SceneFile::parse(&text, "again.toml").unwrap(), f);
    // An explicit intensity, and kind = "disk" spelled out, load too.
    let bright = LINE.replace("kind", "intensity = 2.5\nkind");
    let s = load_ok(&line_scene(&bright));
    assert_eq!(s.light.intensity(), 2.5);
    let explicit = SceneFile::parse(
        &format!(
            "{CAMERA}\n{}",
            LIGHT.replace("[light]\n", "[light]\nkind = \"disk\"\n")
        ),
        "disk.toml",
    )
    .unwrap();
    assert_eq!(explicit.light.kind(), LightKind::Disk);
}

fn load_ok(text: &str) -> dbuffer::scene::Scene {
    SceneFile::parse(text, "ok.toml")
        .and_then(|f| f.build(Path::new("."), "ok.toml"))
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_disk_file_without_kind_writes_back_exactly_its_keys() {
    let f = SceneFile::parse(&scene_with("mesh = \"cube\""), "d.toml").unwrap();
    let text = f.to_toml();
    let light = &text[text.find("[light]").unwrap()..];
    let light = &light[..light.find("\n\n").unwrap_or(light.len())];
    assert_eq!(
        light,
        "[light]\ncenter = [0.0, 4.0, 0.0]\nnormal = [0.0, -1.0, 0.0]\nradius = 0.5\nintensity = 1.0",
        "{text}"
    );
    // Every built-in with a disk light writes back as it reads.
    for name in builtin::names() {
        let f = builtin::file(name).unwrap().unwrap();
        assert_eq!(SceneFile::parse(&f.to_toml(), name).unwrap(), f, "{name}");
    }
}

#[test]
fn bad_line_lights_name_the_key_and_what_was_expected() {
    let cases: &[(String, &[&str])] = &[
        // Zero length: a = b (and shorter than the minimum).
        (
            LINE.replace("[1.0, 4.0, 0.5]", "[-1.0, 4.0, 0.0]"),
            &["light.b", "zero length", "0.0001 m", "[-1, 4, 0]"],
        ),
        (
            LINE.replace("[1.0, 4.0, 0.5]", "[-1.0, 4.00001, 0.0]"),
            &["light.b", "zero length"],
        ),
        // NaN and infinity, in either end.
        (
            LINE.replace("[-1.0, 4.0, 0.0]", "[nan, 4.0, 0.0]"),
            &["light.a", "finite", "NaN"],
        ),
        (
            LINE.replace("[1.0, 4.0, 0.5]", "[1.0, inf, 0.5]"),
            &["light.b", "finite", "inf"],
        ),
        // Missing ends.
        (
            LINE.replace("b = [1.0, 4.0, 0.5]\n", ""),
            &["light.b", "second end point", "line light", "nothing"],
        ),
        (
            LINE.replace("a = [-1.0, 4.0, 0.0]\n", ""),
            &["light.a", "first end point"],
        ),
        // A disk's keys on a line light, a line's keys on a disk.
        (
            format!("{LINE}radius = 0.5\n"),
            &["light.radius", "line light", "kind = \"line\""],
        ),
        (
            format!("{LINE}center = [0.0, 4.0, 0.0]\n"),
            &["light.center", "line light"],
        ),
        (
            format!("{LIGHT}a = [0.0, 4.0, 0.0]\n"),
            &["light.a", "disk light", "kind = \"line\""],
        ),
        // A line's ends without kind = "line" are a disk missing its keys... after the foreign
        // key: the message points at `a`.
        (
            LINE.replace("kind = \"line\"\n", ""),
            &["light.a", "disk light"],
        ),
        // An unknown kind: toml's own message, with the line and the kinds there are (not the
        // value written: errors never quote the file).
        (
            LINE.replace("\"line\"", "\"sphere\""),
            &["kind", "disk", "line", "line 7"],
        ),
    ];
    for (light, parts) in cases {
        let msg = parse_err(&line_scene(light));
        assert_has(&msg, &["my.toml"]);
        assert_has(&msg, parts);
        // The scene's own messages are one line (toml's quote the offending line).
        assert!(
            msg.contains("TOML parse error") || !msg.contains('\n'),
            "one line: {msg}"
        );
    }
    // Through `load`, the path is named too.
    let (msg, path) = load_err(
        &line_scene(&LINE.replace("[1.0, 4.0, 0.5]", "[-1.0, 4.0, 0.0]")),
        &[],
    );
    assert_has(&msg, &[&path, "light.b", "zero length"]);
}

#[test]
fn a_disk_missing_its_keys_says_which() {
    let msg = parse_err(&format!(
        "{CAMERA}\n{}",
        LIGHT.replace("radius = 0.5\n", "")
    ));
    assert_has(&msg, &["my.toml", "light.radius", "radius", "nothing"]);
    let msg = parse_err(&format!(
        "{CAMERA}\n{}",
        LIGHT.replace("center = [0.0, 4.0, 0.0]\n", "")
    ));
    assert_has(&msg, &["my.toml", "light.center"]);
}
