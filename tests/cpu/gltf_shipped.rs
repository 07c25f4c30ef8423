//! glTF models as people ship them: the bundled Fox put through `gltf-transform` 4.5 and
//! `gltfpack` 1.3 (`tests/models/shipped/`, remade by its `make.sh`), each loading to the
//! original's triangles within its quantization error; broken variants of them refused in one
//! line naming the extension, the accessor or the field; and (ignored, run by hand) a folder
//! of other people's test files, such as the Khronos glTF-Validator's, none of which may
//! panic, hang or take a second.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use dbuffer::scene::gltf::{load_gltf, load_gltf_scene, parse_gltf, GltfModel, SceneChoice};
use dbuffer::scene::{load_with, LoadOptions};
use glam::Vec3;
use serde_json::{json, Value};

use dbuffer_fuzzer::gltf_build::glb_raw;

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/models/shipped")
        .join(name)
}

fn fox() -> GltfModel {
    load_gltf(&Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/Fox.glb")).unwrap()
}

/// A GLB's JSON (as a value) and its BIN chunk.
fn split(bytes: &[u8]) -> (Value, Vec<u8>) {
    let (json, bin) = dbuffer::scene::gltf::split_glb(bytes).unwrap();
    (
        serde_json::from_slice(json).unwrap(),
        bin.unwrap_or_default().to_vec(),
    )
}

fn join(doc: &Value, bin: &[u8]) -> Vec<u8> {
    glb_raw(&serde_json::to_vec(doc).unwrap(), Some(bin))
}

/// Each triangle of `b` matched to one of `a` with the same corners in the same cyclic order
/// (the same winding), every corner within `tol` on each axis; returns how many of `a`'s
/// triangles found no match and the largest corner distance among the matches.
fn unmatched(a: &GltfModel, b: &GltfModel, tol: f32) -> (usize, f32) {
    let cell = 4.0 * tol;
    let key = |t: &[Vec3; 3]| {
        let c = (t[0] + t[1] + t[2]) / 3.0 / cell;
        (c.x.floor() as i64, c.y.floor() as i64, c.z.floor() as i64)
    };
    let mut grid: HashMap<(i64, i64, i64), Vec<[Vec3; 3]>> = HashMap::new();
    for t in b.mesh.triangle_corners() {
        grid.entry(key(&t)).or_default().push(t);
    }
    let (mut missing, mut worst) = (0, 0f32);
    for t in a.mesh.triangle_corners() {
        let (x, y, z) = key(&t);
        let mut best: Option<f32> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    for u in grid.get(&(x + dx, y + dy, z + dz)).into_iter().flatten() {
                        for r in 0..3 {
                            let d = (0..3)
                                .map(|k| (t[k] - u[(k + r) % 3]).abs().max_element())
                                .fold(0f32, f32::max);
                            if d <= tol {
                                best = Some(best.map_or(d, |b: f32| b.min(d)));
                            }
                        }
                    }
                }
            }
        }
        match best {
            Some(d) => worst = worst.max(d),
            None => missing += 1,
        }
    }
    (missing, worst)
}

/// One quantization step of `bits` bits over the model's largest extent: positions rounded
/// to such a grid (through the node transform that dequantizes them) are within half a step;
/// a whole step leaves room for the float arithmetic of placing them.
fn step(model: &GltfModel, bits: u32) -> f32 {
    let (lo, hi) = model.mesh.bounds().unwrap();
    (hi - lo).max_element() / ((1u32 << bits) - 1) as f32
}

