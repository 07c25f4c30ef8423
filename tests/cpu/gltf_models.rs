//! glTF models: small `.glb`/`.gltf` files written here byte by byte, their geometry checked
//! against the numbers their node transforms must give, and every kind of bad input refused
//! with a message naming the file and what is wrong, without a panic.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use dbuffer::scene::gltf::{load_gltf, parse_gltf, GltfModel, MAX_TRIANGLES};
use dbuffer::scene::{load, SceneError};
use glam::Vec3;
use proptest::prelude::*;
use serde_json::{json, Value};

use dbuffer_fuzzer::gltf_build::{
    base64, f32_bytes, glb, instanced_strip, quantized_tet, sparse_tet, tet_doc,
};

fn temp_dir(tag: &str) -> PathBuf {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "dbuffer-gltf-test-{}-{}-{tag}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn parse_glb(doc: &Value, bin: &[u8]) -> Result<GltfModel, SceneError> {
    parse_gltf(&glb(doc, bin), "t.glb", None)
}

fn err_glb(doc: &Value, bin: &[u8]) -> String {
    parse_glb(doc, bin).unwrap_err().to_string()
}

fn assert_has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "message lacks {p:?}:\n{msg}");
    }
}

/// The positions of `m`, sorted, to compare as a set.
fn sorted_positions(m: &GltfModel) -> Vec<Vec3> {
    let mut p = m.mesh.positions.clone();
    p.sort_by(|a, b| a.to_array().partial_cmp(&b.to_array()).unwrap());
    p
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

/// Six times the signed volume: positive when the triangles face outward.
fn volume6(m: &GltfModel) -> f32 {
    m.mesh
        .triangle_corners()
        .map(|[a, b, c]| a.dot(b.cross(c)))
        .sum()
}

#[test]
fn nested_node_transforms_place_every_vertex() {
    let s = std::f32::consts::FRAC_1_SQRT_2;
    // Node 0: translate (1,0,0) · scale 2, its child node 1: 90° about +Y, holding the mesh.
    let nodes = json!([
        {"translation": [1, 0, 0], "scale": [2, 2, 2], "children": [1]},
        {"rotation": [0, s, 0, s], "mesh": 0}
    ]);
    let (doc, bin) = tet_doc(Some(5123), nodes, json!([0]));
    let m = parse_glb(&doc, &bin).unwrap();
    assert_eq!(m.mesh.triangles.len(), 4);
    // Ry(90°) takes x to −z and z to x; then ×2; then +(1,0,0).
    let expected = [
        Vec3::new(1.0, 0.0, -2.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 2.0, 0.0),
        Vec3::new(3.0, 0.0, 0.0),
    ];
    let got = sorted_positions(&m);
    assert_eq!(got.len(), 4);
    for e in expected {
        assert!(got.iter().any(|&g| close(g, e)), "{e} not in {got:?}");
    }
    // Rigid motion and uniform scale 2: the volume is 8 × 1/6, still outward.
    assert!((volume6(&m) - 8.0).abs() < 1e-4, "{}", volume6(&m));
    assert!(m.light.is_none());
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
}

#[test]
fn a_matrix_node_and_a_mirror_keep_triangles_outward() {
    // Column-major matrix: mirror x, translate y by 5.
    let nodes = json!([{"matrix": [-1,0,0,0, 0,1,0,0, 0,0,1,0, 0,5,0,1], "mesh": 0}]);
    let (doc, bin) = tet_doc(Some(5125), nodes, json!([0]));
    let m = parse_glb(&doc, &bin).unwrap();
    let got = sorted_positions(&m);
    assert!(
        got.iter().any(|&g| close(g, Vec3::new(-1.0, 5.0, 0.0))),
        "{got:?}"
    );
    assert!(
        volume6(&m) > 0.99,
        "a mirrored node must flip the winding back: {}",
        volume6(&m)
    );
}

#[test]
fn every_index_type_and_no_indices_give_the_same_mesh() {
    let nodes = json!([{"mesh": 0}]);
    let reference = parse_glb(
        &tet_doc(Some(5125), nodes.clone(), json!([0])).0,
        &tet_doc(Some(5125), nodes.clone(), json!([0])).1,
    )
    .unwrap();
    for ty in [Some(5121), Some(5123), None] {
        let (doc, bin) = tet_doc(ty, nodes.clone(), json!([0]));
        let m = parse_glb(&doc, &bin).unwrap();
        // Non-indexed corners are welded back into 4 vertices.
        assert_eq!(m.mesh.positions.len(), 4, "{ty:?}");
        assert_eq!(m.mesh.triangles.len(), 4, "{ty:?}");
        assert_eq!(sorted_positions(&m), sorted_positions(&reference), "{ty:?}");
        assert!((volume6(&m) - 1.0).abs() < 1e-5, "{ty:?}");
    }
}

#[test]
fn a_mesh_used_by_two_nodes_is_there_twice() {
    let nodes = json!([
        {"mesh": 0},
        {"translation": [0, 0, 5], "mesh": 0}
    ]);
    let (doc, bin) = tet_doc(Some(5123), nodes, json!([0, 1]));
    let m = parse_glb(&doc, &bin).unwrap();
    assert_eq!(m.mesh.triangles.len(), 8);
    let (lo, hi) = m.mesh.bounds().unwrap();
    assert!(
        close(lo, Vec3::ZERO) && close(hi, Vec3::new(1.0, 1.0, 6.0)),
        "{lo} {hi}"
    );
}

#[test]
fn the_default_scene_is_used_else_the_first() {
    let nodes = json!([{"mesh": 0}, {"translation": [0, 10, 0], "mesh": 0}]);
    let (mut doc, bin) = tet_doc(Some(5123), nodes, json!([0]));
    doc["scenes"] = json!([{"nodes": [0]}, {"nodes": [1]}]);
    doc["scene"] = json!(1);
    let m = parse_glb(&doc, &bin).unwrap();
    assert!(m.mesh.bounds().unwrap().0.y > 9.0, "scene 1 is the default");
    doc.as_object_mut().unwrap().remove("scene");
    let m = parse_glb(&doc, &bin).unwrap();
    assert!(
        m.mesh.bounds().unwrap().0.y < 1.0,
        "without `scene`, the first"
    );
}

#[test]
fn strips_become_triangles_and_lines_are_skipped_with_a_warning() {
    // A unit square as a strip of 4 vertices (2 triangles), and a line primitive.
    let quad: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 0.0, -1.0],
        [1.0, 0.0, -1.0],
    ];
    let bin = f32_bytes(&quad);
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": 0}, "mode": 5},
            {"attributes": {"POSITION": 0}, "mode": 1}
        ]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}],
        "bufferViews": [{"buffer": 0, "byteLength": 48}],
        "buffers": [{"byteLength": 48}],
    });
    let m = parse_glb(&doc, &bin).unwrap();
    assert_eq!(m.mesh.triangles.len(), 2);
    // Both triangles of the strip face the same way (+Y here).
    for [a, b, c] in m.mesh.triangle_corners() {
        assert!((b - a).cross(c - a).y > 0.0);
    }
    assert_eq!(m.warnings.len(), 1);
    assert_has(&m.warnings[0], &["1 point or line primitive skipped"]);

    let mut lines_only = doc.clone();
    lines_only["meshes"][0]["primitives"] = json!([{"attributes": {"POSITION": 0}, "mode": 1}]);
    assert_has(
        &err_glb(&lines_only, &bin),
        &["t.glb", "contains no triangles", "1 point or line"],
    );
}

