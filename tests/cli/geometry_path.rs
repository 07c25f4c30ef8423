//! `--geometry cpu|gpu`: the D-buffer's geometry stage on either side gives `render` the same
//! counts in `meta.json` and `dbuffer inspect` the same table (the stage itself is held to the
//! CPU's in tests/gpu/geometry_gpu.rs); a name that is neither is refused in one line.

use crate::support as cli;

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// The counts `render` wrote with `--geometry path`.
fn render_counts(scene: &str, path: &str) -> serde_json::Value {
    let out = cli::temp_dir("geometry", &format!("{scene}-{path}"));
    cli::run_ok(
        &[
            "render",
            scene,
            "--size",
            "48x48",
            "--dbuffer-size",
            "128",
            "--geometry",
            path,
        ],
        &out,
    );
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("meta.json")).expect("meta.json"))
            .expect("json");
    let _ = std::fs::remove_dir_all(&out);
    let keys = [
        "umbra_silhouette_edges",
        "penumbra_silhouette_edges",
        "umbra_volume_triangles",
        "penumbra_volume_triangles",
    ];
    serde_json::Value::Array(keys.iter().map(|k| meta[*k].clone()).collect())
}

/// The rows of `inspect`'s table with `--geometry path`.
fn inspect_table(scene: &str, path: &str) -> Vec<String> {
    let out = cli::dbuffer()
        .args(["inspect", scene, "--geometry", path])
        .output()
        .expect("the binary runs");
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let rows: Vec<String> = stdout
        .lines()
        .skip_while(|l| !l.starts_with("caster"))
        .take_while(|l| !l.starts_with("geometry"))
        .map(str::to_string)
        .collect();
    if path == "gpu" {
        assert!(stdout.contains("from the GPU stage"), "{stdout}");
    }
    rows
}

#[test]
fn render_and_inspect_count_the_same_on_either_path() {
    for scene in ["fig1-large-light", "fig7-concave", "table1-1440"] {
        let (cpu, gpu) = (render_counts(scene, "cpu"), render_counts(scene, "gpu"));
        assert!(cpu[2].as_u64().is_some_and(|n| n > 0), "{scene}: {cpu}");
        assert_eq!(cpu, gpu, "{scene}: render's counts, cpu then gpu");
        let (cpu, gpu) = (inspect_table(scene, "cpu"), inspect_table(scene, "gpu"));
        assert!(cpu.len() >= 2, "{scene}: {cpu:?}");
        assert_eq!(cpu, gpu, "{scene}: inspect's table, cpu then gpu");
    }
}

#[test]
fn an_unknown_geometry_path_is_refused_in_one_line() {
    for args in [
        &["render", "fig1-large-light", "--geometry", "fpga"][..],
        &["inspect", "fig1-large-light", "--geometry", "fpga"][..],
    ] {
        let out = cli::dbuffer().args(args).output().expect("the binary runs");
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(stderr.contains("fpga"), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}