#[test]
fn every_shipped_fox_variant_loads_to_the_original_triangles() {
    let original = fox();
    let n = original.mesh.triangles.len();
    // gltf-transform quantize and meshopt, and gltfpack, quantize positions to 14 bits (their
    // defaults); webp is made from the quantized Fox.
    for (file, bits, required) in [
        ("fox-quant.glb", 14, &["KHR_mesh_quantization"][..]),
        (
            "fox-meshopt.glb",
            14,
            &["EXT_meshopt_compression", "KHR_mesh_quantization"],
        ),
        (
            "fox-pack.glb",
            14,
            &["KHR_mesh_quantization", "EXT_meshopt_compression"],
        ),
        (
            "fox-webp.glb",
            14,
            &["KHR_mesh_quantization", "EXT_texture_webp"],
        ),
    ] {
        let bytes = std::fs::read(shipped(file)).unwrap();
        let (doc, _) = split(&bytes);
        for r in required {
            assert!(
                doc["extensionsRequired"]
                    .as_array()
                    .unwrap()
                    .contains(&json!(r)),
                "{file} was made without {r}: remake the corpus"
            );
        }
        let m = load_gltf(&shipped(file)).unwrap_or_else(|e| panic!("{e}"));
        let tol = step(&original, bits);
        assert_eq!(m.mesh.triangles.len(), n, "{file}");
        let (missing, worst) = unmatched(&original, &m, tol);
        assert_eq!(
            missing, 0,
            "{file}: {missing} of {n} triangles not within {tol}"
        );
        // Quantized, so not exact: the error is there, within the step (measured: 0.67 of it
        // for gltf-transform's 14-bit grid through the Fox's skin, 0.5 for gltfpack's).
        assert!(worst > 0.0 && worst <= tol, "{file}: {worst} vs {tol}");
        println!("{file}: {n} triangles, largest corner error {worst:.5} (step {tol:.5})");
        let (back, _) = unmatched(&m, &original, tol);
        assert_eq!(back, 0, "{file}: triangles the original lacks");
        if file == "fox-webp.glb" {
            assert!(
                m.warnings
                    .iter()
                    .any(|w| w.contains("EXT_texture_webp") && w.contains("ignored")),
                "{:?}",
                m.warnings
            );
        }
        for w in &m.warnings {
            assert!(!w.contains('\n'), "{w:?}");
        }
    }
}

#[test]
fn the_original_fox_is_skinned_and_drawn_in_its_rest_pose_with_a_warning() {
    let m = fox();
    assert!(
        m.warnings
            .iter()
            .any(|w| w.contains("skinned mesh") && w.contains("rest pose")),
        "{:?}",
        m.warnings
    );
    // What `dbuffer render Fox.glb` prints: the notes name the file.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/Fox.glb");
    let loaded = load_with(path.to_str().unwrap(), LoadOptions::default()).unwrap();
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("Fox.glb: ") && n.contains("rest pose")),
        "{:?}",
        loaded.notes
    );
}

#[test]
fn the_draco_fox_is_refused_naming_the_extension() {
    let msg = load_gltf(&shipped("fox-draco.glb"))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains(
            "fox-draco.glb: requires KHR_draco_mesh_compression, which dbuffer cannot decode"
        ),
        "{msg}"
    );
    assert!(!msg.contains('\n'));
    // Not required (a loader may fall back), but the accessors have no data: still named.
    let (mut doc, bin) = split(&std::fs::read(shipped("fox-draco.glb")).unwrap());
    doc.as_object_mut().unwrap().remove("extensionsRequired");
    let msg = parse_gltf(&join(&doc, &bin), "d.glb", None)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("KHR_draco_mesh_compression") && msg.contains("meshes[0].primitives[0]"),
        "{msg}"
    );
}

#[test]
fn a_sparse_accessor_on_zeros_loads_as_its_dense_twin() {
    let dense = load_gltf(&shipped("fan.glb")).unwrap();
    let sparse = load_gltf(&shipped("fan-sparse.glb")).unwrap();
    let (doc, _) = split(&std::fs::read(shipped("fan-sparse.glb")).unwrap());
    assert!(
        doc["accessors"][0]["bufferView"].is_null() && doc["accessors"][0]["sparse"].is_object()
    );
    assert_eq!(dense.mesh.triangles.len(), 12);
    assert_eq!(
        sparse.mesh, dense.mesh,
        "exactly the same, nothing is quantized"
    );
    // The centre (0, 0, 0) placed by the node at (0, 1, 0).
    assert!(sparse.mesh.positions.contains(&Vec3::new(0.0, 1.0, 0.0)));
}

/// The meshopt Fox with one change to its JSON or its bytes.
fn broken_meshopt(change: impl FnOnce(&mut Value, &mut Vec<u8>)) -> String {
    let (mut doc, mut bin) = split(&std::fs::read(shipped("fox-meshopt.glb")).unwrap());
    change(&mut doc, &mut bin);
    let msg = parse_gltf(&join(&doc, &bin), "bad.glb", None)
        .map(|m| format!("loaded {} triangles", m.mesh.triangles.len()))
        .unwrap_or_else(|e| e.to_string());
    assert!(!msg.contains('\n'), "{msg:?}");
    msg
}

