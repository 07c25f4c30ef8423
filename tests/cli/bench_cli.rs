//! `dbuffer bench` end to end, through the binary, on a tiny configuration (one scene, a small
//! image, one frame): bench.json parses and has a row for every method and the adapter's name,
//! bench.md has the tables, the scaling plot decodes and has something drawn on it; bad flags are
//! refused with a one-line reason and nothing written. No timing is asserted.

use std::path::PathBuf;

use dbuffer::bench::{FrameSource, Report};
use dbuffer::render::Method;

use crate::support::{self as cli, dbuffer};

fn temp_dir(name: &str) -> PathBuf {
    cli::temp_dir("bench-cli", name)
}

#[test]
fn tiny_bench_writes_json_markdown_and_plot() {
    let dir = temp_dir("ok");
    let out = dbuffer()
        .args([
            "bench",
            "--scenes",
            "table1-224",
            "--sizes",
            "32",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--max-triangles",
            "4096",
            "--out",
        ])
        .arg(&dir)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stderr}");
    // Every method, and the D-buffer once more under the 16-gon inscribed in the disk.
    let methods = format!("table1-224 32²: {} cases", Method::all().len() + 1);
    assert!(stderr.contains(&methods), "progress on stderr: {stderr}");

    let json = std::fs::read(dir.join("bench.json")).expect("bench.json written");
    let report: Report = serde_json::from_slice(&json).expect("bench.json parses as a Report");
    assert!(!report.adapter.trim().is_empty(), "adapter named");
    assert_eq!(report.frames, 1);
    for &m in Method::all() {
        let run = report
            .run("table1-224", 32, m)
            .unwrap_or_else(|| panic!("no row for {m}"));
        assert!(
            run.timing.is_some() != run.error.is_some(),
            "{m}: exactly one of timing and error"
        );
    }
    for m in [Method::DBUFFER, Method::HARD] {
        let t = report.timing("table1-224", 32, m).expect("renders");
        assert!(
            t.frame_ms.median > 0.0 && t.wall_ms.median > 0.0,
            "{m}: {t:?}"
        );
        assert!(t.hit_pixels > 0 && t.hit_pixels <= 32 * 32);
        if report.timestamps {
            assert!(t.pass("shadow_map").is_some() && t.pass("camera_pass").is_some());
            assert!(t.light_ms.is_some());
        }
    }
    assert_eq!(report.scenes.len(), 1);
    assert_eq!(report.scenes[0].caster_triangles, 224);
    let scaled: Vec<usize> = report.scaling.iter().map(|p| p.triangles).collect();
    assert_eq!(scaled, [1024, 4096], "scaling stops at --max-triangles");
    let c = report.coherence.as_ref().expect("coherence measured");
    assert_eq!(
        c.rebuilds as usize, c.frames,
        "one geometry build per rebuilt frame"
    );
    assert_eq!(report.targets.len(), 12);
    // The fused D-buffer's targets are judged on this run's scene, against the D-buffer's and
    // the wedges' frames.
    for name in [
        "dbuffer-fused frame / D-buffer",
        "dbuffer-fused frame / wedges",
    ] {
        let t = report
            .targets
            .iter()
            .find(|t| t.name.starts_with(name))
            .unwrap_or_else(|| panic!("{name}: {:?}", report.targets));
        assert!(t.measured.is_some_and(|m| m > 0.0), "{t:?}");
    }
    let display = report.display.first().expect("the display path measured");
    assert_eq!((display.scene.as_str(), display.size), ("table1-224", 32));
    assert!(display.lab_still.wall_ms.median > 0.0 && display.readback.wall_ms.median > 0.0);
    if report.timestamps {
        assert!(display.floor_gpu_ms.is_some());
    }
    let reference = report
        .timing("table1-224", 32, Method::REFERENCE)
        .expect("the reference renders");
    assert_eq!(
        reference.frame_source,
        FrameSource::FencedWall,
        "its rays are CPU work"
    );
    assert!(reference.rays_ms.is_some());
    assert!(report.reference_rays_per_s.is_some_and(|r| r > 0.0));

    let md = std::fs::read_to_string(dir.join("bench.md")).expect("bench.md written");
    for column in [
        "| scene | caster tris | size | geometry ms (CPU) | light pass ms (GPU) | camera pass ms (GPU) | frame ms | fps |",
        "| method | 32² |",
        "| `table1-224` | 224 | 32² |",
        "### The lab's display path",
        "### Frame coherence",
        "### Geometry scaling",
        "### Targets",
    ] {
        assert!(md.contains(column), "bench.md lacks {column:?}:\n{md}");
    }
    for &m in Method::all() {
        let label = dbuffer::bench::Case::for_method(m).label;
        // A method timed under the other kind of light: "| linear-ssm 2 (line light) |".
        let converted = m
            .needs()
            .map(|kinds| format!("| {label} ({} light) |", kinds[0]));
        assert!(
            md.contains(&format!("| {label} |")) || converted.is_some_and(|row| md.contains(&row)),
            "no competition row for {label}"
        );
    }
    assert!(
        md.contains("| method | frame ms | × dbuffer | × hard |"),
        "bench.md lacks the ratios to the D-buffer and the hard shadow map"
    );
    assert!(stdout.contains("### Table 1"), "the tables are printed too");

    let png = image::open(dir.join("geometry-scaling.png"))
        .expect("the plot decodes")
        .to_rgb8();
    let mut colours: Vec<[u8; 3]> = png.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(
        colours.len() > 20,
        "the plot is not blank ({} colours)",
        colours.len()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_flags_are_refused_with_a_reason() {
    let cases: [(&[&str], &str); 5] = [
        (&["--frames", "0"], "--frames"),
        (&["--sizes", "300x300"], "--sizes"),
        (&["--sizes", "4"], "image size 4"),
        (&["--scenes", "no-such-scene"], "no-such-scene"),
        (&["--max-triangles", "10"], "10 triangles"),
    ];
    for (i, (args, expect)) in cases.into_iter().enumerate() {
        let dir = temp_dir(&format!("bad{i}"));
        let out = dbuffer()
            .arg("bench")
            .args(args)
            .arg("--out")
            .arg(&dir)
            .output()
            .expect("the binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} accepted");
        assert!(stderr.contains(expect), "{args:?}: {stderr}");
        assert_eq!(
            stderr.lines().filter(|l| l.starts_with("dbuffer:")).count(),
            1,
            "one-line reason: {stderr}"
        );
        assert!(!dir.exists(), "{args:?} wrote {}", dir.display());
        // Refused before the GPU starts, and the cause said once.
        assert!(!stderr.contains("bench on "), "{args:?}: {stderr}");
        assert!(stderr.matches(expect).count() <= 2, "{args:?}: {stderr}");
    }
    let out = dbuffer()
        .args(["bench", "--fast"])
        .output()
        .expect("the binary runs");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--fast"));
}

/// A user's method from a WGSL file is timed like a method of the registry: its row has a
/// timing, beside the built-in it is drawn like.
#[test]
fn a_users_method_is_timed() {
    let dir = temp_dir("user");
    let out = dbuffer()
        .args([
            "bench",
            "--scenes",
            "table1-224",
            "--sizes",
            "32",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--max-triangles",
            "1024",
            "--methods",
            "dbuffer,file:examples/methods/dbuffer_vt.wgsl",
            "--out",
        ])
        .arg(&dir)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let json = std::fs::read(dir.join("bench.json")).expect("bench.json written");
    let report: Report = serde_json::from_slice(&json).expect("bench.json parses as a Report");
    let user = report
        .runs
        .iter()
        .find(|r| r.method == "user-dbuffer_vt")
        .unwrap_or_else(|| panic!("no row for the user's method: {stderr}"));
    assert!(user.timing.is_some(), "not timed: {:?}", user.error);
    assert!(report.run("table1-224", 32, Method::DBUFFER).is_some());
}
