//! `dbuffer study` end to end, through the binary, on a small study (two scenes, two settings
//! of each method, a small image): its files are right and complete, a second run reports the
//! same errors bit for bit, the same folder again takes every cell from its cache, a cell's
//! error is what `compare` reports for the same scene, method, knobs, sizes and K, and its cost
//! is timed as `bench` times it (the same passes from the same source); bad study files are
//! refused naming the key before any work. No timing is asserted beyond "the same protocol".

use std::path::{Path, PathBuf};

use dbuffer::bench::{FrameSource, Report};
use dbuffer::compare::report::Report as CompareReport;
use dbuffer::study::Study;

use crate::support::{self as cli, dbuffer, run_ok};

fn temp_dir(name: &str) -> PathBuf {
    cli::temp_dir("study-cli", name)
}

/// The suite's study: two scenes (one of many casters), two settings of the methods that have a
/// quality knob, at 64², K = 64.
const SMALL: &str = r#"
scenes = ["table1-224", "pergola"]
size = "64x64"
samples = 64
warmup = 1
frames = 2

[methods]
dbuffer = { dbuffer_size = [512, 1024] }
dbuffer-fused = { mask_samples = [32, 128] }
hard = "defaults"
pcss = [{ blocker_taps = 8, filter_taps = 12 }, { blocker_taps = 16, filter_taps = 32 }]
smrt = { smrt_rays = [2, 7], smrt_steps = 8 }
msm = { msm_radius = [1, 3] }
sampled = { lights = [4, 16] }
wedges = "defaults"
reference = { samples = [1, 16] }
"#;

fn run_study(file: &Path, out: &Path) -> (Study, String) {
    let output = dbuffer()
        .arg("study")
        .arg(file)
        .arg("--out")
        .arg(out)
        .output()
        .expect("the binary runs");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{stderr}");
    let json = std::fs::read(out.join("study.json")).expect("study.json written");
    let study: Study = serde_json::from_slice(&json).expect("study.json parses as a Study");
    (study, stderr)
}

fn errors(study: &Study) -> Vec<(String, String, String, Option<[u64; 5]>)> {
    study
        .scenes
        .iter()
        .flat_map(|s| {
            s.cells.iter().map(|c| {
                (
                    c.scene.clone(),
                    c.method.clone(),
                    c.setting.clone(),
                    c.error.map(|e| {
                        [e.class_mismatch_pct, e.mae, e.penumbra_mae, e.p99, e.flip]
                            .map(f64::to_bits)
                    }),
                )
            })
        })
        .collect()
}