/// The buffer view holding the POSITION stream of the meshopt Fox.
fn position_view(doc: &Value) -> usize {
    let acc = doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    doc["accessors"][acc]["bufferView"].as_u64().unwrap() as usize
}

#[test]
fn broken_meshopt_streams_are_refused_in_one_line() {
    let ext = "EXT_meshopt_compression";
    // A stream cut short: its byteLength says less than there was.
    let msg = broken_meshopt(|doc, _| {
        let v = position_view(doc);
        let e = &mut doc["bufferViews"][v]["extensions"][ext];
        let n = e["byteLength"].as_u64().unwrap();
        e["byteLength"] = json!(n / 2);
    });
    assert!(
        msg.starts_with("bad.glb: buffer view")
            && msg.contains(ext)
            && msg.contains("does not decode"),
        "{msg}"
    );
    // The stream's bytes overwritten with garbage.
    let msg = broken_meshopt(|doc, bin| {
        let v = position_view(doc);
        let e = &doc["bufferViews"][v]["extensions"][ext];
        let at = e["byteOffset"].as_u64().unwrap_or(0) as usize;
        for b in &mut bin[at..at + 64] {
            *b = 0xff;
        }
    });
    assert!(
        msg.contains(ext) && msg.contains("does not decode"),
        "{msg}"
    );
    // A count that lies: more vertices than the view's byteLength.
    let msg = broken_meshopt(|doc, _| {
        let v = position_view(doc);
        let e = &mut doc["bufferViews"][v]["extensions"][ext];
        e["count"] = json!(e["count"].as_u64().unwrap() * 1000);
    });
    assert!(
        msg.contains(ext) && msg.contains("count") && msg.contains("byteLength"),
        "{msg}"
    );
    // ... and the view agreeing with it: more than the stream can hold (a decompression bomb).
    let msg = broken_meshopt(|doc, _| {
        let v = position_view(doc);
        let stride = doc["bufferViews"][v]["extensions"][ext]["byteStride"]
            .as_u64()
            .unwrap();
        let count = 40_000_000u64 / stride;
        doc["bufferViews"][v]["extensions"][ext]["count"] = json!(count);
        doc["bufferViews"][v]["byteLength"] = json!(count * stride);
    });
    assert!(msg.contains(ext) && msg.contains("the count lies"), "{msg}");
    // ... and a count past what a model may place at all, refused from the count alone.
    let msg = broken_meshopt(|doc, _| {
        let v = position_view(doc);
        let stride = doc["bufferViews"][v]["extensions"][ext]["byteStride"]
            .as_u64()
            .unwrap();
        let count = 1u64 << 30;
        doc["bufferViews"][v]["extensions"][ext]["count"] = json!(count);
        doc["bufferViews"][v]["byteLength"] = json!(count * stride);
    });
    assert!(
        msg.contains(ext) && msg.contains("count 1073741824 is more than"),
        "{msg}"
    );
    // An unknown filter and an unknown mode.
    let msg = broken_meshopt(|doc, _| {
        let v = position_view(doc);
        doc["bufferViews"][v]["extensions"][ext]["filter"] = json!("WAVELET");
    });
    assert!(
        msg.contains(&format!("{ext}.filter")) && msg.contains("unknown filter"),
        "{msg}"
    );
    assert!(!msg.contains("WAVELET"), "{msg}");
    let msg = broken_meshopt(|doc, _| {
        let v = position_view(doc);
        doc["bufferViews"][v]["extensions"][ext]["mode"] = json!("POINTS");
    });
    assert!(msg.contains(&format!("{ext}.mode")), "{msg}");
    // A stride the decoder cannot take.
    let msg = broken_meshopt(|doc, _| {
        let v = position_view(doc);
        doc["bufferViews"][v]["extensions"][ext]["byteStride"] = json!(6);
    });
    assert!(msg.contains(&format!("{ext}.byteStride")), "{msg}");
    // An accessor whose count is more than its view holds.
    let msg = broken_meshopt(|doc, _| {
        let acc = doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .unwrap() as usize;
        doc["accessors"][acc]["count"] = json!(100_000);
    });
    assert!(
        msg.contains("accessor") && msg.contains("out of range"),
        "{msg}"
    );
    // A required geometry extension dbuffer does not know.
    let msg = broken_meshopt(|doc, _| {
        doc["extensionsRequired"]
            .as_array_mut()
            .unwrap()
            .push(json!("EXT_mesh_subdivision"));
    });
    assert!(
        msg.contains("requires EXT_mesh_subdivision, which dbuffer cannot decode"),
        "{msg}"
    );
    // Every one of these changes left the rest of the file as the tool wrote it: unchanged,
    // it loads.
    assert!(broken_meshopt(|_, _| {}).starts_with("loaded "));
}