#[test]
fn a_spot_light_on_a_node_gives_position_and_direction() {
    let s = std::f32::consts::FRAC_1_SQRT_2;
    // Parent translates by (0, 4, 0); the light's node turns −Z to −Y (−90° about X) and sits at
    // (1, 1, 0) in its parent.
    let nodes = json!([
        {"mesh": 0},
        {"translation": [0, 4, 0], "children": [2]},
        {"translation": [1, 1, 0], "rotation": [-s, 0, 0, s],
         "extensions": {"KHR_lights_punctual": {"light": 0}}}
    ]);
    let (mut doc, bin) = tet_doc(Some(5123), nodes, json!([0, 1]));
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "spot", "spot": {"outerConeAngle": 0.7}}
    ]}});
    let m = parse_glb(&doc, &bin).unwrap();
    let l = m.light.expect("the spot light");
    assert_eq!(l.kind, "spot");
    assert!(
        close(l.position, Vec3::new(1.0, 5.0, 0.0)),
        "{}",
        l.position
    );
    assert!(close(l.direction, Vec3::NEG_Y), "{}", l.direction);

    // A point light points down whatever its node's rotation; a directional one is not used.
    doc["extensions"]["KHR_lights_punctual"]["lights"] =
        json!([{"type": "directional"}, {"type": "point"}]);
    doc["nodes"][2]["extensions"]["KHR_lights_punctual"]["light"] = json!(1);
    doc["nodes"][0]["extensions"] = json!({"KHR_lights_punctual": {"light": 0}});
    let m = parse_glb(&doc, &bin).unwrap();
    let l = m.light.expect("the point light");
    assert_eq!(l.kind, "point");
    assert!(close(l.position, Vec3::new(1.0, 5.0, 0.0)));
    assert!(close(l.direction, Vec3::NEG_Y));
    assert!(
        m.warnings.iter().any(|w| w.contains("directional")),
        "{:?}",
        m.warnings
    );
}