#[test]
fn a_small_study_writes_its_files_repeats_its_errors_and_resumes_from_its_cache() {
    let dir = temp_dir("small");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("small.toml");
    std::fs::write(&file, SMALL).unwrap();
    let a = dir.join("a");
    let (study, stderr) = run_study(&file, &a);
    assert!(stderr.contains("study on "), "{stderr}");
    assert!(!study.machine.adapter.trim().is_empty() && !study.machine.cpu.is_empty());
    assert_eq!(study.scenes.len(), 2);
    assert!(!study.stopped);
    for scene in &study.scenes {
        // 2 + 2 + 1 + 2 + 2 + 2 + 2 + 1 + 2 cells.
        assert_eq!(scene.cells.len(), 16, "{}", scene.name);
        assert!(
            scene.noise_floor > 0.0 && scene.noise_floor < 0.05,
            "{}",
            scene.noise_floor
        );
        for c in &scene.cells {
            match &c.not_measured {
                Some(why) => panic!(
                    "{} {} {}: not measured: {why}",
                    scene.name, c.method, c.setting
                ),
                None => {
                    let e = c.error.expect("an error");
                    let cost = c.cost.as_ref().expect("a cost");
                    assert!(cost.frame_ms > 0.0, "{} {}", c.method, c.setting);
                    assert!(e.penumbra_pixels > 0 && e.pixels > 0);
                    assert!((0.0..=1.0).contains(&e.penumbra_mae));
                }
            }
        }
        // A method's dearer setting is named as it was asked for.
        assert!(scene
            .cells
            .iter()
            .any(|c| c.method == "pcss" && c.setting == "blocker-taps 16, filter-taps 32"));
    }
    let md = std::fs::read_to_string(a.join("study.md")).expect("study.md written");
    for part in [
        "## `table1-224`",
        "## `pergola`",
        "**Equal cost**",
        "**Equal error**",
        "**Front**",
    ] {
        assert!(md.contains(part), "study.md lacks {part}:\n{md}");
    }
    for name in ["table1-224.png", "pergola.png", "pergola-flip.png"] {
        let img = image::open(a.join("plots").join(name)).expect("a plot decodes");
        assert_eq!((img.width(), img.height()), (1100, 720), "{name}");
        let rgb = img.to_rgb8();
        let coloured = rgb
            .pixels()
            .filter(|p| p[0] != p[1] || p[1] != p[2])
            .count();
        assert!(
            coloured > 1000,
            "{name}: the methods' lines are drawn ({coloured} px)"
        );
    }

    // The same study into another folder: the same errors, to the bit.
    let b = dir.join("b");
    let (again, _) = run_study(&file, &b);
    assert_eq!(
        errors(&again),
        errors(&study),
        "a second run measures the same errors"
    );
    assert_eq!(again.cached, 0);

    // The first folder again: every cell from the cache, nothing measured.
    let (resumed, stderr) = run_study(&file, &a);
    assert_eq!(resumed.measured, 0, "{stderr}");
    assert_eq!(resumed.cached, 32);
    assert_eq!(errors(&resumed), errors(&study));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_cell_scores_as_compare_and_is_timed_as_bench() {
    let dir = temp_dir("match");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("one.toml");
    std::fs::write(
        &file,
        "scenes = [\"table1-224\"]\nsize = \"64x64\"\nsamples = 64\ndbuffer_size = 512\n\
         frames = 3\n[methods]\npcss = [{ blocker_taps = 8, filter_taps = 12 }]\n",
    )
    .unwrap();
    let (study, _) = run_study(&file, &dir.join("study"));
    let cell = &study.scenes[0].cells[0];
    let e = cell.error.expect("measured");

    // compare at the same size, K, map size and knobs.
    let cmp = dir.join("compare");
    run_ok(
        &[
            "compare",
            "table1-224",
            "--size",
            "64x64",
            "--samples",
            "64",
            "--dbuffer-size",
            "512",
            "--blocker-taps",
            "8",
            "--filter-taps",
            "12",
            "--methods",
            "pcss",
        ],
        &cmp,
    );
    let report: CompareReport =
        serde_json::from_slice(&std::fs::read(cmp.join("report.json")).unwrap()).unwrap();
    let row = report
        .methods
        .iter()
        .find(|r| r.method == "pcss")
        .expect("compare scored pcss");
    assert_eq!(e.class_mismatch_pct, row.class_mismatch_pct);
    assert_eq!(e.mae, row.mae);
    assert_eq!(e.penumbra_mae, row.penumbra_mae);
    assert_eq!(e.p99, row.p99);
    assert_eq!(e.flip, row.flip_mean);
    assert_eq!(e.penumbra_pixels, row.penumbra_pixels);

    // bench, the same method and scene at the same size and map size.
    let bench = dir.join("bench");
    run_ok(
        &[
            "bench",
            "--scenes",
            "table1-224",
            "--sizes",
            "64",
            "--methods",
            "pcss",
            "--frames",
            "3",
            "--warmup",
            "1",
            "--max-triangles",
            "1024",
        ],
        &bench,
    );
    let report: Report =
        serde_json::from_slice(&std::fs::read(bench.join("bench.json")).unwrap()).unwrap();
    let pcss: dbuffer::render::Method = "pcss".parse().unwrap();
    let timing = report
        .timing("table1-224", 64, pcss)
        .expect("bench timed pcss");
    let cost = cell.cost.as_ref().expect("timed");
    assert_eq!(cost.timing.frame_source, timing.frame_source);
    let passes = |t: &dbuffer::bench::Timing| -> Vec<String> {
        t.passes.iter().map(|p| p.pass.clone()).collect()
    };
    assert_eq!(
        passes(&cost.timing),
        passes(timing),
        "the same passes are timed"
    );
    if timing.frame_source == FrameSource::GpuTimestamps {
        assert_eq!(
            cost.frame_ms, cost.timing.frame_ms.median,
            "the frame is the passes' sum"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_study_file_is_refused_naming_the_key_before_any_work() {
    let dir = temp_dir("bad");
    std::fs::create_dir_all(&dir).unwrap();
    for (i, (text, wanted)) in [
        (
            "[methods]\npcsss = \"default\"",
            "methods.pcsss: unknown method 'pcsss'",
        ),
        (
            "[methods]\npcss = { blocker = [8] }",
            "methods.pcss.blocker: pcss has no knob 'blocker'",
        ),
        (
            "[methods]\npcss = { blocker_taps = [99] }",
            "methods.pcss.blocker_taps[0]: --blocker-taps expects 1 to 64, found 99",
        ),
        (
            "[methods]\npcss = { blocker_taps = [] }",
            "methods.pcss.blocker_taps: an empty list sweeps nothing",
        ),
        ("scenes = [\"no-such-scene\"]", "no-such-scene"),
        // 910 default cells of 16 Mi pixels each: over the study's pixel budget.
        ("size = \"4096x4096\"", "MAX_STUDY_PIXELS"),
        // One image over what a cell may be (a cell is drawn and scored as compare does).
        ("size = \"16384x16384\"", "MAX_COMPARE_PIXELS"),
    ]
    .iter()
    .enumerate()
    {
        let file = dir.join(format!("bad{i}.toml"));
        std::fs::write(&file, text).unwrap();
        let out_dir = dir.join(format!("out{i}"));
        let out = dbuffer()
            .arg("study")
            .arg(&file)
            .arg("--out")
            .arg(&out_dir)
            .output()
            .expect("the binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{text}: accepted");
        assert!(stderr.contains(wanted), "{text}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(
            !out_dir.exists(),
            "{text}: refused before any work, yet {} exists",
            out_dir.display()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
