//! Rectangle and polygon lights in scene files (docs/guide/scene-format.md): what loads, how it
//! writes back, and every way a bad one is refused with the key named; and converting between
//! the four kinds of light.

use dbuffer::scene::{Light, LightKind, Outline, SceneFile};
use glam::Vec3;
use std::path::Path;

const CAMERA: &str =
    "[camera]\neye = [0.0, 3.0, 6.0]\ntarget = [0.0, 0.5, 0.0]\nfov_y_deg = 45.0\n";
const OBJECTS: &str = "[[object]]\nmesh = \"plane\"\nscale = 10.0\ncasts_shadow = false\n\n\
                       [[object]]\nmesh = \"cube\"\ntranslate = [0, 1, 0]\n";
const RECT: &str =
    "[light]\nkind = \"rect\"\ncenter = [0.0, 4.0, 0.0]\nnormal = [0.0, -1.0, 0.0]\n\
                    size = [2.0, 0.5]\n";
const POLYGON: &str = "[light]\nkind = \"polygon\"\n\
                       vertices = [[-1.0, 4.0, -1.0], [1.0, 4.0, -1.0], [1.0, 4.0, 1.0], [-1.0, 4.0, 1.0]]\n";

fn scene(light: &str) -> String {
    format!("{CAMERA}\n{light}\n{OBJECTS}")
}

fn load(light: &str) -> dbuffer::scene::Scene {
    SceneFile::parse(&scene(light), "ok.toml")
        .and_then(|f| f.build(Path::new("."), "ok.toml"))
        .unwrap_or_else(|e| panic!("{e}"))
}

fn refused(light: &str) -> String {
    match SceneFile::parse(&scene(light), "my.toml") {
        Ok(_) => panic!("expected an error for:\n{light}"),
        Err(e) => e.to_string(),
    }
}

fn assert_has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "message lacks {p:?}:\n{msg}");
    }
    assert!(!msg.contains('\n'), "one line: {msg}");
}