#[test]
fn a_model_as_scene_stands_on_the_ground_under_its_own_light() {
    let dir = temp_dir("scene");
    let s = (std::f32::consts::PI / 6.0).sin(); // a spot tilted 60° from −Z toward −Y: −120°/2
    let c = (std::f32::consts::PI / 6.0).cos();
    let nodes = json!([
        {"scale": [10, 10, 10], "mesh": 0},
        {"translation": [0, 40, 0], "rotation": [-c, 0, 0, s],
         "extensions": {"KHR_lights_punctual": {"light": 0}}}
    ]);
    let (mut doc, bin) = tet_doc(Some(5123), nodes, json!([0, 1]));
    doc["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "spot", "spot": {}}
    ]}});
    let path = dir.join("lit.glb");
    std::fs::write(&path, glb(&doc, &bin)).unwrap();
    let scene = load(path.to_str().unwrap()).unwrap();
    assert_eq!(scene.name, "lit");
    assert_eq!(scene.objects.len(), 2);
    assert_eq!(scene.caster_triangle_count(), 4);
    let (lo, hi) = scene.objects[1].mesh.bounds().unwrap();
    assert!(lo.y.abs() < 1e-5 && ((hi - lo).max_element() - 1.5).abs() < 1e-4);
    // The model (10 m) became 1.5 m: ×0.15, centred on x and z (its centre was 5, 5).
    let light = *scene.light.as_area().expect("a disk light");
    assert!(
        close(light.center, Vec3::new(-0.75, 6.0, -0.75)),
        "{}",
        light.center
    );
    // −Z turned by −120° about X: (0, −sin 120°, cos 120°)·(−1)... = (0, −0.866, 0.5).
    assert!(
        close(light.normal, Vec3::new(0.0, -0.866_025_4, 0.5)),
        "{}",
        light.normal
    );
    assert!(light.radius > 0.0 && light.radius <= 0.5);
    // No light in the file: the default light over the model.
    let (doc, bin) = tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
    let plain = dir.join("plain.glb");
    std::fs::write(&plain, glb(&doc, &bin)).unwrap();
    let scene = load(plain.to_str().unwrap()).unwrap();
    let light = *scene.light.as_area().expect("a disk light");
    assert!(close(light.center, Vec3::new(0.0, 4.0, 0.0)));
    assert!(close(light.normal, Vec3::NEG_Y));
    // Framed: the camera looks at the model and the light from above the ground.
    assert!(
        scene.camera.eye.y > 1.0 && scene.camera.eye.z > 1.0,
        "{:?}",
        scene.camera
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gltf_with_a_bin_file_a_data_uri_and_in_a_scene_file() {
    let dir = temp_dir("files");
    let (mut doc, bin) = tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
    std::fs::create_dir_all(dir.join("models")).unwrap();
    std::fs::write(dir.join("models").join("tet mesh.bin"), &bin).unwrap();
    doc["buffers"][0]["uri"] = json!("tet%20mesh.bin");
    std::fs::write(
        dir.join("models/tet.gltf"),
        serde_json::to_vec(&doc).unwrap(),
    )
    .unwrap();
    let m = load_gltf(&dir.join("models/tet.gltf")).unwrap();
    assert_eq!(m.mesh.triangles.len(), 4);

    // The same bytes as a base64 data: URI.
    let b64 = base64(&bin);
    doc["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{b64}"));
    let m = parse_gltf(&serde_json::to_vec(&doc).unwrap(), "inline.gltf", None).unwrap();
    assert_eq!(m.mesh.triangles.len(), 4);

    // `mesh = "models/tet.gltf"`, relative to the scene file, placed by the object's transform.
    let toml = "[light]\ncenter = [0, 4, 0]\nnormal = [0, -1, 0]\nradius = 0.5\n\n\
                [[object]]\nmesh = \"models/tet.gltf\"\ntranslate = [0, 1, 0]\n";
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    let scene = load(dir.join("scene.toml").to_str().unwrap()).unwrap();
    assert_eq!(scene.caster_triangle_count(), 4);
    let (lo, _) = scene.objects[0].mesh.bounds().unwrap();
    assert!(close(lo, Vec3::new(0.0, 1.0, 0.0)), "{lo}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn truncated_and_wrong_magic_glb() {
    let (doc, bin) = tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
    let good = glb(&doc, &bin);
    for cut in [0, 3, 8, 11, 16, 40, good.len() - 30, good.len() - 1] {
        let bytes = &good[..cut];
        let msg = parse_gltf(bytes, "cut.glb", None).unwrap_err().to_string();
        assert!(msg.starts_with("cut.glb: "), "{msg}");
        assert!(
            msg.contains("truncated") || msg.contains("magic"),
            "cut at {cut}: {msg}"
        );
    }
    // Wrong magic on a .glb.
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(&good[8..]);
    let msg = parse_gltf(&png, "model.glb", None).unwrap_err().to_string();
    assert_has(&msg, &["model.glb", "magic `glTF`", "89 50 4e 47"]);
    // A header length under the minimum does not underflow.
    let mut short = good.clone();
    short[8..12].copy_from_slice(&4u32.to_le_bytes());
    assert_has(
        &parse_gltf(&short, "s.glb", None).unwrap_err().to_string(),
        &["s.glb", "too short"],
    );
    // A JSON chunk that claims more than there is.
    let mut long = good.clone();
    long[12..16].copy_from_slice(&1_000_000u32.to_le_bytes());
    assert_has(
        &parse_gltf(&long, "l.glb", None).unwrap_err().to_string(),
        &["l.glb", "truncated", "1000000"],
    );
    // Version 1.
    let mut v1 = good;
    v1[4..8].copy_from_slice(&1u32.to_le_bytes());
    assert_has(
        &parse_gltf(&v1, "v.glb", None).unwrap_err().to_string(),
        &["v.glb", "version 1"],
    );
}

#[test]
fn accessors_out_of_range_or_of_the_wrong_type() {
    let nodes = json!([{"mesh": 0}]);
    let (doc, bin) = tet_doc(Some(5123), nodes, json!([0]));
    // More positions than the view holds.
    let mut d = doc.clone();
    d["accessors"][0]["count"] = json!(5);
    assert_has(
        &err_glb(&d, &bin),
        &[
            "t.glb",
            "accessor 0",
            "POSITION of mesh 0, primitive 0",
            "out of range",
            "5 items",
        ],
    );
    // No items, from past the end of the view: refused, not a slice past the end.
    let mut d = doc.clone();
    d["accessors"][0]["count"] = json!(0);
    d["accessors"][0]["byteOffset"] = json!(1000);
    assert_has(
        &err_glb(&d, &bin),
        &["accessor 0", "out of range", "0 items"],
    );
    // An offset past the view.
    let mut d = doc.clone();
    d["accessors"][1]["byteOffset"] = json!(2);
    assert_has(
        &err_glb(&d, &bin),
        &["accessor 1", "indices of mesh 0", "out of range"],
    );
    // A view past its buffer's bytes.
    let mut d = doc.clone();
    d["bufferViews"][1]["byteLength"] = json!(400);
    d["accessors"][1]["count"] = json!(12);
    assert_has(
        &err_glb(&d, &bin),
        &["buffer view 1 is out of range", "buffer 0"],
    );
    // A view offset near 2^64: the end of the view must not wrap around (a debug build
    // panicked on the overflow).
    let mut d = doc.clone();
    d["bufferViews"][0]["byteOffset"] = json!(u64::MAX);
    assert_has(
        &err_glb(&d, &bin),
        &[
            "t.glb",
            "buffer view 0 is out of range",
            "18446744073709551615",
        ],
    );
    // A buffer that says more than the BIN chunk has.
    let mut d = doc.clone();
    d["buffers"][0]["byteLength"] = json!(4000);
    assert_has(
        &err_glb(&d, &bin),
        &["buffer 0 says 4000 bytes", "BIN chunk"],
    );
    // Positions that are neither FLOAT nor a type KHR_mesh_quantization allows, or not VEC3.
    let mut d = doc.clone();
    d["accessors"][0]["componentType"] = json!(5125);
    assert_has(
        &err_glb(&d, &bin),
        &["accessor 0", "UNSIGNED_INT VEC3", "expected VEC3 positions"],
    );
    let mut d = doc.clone();
    d["accessors"][0]["type"] = json!("VEC2");
    assert_has(&err_glb(&d, &bin), &["accessor 0", "FLOAT VEC2"]);
    // Float indices.
    let mut d = doc.clone();
    d["accessors"][1]["componentType"] = json!(5126);
    d["accessors"][1]["count"] = json!(6);
    assert_has(&err_glb(&d, &bin), &["accessor 1", "expected unsigned"]);
    // A stride smaller than an element.
    let mut d = doc.clone();
    d["bufferViews"][0]["byteStride"] = json!(4);
    let msg = err_glb(&d, &bin);
    assert!(
        msg.contains("byteStride") || msg.contains("invalid glTF"),
        "{msg}"
    );
    // Sparse accessors: more values than elements, an index past them, a view missing.
    let mut d = doc.clone();
    d["accessors"][0]["sparse"] = json!({"count": 5,
        "indices": {"bufferView": 1, "componentType": 5123},
        "values": {"bufferView": 0}});
    assert_has(&err_glb(&d, &bin), &["accessor 0", "5 sparse values"]);
    let mut d = doc.clone();
    // The face indices' first two u16 (0, 2) read as one u32: 131072, past the 4 elements.
    d["accessors"][0]["sparse"] = json!({"count": 1,
        "indices": {"bufferView": 1, "componentType": 5125},
        "values": {"bufferView": 0}});
    assert_has(
        &err_glb(&d, &bin),
        &["accessor 0", "sparse index", "out of range"],
    );
    let mut d = doc.clone();
    d["accessors"][0]["sparse"] = json!({"count": 1,
        "indices": {"componentType": 5123}, "values": {"bufferView": 0}});
    assert_has(
        &err_glb(&d, &bin),
        &["accessors[0].sparse.indices.bufferView is missing"],
    );
}

#[test]
fn an_index_past_the_vertices_is_refused() {
    let (doc, mut bin) = tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
    // The 5th index (item 4) becomes 9.
    let at = 48 + 4 * 2;
    bin[at..at + 2].copy_from_slice(&9u16.to_le_bytes());
    assert_has(
        &err_glb(&doc, &bin),
        &[
            "t.glb",
            "accessor 1",
            "index 9 at item 4 is out of range",
            "4 vertices",
        ],
    );
}

#[test]
fn huge_counts_are_refused_before_allocating() {
    let (doc, bin) = tet_doc(Some(5125), json!([{"mesh": 0}]), json!([0]));
    let mut d = doc.clone();
    d["accessors"][0]["count"] = json!(4_000_000_000u64);
    assert_has(
        &err_glb(&d, &bin),
        &["accessor 0", "out of range", "4000000000 items"],
    );
    let mut d = doc.clone();
    d["accessors"][1]["count"] = json!(3 * (MAX_TRIANGLES as u64 + 1));
    assert_has(
        &err_glb(&d, &bin),
        &["accessor 1", "16777216 triangles", "limit"],
    );
    let mut d = doc.clone();
    d["accessors"][1]["count"] = json!(u64::MAX / 2);
    let msg = err_glb(&d, &bin);
    assert!(msg.contains("t.glb"), "{msg}");
    // A view of 2^64 - 1 bytes under one-byte indices: the budget's count of what the view
    // can hold must not overflow (a debug build panicked).
    let (mut d, bin8) = tet_doc(Some(5121), json!([{"mesh": 0}]), json!([0]));
    d["bufferViews"][1]["byteLength"] = json!(u64::MAX);
    assert_has(&err_glb(&d, &bin8), &["t.glb", "buffer view 1"]);
    // A huge byteLength on a buffer the BIN chunk cannot back.
    let mut d = doc;
    d["buffers"][0]["byteLength"] = json!(1u64 << 40);
    assert_has(&err_glb(&d, &bin), &["t.glb", "buffer 0"]);
}

#[test]
fn instances_over_the_budget_are_refused_before_reading() {
    // A 60 000-index strip (59 998 triangles) placed by 300 nodes: 18M triangles from 64 KB.
    let bytes = instanced_strip(60_000, 300);
    assert!(bytes.len() < 70_000);
    let msg = parse_gltf(&bytes, "many.glb", None)
        .unwrap_err()
        .to_string();
    assert_has(
        &msg,
        &[
            "many.glb",
            "places at least",
            "before reading",
            "MAX_SCENE_TRIANGLES",
        ],
    );
    // A shorter strip placed three times loads.
    let m = parse_gltf(&instanced_strip(600, 3), "few.glb", None).unwrap();
    assert_eq!(m.mesh.triangles.len(), 3 * 598);
    assert_eq!(m.mesh.positions.len(), 256, "the instances weld together");
}

#[test]
fn a_position_accessor_past_the_list_is_refused_not_a_panic() {
    // gltf-json 1.4.1's validation indexes `accessors` with it unchecked.
    let (mut doc, bin) = tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(7);
    assert_has(
        &err_glb(&doc, &bin),
        &[
            "t.glb",
            "invalid glTF",
            "meshes[0].primitives[0].attributes[\"POSITION\"]",
        ],
    );
    doc.as_object_mut().unwrap().remove("accessors");
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(0);
    assert_has(&err_glb(&doc, &bin), &["t.glb", "invalid glTF", "POSITION"]);
}

#[test]
fn validation_errors_quote_no_extension_or_attribute_name() {
    let (mut doc, bin) = tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
    doc["extensionsRequired"] = json!(["SECRET\nline", "SECRET_TWO"]);
    let msg = err_glb(&doc, &bin);
    assert_has(&msg, &["t.glb", "invalid glTF", "extensionsRequired[0]"]);
    assert!(!msg.contains("SECRET") && !msg.contains('\n'), "{msg:?}");
}

#[test]
fn a_path_with_a_newline_stays_on_one_line() {
    let dir = temp_dir("newline");
    let (mut doc, _) = tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
    doc["buffers"][0]["uri"] = json!("a%0Ab.bin");
    let path = dir.join("m.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let msg = load_gltf(&path).unwrap_err().to_string();
    assert!(!msg.contains('\n'), "{msg:?}");
    assert_has(&msg, &["m.gltf", "buffer 0", "a\\nb.bin"]);
    let msg = load_gltf(&dir.join("x\ny.glb")).unwrap_err().to_string();
    assert!(!msg.contains('\n'), "{msg:?}");
    assert_has(&msg, &["x\\ny.glb", "cannot read"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn buffer_files_missing_outside_or_not_files() {
    let dir = temp_dir("uris");
    let (mut doc, _) = tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
    std::fs::create_dir_all(dir.join("folder.bin")).unwrap();
    for (uri, parts) in [
        (
            "missing.bin",
            vec!["m.gltf", "buffer 0", "missing.bin", "cannot read"],
        ),
        (
            "../outside.bin",
            vec!["m.gltf", "buffer 0", "inside the model's folder"],
        ),
        (
            "/etc/passwd",
            vec!["m.gltf", "buffer 0", "inside the model's folder"],
        ),
        (
            "file:///etc/passwd",
            vec!["m.gltf", "buffer 0", "inside the model's folder"],
        ),
        (
            "folder.bin",
            vec!["m.gltf", "buffer 0", "folder.bin", "not a regular file"],
        ),
        (
            "data:application/octet-stream,raw",
            vec!["m.gltf", "buffer 0", "base64"],
        ),
        (
            "data:application/octet-stream;base64,!!!!",
            vec!["m.gltf", "buffer 0", "not valid base64"],
        ),
    ] {
        doc["buffers"][0]["uri"] = json!(uri);
        let path = dir.join("m.gltf");
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        let msg = load_gltf(&path).unwrap_err().to_string();
        assert_has(&msg, &parts);
        assert!(
            msg.contains(&dir.join("m.gltf").display().to_string()),
            "{msg}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_model_file_that_is_a_directory_or_missing() {
    let dir = temp_dir("notfile");
    let folder = dir.join("folder.glb");
    std::fs::create_dir_all(&folder).unwrap();
    assert_has(
        &load_gltf(&folder).unwrap_err().to_string(),
        &["folder.glb", "not a regular file"],
    );
    let msg = load(dir.join("nothing.glb").to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert_has(&msg, &["nothing.glb", "cannot read"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn no_triangles_bad_json_and_bad_graphs() {
    // Every triangle degenerate: three equal corners.
    let same = f32_bytes(&[[1.0, 2.0, 3.0]; 3]);
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36}],
    });
    // It loads, with nothing to draw, and says so.
    let m = parse_glb(&doc, &same).unwrap();
    assert!(m.mesh.triangles.is_empty());
    assert!(
        m.warnings.iter().any(|w| w.contains("nothing to draw")),
        "{:?}",
        m.warnings
    );
    // No scene at all: drawn from the root nodes, with a note.
    let mut d = doc.clone();
    d["scenes"] = json!([]);
    let m = parse_glb(&d, &same).unwrap();
    assert!(
        m.warnings.iter().any(|w| w.contains("has no scenes")),
        "{:?}",
        m.warnings
    );
    // No triangle primitive at all: refused.
    let mut d = doc.clone();
    d["meshes"][0]["primitives"][0]["mode"] = json!(0);
    assert_has(
        &err_glb(&d, &same),
        &["t.glb", "contains no triangles", "1 point or line"],
    );
    // A node that is its own child.
    let mut d = doc.clone();
    d["nodes"][0]["children"] = json!([0]);
    assert_has(&err_glb(&d, &same), &["t.glb", "node 0 is reached twice"]);
    // An index that points nowhere (the gltf crate's validation).
    let mut d = doc.clone();
    d["nodes"][0]["mesh"] = json!(7);
    assert_has(
        &err_glb(&d, &same),
        &["t.glb", "invalid glTF", "nodes[0].mesh"],
    );
    // Not JSON; the text is not quoted back.
    let msg = parse_gltf(b"{\"asset\": SECRET-TOKEN}", "bad.gltf", None)
        .unwrap_err()
        .to_string();
    assert_has(&msg, &["bad.gltf", "not glTF JSON", "line 1"]);
    assert!(!msg.contains("SECRET"), "{msg}");
    // A .gltf whose buffer needs a file, parsed without a folder.
    let mut d = doc;
    d["buffers"][0]["uri"] = json!("x.bin");
    let msg = parse_gltf(&serde_json::to_vec(&d).unwrap(), "nofolder.gltf", None)
        .unwrap_err()
        .to_string();
    assert_has(&msg, &["nofolder.gltf", "buffer 0", "separate file"]);
}

#[test]
fn a_deep_chain_of_nodes_is_refused_not_walked() {
    let n = 1100;
    let mut nodes: Vec<Value> = (0..n).map(|i| json!({"children": [i + 1]})).collect();
    nodes.push(json!({"mesh": 0}));
    let (doc, bin) = tet_doc(Some(5123), Value::Array(nodes), json!([0]));
    assert_has(&err_glb(&doc, &bin), &["t.glb", "deeper than 1024"]);
}

#[test]
fn the_fox_in_assets_loads() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/Fox.glb");
    let m = load_gltf(&path).unwrap();
    // 1728 corners, 576 triangles in the file (non-indexed), welded.
    assert!(
        m.mesh.triangles.len() > 500 && m.mesh.triangles.len() <= 576,
        "{}",
        m.mesh.triangles.len()
    );
    assert!(m.mesh.positions.len() < 1728, "corners are welded");
    let (lo, hi) = m.mesh.bounds().unwrap();
    // The accessor's own min/max: y from −0.12 to 78.9, z from −88.1 to 66.6.
    assert!(
        (hi.y - 78.907).abs() < 0.01 && (lo.z + 88.095).abs() < 0.01,
        "{lo} {hi}"
    );
    let scene = load(path.to_str().unwrap()).unwrap();
    assert_eq!(scene.name, "Fox");
    assert_eq!(scene.caster_triangle_count(), m.mesh.triangles.len());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any truncation of a valid GLB, and any few bytes overwritten, never panic the loader.
    #[test]
    fn damaged_glb_never_panics(
        cut in 0usize..400,
        flips in prop::collection::vec((0usize..400, any::<u8>()), 0..6),
    ) {
        let (doc, bin) = tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
        let mut bytes = glb(&doc, &bin);
        for (at, b) in flips {
            if let Some(x) = bytes.get_mut(at) {
                *x = b;
            }
        }
        bytes.truncate(cut.min(bytes.len()));
        let _ = parse_gltf(&bytes, "fuzz.glb", None);
    }
}

#[test]
fn quantized_positions_of_every_integer_type_dequantize_through_the_node() {
    let (doc, bin) = tet_doc(Some(5123), json!([{"mesh": 0}]), json!([0]));
    let reference = sorted_positions(&parse_glb(&doc, &bin).unwrap());
    for ty in [5120, 5121, 5122, 5123] {
        for normalized in [true, false] {
            let (doc, bin) = quantized_tet(ty, normalized);
            let m = parse_glb(&doc, &bin).unwrap_or_else(|e| panic!("{ty} {normalized}: {e}"));
            let got = sorted_positions(&m);
            assert_eq!(got.len(), 4, "{ty} {normalized}");
            for (g, r) in got.iter().zip(&reference) {
                assert!(close(*g, *r), "{ty} {normalized}: {g} vs {r}");
            }
            assert!((volume6(&m) - 1.0).abs() < 1e-4, "{ty} {normalized}");
        }
    }
    // Signed normalized bytes: -128 is -1 as glTF says (clamped), not -1.008.
    let (mut doc, mut bin) = quantized_tet(5120, true);
    bin[0] = 0x80; // the first corner's x: -128
    doc["nodes"][0]["scale"] = json!([1, 1, 1]);
    let m = parse_glb(&doc, &bin).unwrap();
    assert!(
        m.mesh.positions.iter().any(|p| p.x == -1.0),
        "{:?}",
        m.mesh.positions
    );
}

#[test]
fn accessors_without_a_buffer_view_are_zeros_and_sparse_on_zeros() {
    // Positions: no bufferView (four zeros), then sparse values for elements 1, 2, 3.
    let (doc, bin) = sparse_tet();
    let m = parse_glb(&doc, &bin).unwrap();
    let (tet, tet_bin) = tet_doc(Some(5121), json!([{"mesh": 0}]), json!([0]));
    assert_eq!(
        sorted_positions(&m),
        sorted_positions(&parse_glb(&tet, &tet_bin).unwrap())
    );
    assert!((volume6(&m) - 1.0).abs() < 1e-6);
    // 16M positions without a view or sparse values: all at the origin, nothing to draw, and
    // not 320 MB of zeros welded back into one point.
    let mut d = doc.clone();
    d["accessors"][0].as_object_mut().unwrap().remove("sparse");
    d["accessors"][0]["count"] = json!(16_000_000);
    d["meshes"][0]["primitives"][0]
        .as_object_mut()
        .unwrap()
        .remove("indices");
    let (m, used) = dbuffer_fuzzer::measure(|| parse_glb(&d, &bin).unwrap());
    assert!(
        m.mesh.triangles.is_empty() && used < 1 << 20,
        "{used} bytes"
    );
    // Without the sparse values: all four corners at the origin, nothing to draw.
    let mut d = doc.clone();
    d["accessors"][0].as_object_mut().unwrap().remove("sparse");
    let m = parse_glb(&d, &bin).unwrap();
    assert!(m.mesh.triangles.is_empty() && m.mesh.positions == [Vec3::ZERO]);
    // A .gltf whose buffer has no uri (its data left to the application): zeros, a note.
    let mut d = doc.clone();
    d["bufferViews"][0]["buffer"] = json!(1);
    d["buffers"] = json!([{"byteLength": bin.len()}, {"byteLength": 36}]);
    d["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        base64(&bin)
    ));
    let m = parse_gltf(&serde_json::to_vec(&d).unwrap(), "no-data.gltf", None).unwrap();
    assert!(m.mesh.triangles.is_empty());
    assert!(
        m.warnings.iter().any(|w| w.contains("buffer 1 has no uri")),
        "{:?}",
        m.warnings
    );
}

#[test]
fn what_dbuffer_does_not_draw_never_stops_a_load() {
    // Materials, textures, images, samplers, animations, skins and cameras that are broken,
    // partial or extended in every way the strict crate refused, around a good mesh.
    let (mut doc, bin) = tet_doc(
        Some(5123),
        json!([{"mesh": 0, "skin": 0, "camera": 9}]),
        json!([0]),
    );
    doc["meshes"][0]["primitives"][0]["material"] = json!(42);
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(99);
    doc["meshes"][0]["primitives"][0]["targets"] = json!([{"POSITION": 0}]);
    doc["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 7}}}]);
    doc["textures"] = json!([{"extensions": {"EXT_texture_webp": {"source": 3}}}]);
    doc["images"] = json!([{"uri": "missing.ktx2"}, 5]);
    doc["samplers"] = "not even an array".into();
    doc["animations"] = json!([{"channels": [{"sampler": 0, "target": {"path": "weights"}}],
                                "samplers": [{"input": 77, "output": 78}]}]);
    doc["skins"] = json!([{"joints": [12, 13]}]);
    doc["cameras"] = json!([{"type": "fisheye"}]);
    doc["extensionsUsed"] = json!(["KHR_materials_variants", "EXT_texture_webp"]);
    doc["extensionsRequired"] = json!(["EXT_texture_webp", "KHR_materials_pbrSpecularGlossiness"]);
    let m = parse_glb(&doc, &bin).unwrap();
    assert_eq!(m.mesh.triangles.len(), 4);
    let w = m.warnings.join("\n");
    for part in [
        "requires EXT_texture_webp: ignored, textures",
        "requires KHR_materials_pbrSpecularGlossiness: ignored, materials",
        "skinned mesh (node 0) drawn in its rest pose",
        "morph targets",
    ] {
        assert!(w.contains(part), "{part:?} not in {w}");
    }
}
