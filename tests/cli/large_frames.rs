//! Frames past the readback's banding threshold, through every command that reads them back:
//! `render`, `compare`, `compare --orbit` and `animate` at 4000×2100, whose depth (16,128-byte
//! rows, 33.9 MB) is more than one 32 MiB staging buffer and is read through its `R32Float`
//! copy, and whose colour, V and cost targets come back in bands. Each big run's files are the
//! same command's files at 400×210 (the same view), the big image box-filtered 10×10: a depth
//! read that failed, or a band out of place, is far off. Cheap methods (`--methods hard`, one
//! reference sample) keep them to seconds of work each.
//!
//! The largest sizes the limits allow (`MAX_COMPARE_PIXELS`, `MAX_ANIMATE_PIXELS`) run behind
//! `cargo test --release --locked --test cli large_frames -- --ignored` (minutes;
//! docs/development/testing.md), with the peak resident memory of each run checked against
//! `MEMORY_BOUND_BYTES`.
//!
//! Errors: every subcommand fed a GPU error (`DBUFFER_GPU_FAULT`) prints it as lines, with no
//! literal `\n`, and leaves its folder as it was.

use std::path::{Path, PathBuf};

use dbuffer::output::read_exr_rgba;

use crate::support::{self as cli, dbuffer, run_ok};

/// 8.4 Mpx: past the banding threshold in every target (a thin image: the depth of any image
/// over 8.39 Mpx is more than 32 MiB).
const BIG: (u32, u32) = (4000, 2100);
/// The same view, a tenth on a side.
const SMALL: (u32, u32) = (400, 210);
const F: u32 = 10;

/// The depth's bytes as a staging buffer holds them (rows padded to 256 bytes): 16,128 a row.
const BIG_DEPTH_BYTES: u64 = (BIG.0 as u64 * 4).div_ceil(256) * 256 * BIG.1 as u64;

const _: () = {
    // The whole depth is more than one staging buffer, and SMALL is BIG a tenth on a side.
    assert!(BIG_DEPTH_BYTES > dbuffer::render::readback::STAGING_CAP);
    assert!(BIG.0 == F * SMALL.0 && BIG.1 == F * SMALL.1);
};

fn temp_dir(name: &str) -> PathBuf {
    cli::temp_dir("large-frames", name)
}

fn size((w, h): (u32, u32)) -> String {
    format!("{w}x{h}")
}

/// `dbuffer ARGS --size S` at BIG and at SMALL, each into a folder of its own (named after
/// `name`): the two folders.
fn at_both_sizes(name: &str, args: &[&str]) -> (PathBuf, PathBuf) {
    let (big, small) = (
        temp_dir(&format!("{name}-big")),
        temp_dir(&format!("{name}-small")),
    );
    for (dir, s) in [(&big, BIG), (&small, SMALL)] {
        run_ok(&[args, &["--size", &size(s)][..]].concat(), dir);
    }
    (big, small)
}

/// A PNG's RGB pixels and size.
fn png(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    let (w, h) = img.dimensions();
    (w, h, img.pixels().map(|p| p.0).collect())
}

/// The mean over every pixel and channel of |big box-filtered F×F − small| (BIG and SMALL),
/// in 8-bit steps.
fn image_difference(big: &Path, small: &Path) -> f64 {
    box_difference(big, small, F)
}

/// The mean over every pixel and channel of |big box-filtered f×f − small|, in 8-bit steps,
/// for a big image `f` times the small one on a side.
fn box_difference(big: &Path, small: &Path, f: u32) -> f64 {
    let (bw, bh, b) = png(big);
    let (sw, sh, s) = png(small);
    assert_eq!((bw, bh), (f * sw, f * sh), "{}", big.display());
    let mut sum = 0.0;
    for (i, px) in s.iter().enumerate() {
        let (sx, sy) = (i as u32 % sw, i as u32 / sw);
        for c in 0..3 {
            let mut block = 0.0;
            for y in sy * f..(sy + 1) * f {
                for x in sx * f..(sx + 1) * f {
                    block += f64::from(b[(y * bw + x) as usize][c]);
                }
            }
            sum += (block / f64::from(f * f) - f64::from(px[c])).abs();
        }
    }
    sum / (3 * s.len()) as f64
}

/// A comparison's report.json.
fn report_of(dir: &Path) -> dbuffer::compare::report::Report {
    let json = std::fs::read_to_string(dir.join("report.json")).unwrap();
    serde_json::from_str(&json).unwrap_or_else(|e| panic!("{e}"))
}

/// An APNG's size and frame count.
fn apng_info(path: &Path) -> ((u32, u32), Option<u32>) {
    let apng = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let reader = png::Decoder::new(std::io::Cursor::new(apng))
        .read_info()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let info = reader.info();
    (
        (info.width, info.height),
        info.animation_control.map(|a| a.num_frames),
    )
}