#[test]
fn a_rect_light_loads_with_its_default_tangent_and_round_trips() {
    let s = load(RECT);
    let Light::Area(a) = s.light else {
        panic!("{:?}", s.light)
    };
    let Outline::Rect { tangent, size } = a.outline else {
        panic!("{:?}", a.outline)
    };
    assert_eq!(size, [2.0, 0.5]);
    // The normal is −Y: the least parallel world axis is +X (the first of X and Z).
    assert!((tangent - Vec3::X).length() < 1e-6, "{tangent}");
    assert_eq!(s.light.kind(), LightKind::Rect);
    assert!((a.area() - 1.0).abs() < 1e-6);
    let corners = a.corners().unwrap();
    assert_eq!(corners.len(), 4);
    // Counter-clockwise seen from below: Newell's normal is the light's.
    assert!(corners.area_normal().normalize().dot(a.normal) > 0.999);
    let f = SceneFile::parse(&scene(RECT), "r.toml").unwrap();
    assert_eq!(SceneFile::parse(&f.to_toml(), "again.toml").unwrap(), f);
    // A tangent is projected onto the light's plane.
    let tilted = format!("{RECT}tangent = [1.0, 1.0, 1.0]\n");
    let Light::Area(a) = load(&tilted).light else {
        unreachable!()
    };
    let (t, _) = a.basis();
    assert!(t.dot(a.normal).abs() < 1e-6);
    assert!(
        (t - Vec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-5,
        "{t}"
    );
}

#[test]
fn a_polygon_light_loads_at_its_centroid_and_round_trips() {
    let s = load(POLYGON);
    let Light::Area(a) = s.light else {
        panic!("{:?}", s.light)
    };
    assert_eq!(s.light.kind(), LightKind::Polygon);
    assert!((a.center - Vec3::new(0.0, 4.0, 0.0)).length() < 1e-6);
    // (x, z) = (−1, −1) → (1, −1) → (1, 1): Newell's normal (right-hand rule) is −Y, down.
    assert!((a.normal - Vec3::NEG_Y).length() < 1e-6, "{}", a.normal);
    assert!((a.area() - 4.0).abs() < 1e-5);
    assert!((a.radius - 2f32.sqrt()).abs() < 1e-5);
    let f = SceneFile::parse(&scene(POLYGON), "p.toml").unwrap();
    assert_eq!(SceneFile::parse(&f.to_toml(), "again.toml").unwrap(), f);
    // The other winding emits up: one-sided, like the disk.
    let up = POLYGON.replace(
        "[[-1.0, 4.0, -1.0], [1.0, 4.0, -1.0], [1.0, 4.0, 1.0], [-1.0, 4.0, 1.0]]",
        "[[-1.0, 4.0, 1.0], [1.0, 4.0, 1.0], [1.0, 4.0, -1.0], [-1.0, 4.0, -1.0]]",
    );
    assert!((load(&up).light.as_area().unwrap().normal - Vec3::Y).length() < 1e-6);
    // A triangle's centroid is the mean of its corners.
    let tri = "[light]\nkind = \"polygon\"\nvertices = [[0, 4, 0], [0, 4, 3], [3, 4, 0]]\n";
    let c = load(tri).light.center();
    assert!((c - Vec3::new(1.0, 4.0, 1.0)).length() < 1e-5, "{c}");
}

#[test]
fn bad_polygon_lights_name_the_key_and_what_is_wrong() {
    let poly = |v: &str| format!("[light]\nkind = \"polygon\"\nvertices = {v}\n");
    let many: Vec<String> = (0..17)
        .map(|k| {
            let a = k as f64 / 17.0 * std::f64::consts::TAU;
            format!("[{:.6}, 4.0, {:.6}]", a.cos(), -a.sin())
        })
        .collect();
    let cases: Vec<(String, &[&str])> = vec![
        // Non-planar beyond 1e-4 of its diameter (2.8 m: 0.01 m off is far beyond).
        (
            poly("[[-1, 4, -1], [-1, 4, 1], [1, 4.01, 1], [1, 4, -1]]"),
            &["light.vertices", "coplanar", "off the polygon's plane"],
        ),
        // Concave: an arrow head.
        (
            poly("[[-1, 4, -1], [-1, 4, 1], [0, 4, 0], [1, 4, 1], [1, 4, -1]]"),
            &["light.vertices", "convex", "concave"],
        ),
        // A star (every corner turns the same way, twice round).
        (
            poly(
                "[[0, 4, 1], [0.588, 4, -0.809], [-0.951, 4, 0.309], [0.951, 4, 0.309], \
                 [-0.588, 4, -0.809]]",
            ),
            &["light.vertices", "convex"],
        ),
        // Collinear: zero area.
        (
            poly("[[0, 4, 0], [1, 4, 0], [2, 4, 0]]"),
            &["light.vertices", "zero area"],
        ),
        // A repeated vertex.
        (
            poly("[[-1, 4, -1], [-1, 4, 1], [-1, 4, 1], [1, 4, -1]]"),
            &["light.vertices", "distinct", "vertex 2 repeats vertex 1"],
        ),
        // More than 16, fewer than 3.
        (
            poly(&format!("[{}]", many.join(", "))),
            &["light.vertices", "at most 16", "17 vertices"],
        ),
        (
            poly("[[0, 4, 0], [1, 4, 0]]"),
            &["light.vertices", "3 to 16", "2 vertices"],
        ),
        // NaN and infinity.
        (
            poly("[[nan, 4, -1], [-1, 4, 1], [1, 4, 1]]"),
            &["light.vertices", "finite", "NaN"],
        ),
        (
            poly("[[inf, 4, -1], [-1, 4, 1], [1, 4, 1]]"),
            &["light.vertices", "finite", "inf"],
        ),
        // Another kind's keys on a polygon.
        (
            format!("{POLYGON}radius = 0.5\n"),
            &["light.radius", "polygon light", "kind = \"disk\""],
        ),
        (
            format!("{POLYGON}center = [0, 4, 0]\n"),
            &["light.center", "polygon light", "vertices"],
        ),
        (
            format!("{POLYGON}a = [0, 4, 0]\n"),
            &["light.a", "polygon light", "kind = \"line\""],
        ),
        (
            format!("{POLYGON}size = [1, 1]\n"),
            &["light.size", "polygon light", "kind = \"rect\""],
        ),
        // No vertices at all.
        (
            "[light]\nkind = \"polygon\"\n".into(),
            &["light.vertices", "nothing"],
        ),
        // Vertices on a disk.
        (
            "[light]\ncenter = [0, 4, 0]\nnormal = [0, -1, 0]\nradius = 0.5\n\
             vertices = [[0, 4, 0], [1, 4, 0], [0, 4, 1]]\n"
                .into(),
            &["light.vertices", "disk light", "kind = \"polygon\""],
        ),
    ];
    for (light, parts) in &cases {
        let msg = refused(light);
        assert_has(&msg, &["my.toml"]);
        assert_has(&msg, parts);
    }
}

#[test]
fn bad_rect_lights_name_the_key_and_what_is_wrong() {
    let cases: Vec<(String, &[&str])> = vec![
        (
            RECT.replace("[2.0, 0.5]", "[2.0, 0.0]"),
            &["light.size", "positive width and height"],
        ),
        (
            RECT.replace("[2.0, 0.5]", "[-1.0, 1.0]"),
            &["light.size", "positive"],
        ),
        (
            RECT.replace("[2.0, 0.5]", "[nan, 1.0]"),
            &["light.size", "finite"],
        ),
        (
            RECT.replace("size = [2.0, 0.5]\n", ""),
            &["light.size", "width, height", "nothing"],
        ),
        (
            format!("{RECT}tangent = [0.0, 2.0, 0.0]\n"),
            &["light.tangent", "not parallel to light.normal"],
        ),
        (
            format!("{RECT}tangent = [0.0, 0.0, 0.0]\n"),
            &["light.tangent", "not parallel"],
        ),
        (
            RECT.replace("[0.0, -1.0, 0.0]", "[0.0, 0.0, 0.0]"),
            &["light.normal", "non-zero"],
        ),
        (
            format!("{RECT}radius = 1.0\n"),
            &["light.radius", "rect light", "kind = \"disk\""],
        ),
        (
            format!("{RECT}b = [1.0, 1.0, 1.0]\n"),
            &["light.b", "rect light", "kind = \"line\""],
        ),
    ];
    for (light, parts) in &cases {
        let msg = refused(light);
        assert_has(&msg, &["my.toml"]);
        assert_has(&msg, parts);
    }
}

#[test]
fn lights_convert_between_every_kind_in_place() {
    let start = load(RECT).light;
    for from in LightKind::ALL {
        let light = start.converted(from);
        assert_eq!(light.kind(), from);
        for to in LightKind::ALL {
            let out = light.converted(to);
            assert_eq!(out.kind(), to, "{from} → {to}");
            // Same place (within a centimetre), same intensity.
            assert!(
                out.center().distance(light.center()) < 1e-2,
                "{from} → {to}: {} vs {}",
                out.center(),
                light.center()
            );
            assert_eq!(out.intensity(), light.intensity());
            // What it became loads back through a scene file as it is.
            let spec = dbuffer::scene::file::LightSpec::of(&out);
            let mut file = SceneFile::parse(&scene(RECT), "c.toml").unwrap();
            file.light = spec;
            file.validate("c.toml")
                .unwrap_or_else(|e| panic!("{from} → {to}: {e}"));
        }
    }
    // A disk becomes the square of its area, and back.
    let disk = start.converted(LightKind::Disk);
    let square = disk.converted(LightKind::Rect);
    let (d, s) = (disk.as_area().unwrap(), square.as_area().unwrap());
    assert!((d.area() - s.area()).abs() < 1e-4 * d.area());
    let back = square.converted(LightKind::Disk);
    assert!((back.as_area().unwrap().radius - d.radius).abs() < 1e-5);
    // A rect's corners are the polygon it becomes.
    let poly = start.converted(LightKind::Polygon);
    assert_eq!(
        poly.as_area().unwrap().corners(),
        start.as_area().unwrap().corners()
    );
}

#[test]
fn older_files_load_unchanged() {
    // Every built-in scene file loads and writes back as it reads (its light's keys included).
    for name in dbuffer::scene::builtin::names() {
        let f = dbuffer::scene::builtin::file(name).unwrap().unwrap();
        assert_eq!(SceneFile::parse(&f.to_toml(), name).unwrap(), f, "{name}");
    }
}

#[test]
fn a_handle_resizes_a_rect_and_moves_a_polygon_vertex() {
    let mut rect = SceneFile::parse(&scene(RECT), "r.toml").unwrap().light;
    let corner = rect
        .light()
        .as_area()
        .unwrap()
        .corners()
        .unwrap()
        .vertices()[2];
    let to = corner + Vec3::new(0.5, 0.0, 0.25);
    rect.set_corner(2, [to.x as f64, to.y as f64, to.z as f64]);
    assert_eq!(rect.size, Some([3.0, 1.0]), "{rect:?}");
    let mut poly = SceneFile::parse(&scene(POLYGON), "p.toml").unwrap().light;
    poly.set_corner(0, [-1.5, 4.2, -1.5]);
    let v = poly.vertices.clone().unwrap();
    assert_eq!(v[0], [-1.5, 4.0, -1.5], "moved in the polygon's plane");
    // A move that makes it concave is not taken.
    poly.set_corner(0, [0.5, 4.0, 0.5]);
    assert_eq!(poly.vertices.unwrap()[0], [-1.5, 4.0, -1.5]);
}