#[test]
fn broken_quantized_positions_are_refused_naming_the_accessor() {
    let (doc, bin) = split(&std::fs::read(shipped("fox-quant.glb")).unwrap());
    let acc = doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let mut d = doc.clone();
    d["accessors"][acc]["componentType"] = json!(5125);
    let msg = parse_gltf(&join(&d, &bin), "q.glb", None)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains(&format!("accessor {acc}")) && msg.contains("UNSIGNED_INT VEC3"),
        "{msg}"
    );
    let mut d = doc.clone();
    d["accessors"][acc]["componentType"] = json!(1234);
    let msg = parse_gltf(&join(&d, &bin), "q.glb", None)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains(&format!("accessors[{acc}].componentType is 1234")),
        "{msg}"
    );
}

#[test]
fn scene_n_picks_a_scene_and_a_file_without_scenes_draws_its_root_nodes() {
    let (mut doc, bin) = split(&std::fs::read(shipped("fan.glb")).unwrap());
    // Scene 1 moves the fan up by 10 through a new parent node.
    let nodes = doc["nodes"].as_array_mut().unwrap();
    nodes.push(json!({"translation": [0, 10, 0], "children": [0]}));
    doc["scenes"] = json!([{"nodes": [0]}, {"nodes": [1]}]);
    let bytes = join(&doc, &bin);
    let y = |m: &GltfModel| m.mesh.bounds().unwrap().0.y;
    let first =
        dbuffer::scene::gltf::parse_gltf_scene(&bytes, "s.glb", None, SceneChoice::default())
            .unwrap();
    let second = dbuffer::scene::gltf::parse_gltf_scene(
        &bytes,
        "s.glb",
        None,
        SceneChoice { scene: Some(1) },
    )
    .unwrap();
    assert!((y(&first) - 1.0).abs() < 1e-6 && (y(&second) - 11.0).abs() < 1e-6);
    let msg = dbuffer::scene::gltf::parse_gltf_scene(
        &bytes,
        "s.glb",
        None,
        SceneChoice { scene: Some(2) },
    )
    .unwrap_err()
    .to_string();
    assert!(
        msg.contains("--scene 2: the file has 2 scenes (0 to 1)"),
        "{msg}"
    );
    // Without `scenes`: the root node (1, holding 0), with a note.
    doc.as_object_mut().unwrap().remove("scenes");
    doc.as_object_mut().unwrap().remove("scene");
    let m = parse_gltf(&join(&doc, &bin), "s.glb", None).unwrap();
    assert!((y(&m) - 11.0).abs() < 1e-6);
    assert!(
        m.warnings.iter().any(|w| w.contains("has no scenes")),
        "{:?}",
        m.warnings
    );

    // The same through the scene loader, and --scene refused where it means nothing.
    let dir = std::env::temp_dir().join(format!("dbuffer-scene-n-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("two.glb");
    std::fs::write(&path, &bytes).unwrap();
    let m = load_gltf_scene(&path, SceneChoice { scene: Some(1) }).unwrap();
    assert!((y(&m) - 11.0).abs() < 1e-6);
    let loaded = load_with(
        path.to_str().unwrap(),
        LoadOptions {
            gltf_scene: Some(1),
        },
    )
    .unwrap();
    assert_eq!(loaded.scene.caster_triangle_count(), 12);
    let msg = load_with(
        "fig7-concave",
        LoadOptions {
            gltf_scene: Some(1),
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        msg.contains("--scene 1") && msg.contains(".gltf or .glb"),
        "{msg}"
    );
    // `gltf_scene` in a scene file.
    let toml = "[light]\ncenter = [0, 20, 0]\nnormal = [0, -1, 0]\nradius = 0.5\n\n\
                [[object]]\nmesh = \"two.glb\"\ngltf_scene = 1\n";
    std::fs::write(dir.join("s.toml"), toml).unwrap();
    let scene = dbuffer::scene::load(dir.join("s.toml").to_str().unwrap()).unwrap();
    assert!((scene.objects[0].mesh.bounds().unwrap().0.y - 11.0).abs() < 1e-5);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A folder of glTF test files (`DBUFFER_GLTF_SUITE=DIR`, e.g. the test folder of the Khronos
/// glTF-Validator, which is not part of this repository): every file is
/// loaded, none may panic or take a second; a file its `.report.json` calls valid (no errors)
/// that holds a triangle mesh with positions must load. Prints the counts and each refusal.
#[test]
#[ignore = "needs DBUFFER_GLTF_SUITE, a folder of other people's glTF files"]
fn a_validator_suite_loads_without_panics_or_hangs() {
    let Some(root) = std::env::var_os("DBUFFER_GLTF_SUITE") else {
        panic!("set DBUFFER_GLTF_SUITE to a folder of .gltf/.glb files");
    };
    let mut files = Vec::new();
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if dbuffer::scene::gltf::is_gltf_path(&p) {
                out.push(p);
            }
        }
    }
    walk(Path::new(&root), &mut files);
    files.sort();
    assert!(!files.is_empty());
    let (mut loaded, mut refused, mut must, mut failed) = (0, 0, 0, Vec::new());
    let mut slowest = (Duration::ZERO, PathBuf::new());
    for f in &files {
        let start = Instant::now();
        let result = std::panic::catch_unwind(|| load_gltf(f));
        let took = start.elapsed();
        if took > slowest.0 {
            slowest = (took, f.clone());
        }
        assert!(took < Duration::from_secs(1), "{}: {took:?}", f.display());
        let result = result.unwrap_or_else(|_| panic!("{} panicked", f.display()));
        let report = f.with_file_name(format!(
            "{}.report.json",
            f.file_name().unwrap().to_string_lossy()
        ));
        let valid = std::fs::read(&report)
            .ok()
            .and_then(|b| serde_json::from_slice::<Value>(&b).ok())
            .and_then(|r| r["issues"]["numErrors"].as_u64())
            == Some(0);
        let has_mesh = holds_triangles(f);
        if valid && has_mesh {
            must += 1;
        }
        match result {
            Ok(_) => loaded += 1,
            Err(e) => {
                refused += 1;
                let msg = e.to_string();
                assert!(!msg.contains('\n'), "{msg:?}");
                println!("refused{} {msg}", if valid { " (valid)" } else { "" });
                if valid && has_mesh {
                    failed.push(msg);
                }
            }
        }
    }
    println!(
        "{} files: {loaded} loaded, {refused} refused; {must} valid with a triangle mesh, {} of \
         them refused; slowest {:?} ({})",
        files.len(),
        failed.len(),
        slowest.0,
        slowest.1.display()
    );
    assert!(
        failed.is_empty(),
        "valid files refused:\n{}",
        failed.join("\n")
    );
}

/// Whether a file's JSON has a mesh primitive with triangles (mode 4, 5 or 6) and POSITION.
fn holds_triangles(path: &Path) -> bool {
    let Ok(bytes) = std::fs::read(path) else {
        return false;
    };
    let json: &[u8] = if bytes.starts_with(b"glTF") {
        match dbuffer::scene::gltf::split_glb(&bytes) {
            Ok((j, _)) => j,
            Err(_) => return false,
        }
    } else {
        &bytes
    };
    let Ok(doc) = serde_json::from_slice::<Value>(json) else {
        return false;
    };
    doc["meshes"].as_array().into_iter().flatten().any(|m| {
        m["primitives"].as_array().into_iter().flatten().any(|p| {
            matches!(p["mode"].as_u64().unwrap_or(4), 4..=6) && p["attributes"]["POSITION"].is_u64()
        })
    })
}