/// The mean |V| difference between a big visibility EXR box-filtered F×F and a small one, over
/// the small pixels whose block shows a surface throughout (alpha 1), and how many those are.
fn visibility_difference(big: &Path, small: &Path) -> (f64, usize) {
    let (bw, bh, b) = read_exr_rgba(big).unwrap_or_else(|e| panic!("{e}"));
    let (sw, sh, s) = read_exr_rgba(small).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(((bw, bh), (sw, sh)), (BIG, SMALL));
    let (mut sum, mut n) = (0.0, 0usize);
    for (i, px) in s.iter().enumerate() {
        let (sx, sy) = (i as u32 % sw, i as u32 / sw);
        let block: Vec<[f32; 4]> = (sy * F..(sy + 1) * F)
            .flat_map(|y| (sx * F..(sx + 1) * F).map(move |x| (y * bw + x) as usize))
            .map(|j| b[j])
            .collect();
        if px[3] < 1.0 || block.iter().any(|p| p[3] < 1.0) {
            continue;
        }
        let mean = block.iter().map(|p| f64::from(p[0])).sum::<f64>() / block.len() as f64;
        sum += (mean - f64::from(px[0])).abs();
        n += 1;
    }
    (sum / n.max(1) as f64, n)
}

/// `render --method hard` past the threshold: its image, V and surface are the small render's.
/// (Before the depth was read through its copy, the whole readback failed and image.png came
/// out black without an error.)
#[test]
fn render_past_the_banding_threshold_is_the_small_render_resampled() {
    let (big, small) = at_both_sizes("render", &["render", "fig7-concave", "--method", "hard"]);
    let d = image_difference(&big.join("image.png"), &small.join("image.png"));
    assert!(d < 2.0, "image.png: {d} steps from the small render");
    let (v, n) = visibility_difference(&big.join("visibility.exr"), &small.join("visibility.exr"));
    assert!(
        n > 30_000 && v < 0.02,
        "visibility.exr: {v} over {n} pixels"
    );
    // The surface each pixel shows, from the depth: at the small pixel's centre (the corner the
    // block's four middle pixels share) the big render's mean position is the small pixel's,
    // within a centimetre on a scene 10 m across, but where an edge runs between them.
    let (bw, _, b) = read_exr_rgba(&big.join("position.exr")).unwrap();
    let (sw, _, s) = read_exr_rgba(&small.join("position.exr")).unwrap();
    let (mut near, mut compared) = (0usize, 0usize);
    for (i, px) in s.iter().enumerate().filter(|(_, p)| p[3] == 1.0) {
        let (cx, cy) = ((i as u32 % sw) * F + F / 2, (i as u32 / sw) * F + F / 2);
        let middle: Vec<[f32; 4]> = [(cx - 1, cy - 1), (cx, cy - 1), (cx - 1, cy), (cx, cy)]
            .iter()
            .map(|&(x, y)| b[(y * bw + x) as usize])
            .collect();
        if middle.iter().any(|p| p[3] != 1.0) {
            continue;
        }
        let off = (0..3)
            .map(|c| (middle.iter().map(|p| p[c]).sum::<f32>() / 4.0 - px[c]).powi(2))
            .sum::<f32>()
            .sqrt();
        near += usize::from(off < 0.01);
        compared += 1;
    }
    assert!(
        compared > 30_000 && near as f64 > 0.99 * compared as f64,
        "position.exr: {near} of {compared} pixels within 1 cm"
    );
    for dir in [big, small] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// `compare --methods hard` past the threshold: the reference, the hard shadow and the exact
/// hard shadow as the same comparison at 400×210 has them (the reference's 100 one-sample
/// pixels a block against 64 samples a pixel), the report holding the three.
#[test]
fn compare_past_the_banding_threshold_is_the_small_comparison_resampled() {
    let (big, small) = (temp_dir("compare-big"), temp_dir("compare-small"));
    for (dir, s, k) in [(&big, BIG, "1"), (&small, SMALL, "64")] {
        run_ok(
            &[
                "compare",
                "fig7-concave",
                "--methods",
                "hard",
                "--samples",
                k,
                "--size",
                &size(s),
            ],
            dir,
        );
    }
    let report = report_of(&big);
    let methods: Vec<&str> = report.methods.iter().map(|m| m.method.as_str()).collect();
    assert_eq!(methods, ["reference", "hard", "reference-hard"]);
    assert_eq!((report.width, report.height), BIG);
    for (file, within) in [
        ("reference-visibility.exr", 0.03),
        ("hard-visibility.exr", 0.02),
        ("reference-hard-visibility.exr", 0.02),
    ] {
        let (v, n) = visibility_difference(&big.join(file), &small.join(file));
        assert!(n > 30_000 && v < within, "{file}: {v} over {n} pixels");
    }
    let d = image_difference(&big.join("hard.png"), &small.join("hard.png"));
    assert!(d < 2.0, "hard.png: {d} steps from the small comparison");
    // Every file of the report is there, and the montage's cells are reduced to 250 px wide.
    for m in &report.methods {
        for f in [&m.image, &m.visibility, &m.flip] {
            assert!(big.join(f).is_file(), "{f}");
        }
    }
    let layout = dbuffer::compare::montage::Layout::new(BIG.0, BIG.1, 3, 4);
    let (mw, mh, _) = png(&big.join("montage.png"));
    assert_eq!((mw, mh), (layout.width, layout.height));
    assert!(layout.cell.0 <= dbuffer::compare::montage::MAX_CELL);
    for dir in [big, small] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// `animate --method hard` past the threshold: its first frame is the small animation's.
#[test]
fn animate_past_the_banding_threshold_is_the_small_animation_resampled() {
    let (big, small) = at_both_sizes(
        "animate",
        &[
            "animate",
            "fig7-concave",
            "--method",
            "hard",
            "--frames",
            "2",
        ],
    );
    for frame in ["frame-0000.png", "frame-0001.png"] {
        let d = image_difference(&big.join(frame), &small.join(frame));
        assert!(d < 2.0, "{frame}: {d} steps from the small animation");
    }
    assert_eq!(apng_info(&big.join("animation.png")), (BIG, Some(2)));
    for dir in [big, small] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// `compare --orbit light --methods hard` past the threshold: the motion measured at 4000×2100
/// is the small orbit's (the hard shadow's temporal error within a tenth of it), and the APNG
/// is the full size.
#[test]
fn compare_orbit_past_the_banding_threshold_measures_the_small_orbits_motion() {
    let (big, small) = at_both_sizes(
        "orbit",
        &[
            "compare",
            "fig7-concave",
            "--orbit",
            "light",
            "--frames",
            "2",
            "--methods",
            "hard",
            "--samples",
            "1",
        ],
    );
    let mut temporal = Vec::new();
    for dir in [&big, &small] {
        let report = report_of(dir);
        let hard = report.methods.iter().find(|m| m.method == "hard").unwrap();
        temporal.push(hard.temporal_error.expect("measured in motion"));
        assert_eq!(report.motion.as_ref().map(|m| m.frames), Some(2));
    }
    let (b, s) = (temporal[0], temporal[1]);
    assert!(
        b > 0.0 && (b - s).abs() < 0.1 * s,
        "{b} at 4000x2100, {s} at 400x210"
    );
    assert_eq!(
        apng_info(&big.join("motion.png")),
        ((2 * BIG.0 + 4, BIG.1), Some(1))
    );
    for dir in [big, small] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// Every subcommand that draws, fed a GPU error: the error as lines (its causes indented,
/// what to do last), no literal `\n`, status 1, and the output folder as it was.
#[test]
fn every_subcommand_prints_a_gpu_error_as_lines() {
    let cases: &[(&str, &[&str])] = &[
        ("1", &["render", "fig7-concave", "--size", "32x24"]),
        // The fifth frame: the reference and two methods have been written by then.
        (
            "5",
            &[
                "compare",
                "fig7-concave",
                "--size",
                "32x24",
                "--samples",
                "4",
            ],
        ),
        // The still comparison is frames 1 to 7 (the reference, then reference-hard, hard and
        // pcf twice each); the tenth is the orbit's second frame.
        (
            "10",
            &[
                "compare",
                "fig7-concave",
                "--size",
                "32x24",
                "--samples",
                "4",
                "--orbit",
                "light",
                "--frames",
                "2",
                "--methods",
                "hard,pcf",
            ],
        ),
        (
            "2",
            &[
                "animate",
                "fig7-concave",
                "--size",
                "32x24",
                "--frames",
                "3",
            ],
        ),
        (
            "5",
            &[
                "bench",
                "--scenes",
                "table1-224",
                "--sizes",
                "32",
                "--frames",
                "1",
                "--warmup",
                "0",
                "--methods",
                "hard",
                "--max-triangles",
                "2000",
            ],
        ),
    ];
    for (fault, args) in cases {
        let dir = temp_dir(&format!("fault-{}", args[0]));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("report.json"), "before").unwrap();
        let out = dbuffer()
            .env(dbuffer::render::context::FAULT_ENV, fault)
            .args(*args)
            .arg("--out")
            .arg(&dir)
            .output()
            .expect("the binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        let what = args[..2].join(" ");
        assert!(!stderr.contains("\\n"), "{what}: a literal \\n:\n{stderr}");
        assert!(!stderr.contains("Caused by"), "{what}:\n{stderr}");
        let lines: Vec<&str> = stderr.lines().collect();
        let first = lines
            .iter()
            .position(|l| l.contains("the GPU reported an error: Validation Error"))
            .unwrap_or_else(|| panic!("{what}: no GPU error in\n{stderr}"));
        assert!(
            lines[first + 1].starts_with("    In a CommandEncoder")
                && lines[first + 2].contains("injected by DBUFFER_GPU_FAULT"),
            "{what}: its causes on lines of their own:\n{stderr}"
        );
        if args[0] == "bench" {
            // One case failed: the bench goes on and says which, its tables "n/a (error)".
            assert!(out.status.success(), "{what}:\n{stderr}");
            assert!(
                lines[first].starts_with("error     hard on table1-224"),
                "{stderr}"
            );
        } else {
            assert_eq!(out.status.code(), Some(1), "{what}:\n{stderr}");
            assert!(lines[first].starts_with("dbuffer: "), "{stderr}");
            assert!(
                lines[first + 3].starts_with("  what you can do:"),
                "{what}:\n{stderr}"
            );
            // All or nothing: the folder holds what it held.
            let left: Vec<_> = std::fs::read_dir(&dir)
                .unwrap()
                .map(|e| e.unwrap().file_name())
                .collect();
            assert_eq!(left, ["report.json"], "{what}");
            assert_eq!(std::fs::read(dir.join("report.json")).unwrap(), b"before");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The largest sizes the limits allow, every method, with the peak resident memory of each run
/// (`wait4`'s account of the child) within `MEMORY_BOUND_BYTES`; the files checked against the
/// same runs at a sixteenth of the pixels. Minutes of work: run by hand,
/// `cargo test --release --locked --test cli large_frames -- --ignored --nocapture`.
#[test]
#[ignore]
fn the_largest_allowed_sizes_run_within_the_memory_bound() {
    use dbuffer::budget::{MAX_ANIMATE_PIXELS, MAX_COMPARE_PIXELS, MEMORY_BOUND_BYTES};
    const SIDE: u32 = 4096;
    const { assert!(SIDE as u64 * SIDE as u64 == MAX_COMPARE_PIXELS) };
    const { assert!(SIDE as u64 * SIDE as u64 == MAX_ANIMATE_PIXELS) };
    let max = format!("{SIDE}x{SIDE}");
    let quarter = format!("{}x{}", SIDE / 4, SIDE / 4);
    let runs: &[(&str, &[&str])] = &[
        ("compare", &["compare", "fig7-concave", "--samples", "16"]),
        (
            "orbit",
            &[
                "compare",
                "fig7-concave",
                "--samples",
                "16",
                "--orbit",
                "light",
                "--frames",
                "2",
            ],
        ),
        ("animate", &["animate", "fig7-concave", "--frames", "2"]),
    ];
    for (name, args) in runs {
        let (big, small) = (
            temp_dir(&format!("max-{name}")),
            temp_dir(&format!("q-{name}")),
        );
        let t = std::time::Instant::now();
        let peak = peak_rss_of(&[args, &["--size", &max][..]].concat(), &big);
        eprintln!(
            "{name} at {max}: peak resident {:.2} GB, {:.0} s",
            peak as f64 / 1e9,
            t.elapsed().as_secs_f64()
        );
        assert!(peak <= MEMORY_BOUND_BYTES, "{name}: {peak} bytes");
        run_ok(&[args, &["--size", &quarter][..]].concat(), &small);
        let files: &[&str] = if *name == "animate" {
            &["frame-0000.png", "frame-0001.png"]
        } else {
            &["reference.png", "dbuffer.png", "hard.png"]
        };
        for f in files {
            let d = box_difference(&big.join(f), &small.join(f), 4);
            eprintln!("{name}: {f} {d:.2} steps from the {quarter} run's, resampled");
            assert!(d < 3.0, "{name}: {f}: {d}");
        }
        for dir in [big, small] {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// Run `dbuffer ARGS --out OUT` to success; its peak resident memory in bytes.
// The child is reaped by `wait4` below, which also gives its own peak (not `Child::wait`).
#[allow(clippy::zombie_processes)]
fn peak_rss_of(args: &[&str], out: &Path) -> u64 {
    let child = dbuffer()
        .args(args)
        .arg("--out")
        .arg(out)
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("the binary runs");
    let mut status = 0;
    // SAFETY: zeroed is a valid rusage.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: the child's pid, valid pointers to a status and a rusage; the child is reaped
    // here, never waited for through `Child`.
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as libc::pid_t, "wait4");
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "{args:?}: status {status}"
    );
    // Linux reports kilobytes.
    usage.ru_maxrss as u64 * 1024
}
