//! Image snapshot tests: compare a rendered RGBA8 image with `tests/snapshots/NAME.png`.
//!
//! A module of the gpu test binary; a test module uses it with
//!
//! ```ignore
//! use crate::support::snapshot;
//!
//! snapshot::check_snapshot("plane_disk_light", 64, 64, &pixels);
//! ```
//!
//! - Thresholds live in one file, `tests/snapshots/tolerance.toml` (see [`Tolerance`]): a pixel
//!   fails when any channel differs by more than `per_channel`; the snapshot fails when more than
//!   `max_failing_fraction` of its pixels fail. `[overrides.NAME]` tables change them for one
//!   snapshot.
//! - A failure writes `NAME.new.png` (what was rendered) and `NAME.diff.png` (failing pixels red
//!   over the dimmed snapshot) beside the snapshot; both are git-ignored and removed again when
//!   the snapshot next passes.
//! - `UPDATE_SNAPSHOTS=1` writes the rendered image as the snapshot when it is missing or fails,
//!   and passes; a snapshot that still passes is left as it is, so re-running does not churn PNGs
//!   with sub-threshold noise. `UPDATE_SNAPSHOTS=force` rewrites every snapshot checked.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use image::RgbaImage;
use serde::Deserialize;

/// The name of the tolerance file in a snapshot directory.
pub const TOLERANCE_FILE: &str = "tolerance.toml";

/// Where the project's snapshots live.
pub fn snapshot_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots")
}

/// Compare `rgba8` (`width` × `height`, row-major, 4 bytes a pixel) with the snapshot `name` in
/// `tests/snapshots/`, honouring `UPDATE_SNAPSHOTS`; panics with the report on failure.
pub fn check_snapshot(name: &str, width: u32, height: u32, rgba8: &[u8]) {
    if let Err(report) = check_snapshot_in(
        &snapshot_dir(),
        name,
        width,
        height,
        rgba8,
        Update::from_env(),
    ) {
        panic!("{report}");
    }
}

/// Whether a check may write the snapshot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Update {
    /// Compare only (`UPDATE_SNAPSHOTS` unset, empty, `0` or `false`).
    No,
    /// Write the snapshot when it is missing or fails, then pass (`UPDATE_SNAPSHOTS=1`).
    Failing,
    /// Always write the snapshot (`UPDATE_SNAPSHOTS=force`).
    Force,
}

impl Update {
    /// From the `UPDATE_SNAPSHOTS` environment variable.
    pub fn from_env() -> Self {
        Self::from_value(std::env::var("UPDATE_SNAPSHOTS").ok().as_deref())
    }

    /// From the value of `UPDATE_SNAPSHOTS` (`None`: unset).
    pub fn from_value(value: Option<&str>) -> Self {
        match value {
            None | Some("" | "0" | "false") => Update::No,
            Some("force") => Update::Force,
            Some(_) => Update::Failing,
        }
    }
}

/// What a passing check did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// The image matched the snapshot within tolerance.
    Matched {
        /// Pixels over the per-channel threshold (at most the allowed fraction).
        failing: usize,
        /// The largest channel difference seen anywhere.
        max_diff: u8,
    },
    /// The snapshot was written (update mode).
    Written,
}

/// Thresholds for one snapshot.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerance {
    /// A pixel fails when any channel (0–255) differs by more than this.
    pub per_channel: u8,
    /// The snapshot fails when more than this fraction (0–1) of its pixels fail.
    pub max_failing_fraction: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ToleranceFile {
    per_channel: u8,
    max_failing_fraction: f64,
    #[serde(default)]
    overrides: BTreeMap<String, ToleranceOverride>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ToleranceOverride {
    per_channel: Option<u8>,
    max_failing_fraction: Option<f64>,
}

/// The tolerance for snapshot `name` from `dir/tolerance.toml`.
pub fn load_tolerance(dir: &Path, name: &str) -> Result<Tolerance, String> {
    let path = dir.join(TOLERANCE_FILE);
    let example = "per_channel = 8\nmax_failing_fraction = 0.005";
    let text = std::fs::read_to_string(&path).map_err(|e| {
        format!(
            "cannot read the snapshot tolerances {}: {e}\nit should hold, for example:\n{example}",
            path.display()
        )
    })?;
    let file: ToleranceFile =
        toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut tolerance = Tolerance {
        per_channel: file.per_channel,
        max_failing_fraction: file.max_failing_fraction,
    };
    if let Some(o) = file.overrides.get(name) {
        tolerance.per_channel = o.per_channel.unwrap_or(tolerance.per_channel);
        tolerance.max_failing_fraction = o
            .max_failing_fraction
            .unwrap_or(tolerance.max_failing_fraction);
    }
    let f = tolerance.max_failing_fraction;
    if !(0.0..=1.0).contains(&f) {
        return Err(format!(
            "{}: max_failing_fraction for `{name}` is {f}, not in 0..=1",
            path.display()
        ));
    }
    Ok(tolerance)
}

/// A pixel-by-pixel comparison of two same-sized images.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// Pixels with a channel difference over the threshold.
    pub failing: usize,
    /// All pixels.
    pub total: usize,
    /// The largest channel difference seen anywhere.
    pub max_diff: u8,
    /// Failing pixels red, every other pixel the expected image's colour at a third of its
    /// brightness, opaque.
    pub diff: RgbaImage,
}

impl Comparison {
    /// Whether the failing pixels are within `tolerance`.
    pub fn passes(&self, tolerance: &Tolerance) -> bool {
        self.failing as f64 <= tolerance.max_failing_fraction * self.total as f64
    }
}

/// Compare `actual` with `expected` (same size) channel by channel.
pub fn compare(expected: &RgbaImage, actual: &RgbaImage, per_channel: u8) -> Comparison {
    let mut diff = RgbaImage::new(expected.width(), expected.height());
    let mut failing = 0;
    let mut max_diff = 0;
    for ((e, a), d) in expected
        .pixels()
        .zip(actual.pixels())
        .zip(diff.pixels_mut())
    {
        let pixel_diff = (0..4).map(|c| e[c].abs_diff(a[c])).max().unwrap_or(0);
        max_diff = max_diff.max(pixel_diff);
        *d = if pixel_diff > per_channel {
            failing += 1;
            image::Rgba([255, 0, 0, 255])
        } else {
            let dim = |c: u8| (u16::from(c) * u16::from(e[3]) / (255 * 3)) as u8;
            image::Rgba([dim(e[0]), dim(e[1]), dim(e[2]), 255])
        };
    }
    Comparison {
        failing,
        total: expected.pixels().len(),
        max_diff,
        diff,
    }
}

/// [`check_snapshot`] with the snapshot directory and update mode given: `Err` is the report.
pub fn check_snapshot_in(
    dir: &Path,
    name: &str,
    width: u32,
    height: u32,
    rgba8: &[u8],
    update: Update,
) -> Result<Outcome, String> {
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-".contains(c))
    {
        return Err(format!(
            "snapshot name `{name}`: use letters, digits, `_` and `-` only"
        ));
    }
    let expected_len = width as usize * height as usize * 4;
    let actual = RgbaImage::from_raw(width, height, rgba8.to_vec())
        .filter(|_| rgba8.len() == expected_len)
        .ok_or_else(|| {
            format!(
                "snapshot `{name}`: {} bytes is not a {width}x{height} RGBA8 image ({expected_len} bytes)",
                rgba8.len()
            )
        })?;
    let path = dir.join(format!("{name}.png"));
    let new_path = dir.join(format!("{name}.new.png"));
    let diff_path = dir.join(format!("{name}.diff.png"));
    let accept = || -> Result<Outcome, String> {
        write_png(&path, &actual)?;
        remove_stale(&new_path, &diff_path);
        Ok(Outcome::Written)
    };
    if update == Update::Force {
        return accept();
    }

    let expected = if path.exists() {
        Some(
            image::open(&path)
                .map_err(|e| format!("cannot read snapshot {}: {e}", path.display()))?
                .to_rgba8(),
        )
    } else {
        None
    };
    let Some(expected) = expected else {
        if update == Update::Failing {
            return accept();
        }
        write_png(&new_path, &actual)?;
        return Err(format!(
            "snapshot `{name}` does not exist: {} is missing.\n\
             The rendered image is in {}. To accept it as the snapshot, run the test again with\n\
             UPDATE_SNAPSHOTS=1 (e.g. `UPDATE_SNAPSHOTS=1 cargo test --test gpu <this test>`), look at\n\
             the PNG, and commit it.",
            path.display(),
            new_path.display()
        ));
    };

    if expected.dimensions() != actual.dimensions() {
        if update == Update::Failing {
            return accept();
        }
        write_png(&new_path, &actual)?;
        return Err(format!(
            "snapshot `{name}` is {}x{} but the image is {width}x{height}.\n\
             Rendered image: {}\n{}",
            expected.width(),
            expected.height(),
            new_path.display(),
            accept_hint()
        ));
    }

    let tolerance = load_tolerance(dir, name)?;
    let comparison = compare(&expected, &actual, tolerance.per_channel);
    if comparison.passes(&tolerance) {
        remove_stale(&new_path, &diff_path);
        return Ok(Outcome::Matched {
            failing: comparison.failing,
            max_diff: comparison.max_diff,
        });
    }
    if update == Update::Failing {
        return accept();
    }
    write_png(&new_path, &actual)?;
    write_png(&diff_path, &comparison.diff)?;
    Err(format!(
        "snapshot `{name}` differs from {}:\n\
         {} of {} pixels ({:.3}%) differ by more than {} in some channel (allowed: {:.3}%); \
         max channel difference {}.\n\
         Rendered image: {}\n\
         Diff (failing pixels red over the dimmed snapshot): {}\n{}",
        path.display(),
        comparison.failing,
        comparison.total,
        100.0 * comparison.failing as f64 / comparison.total.max(1) as f64,
        tolerance.per_channel,
        100.0 * tolerance.max_failing_fraction,
        comparison.max_diff,
        new_path.display(),
        diff_path.display(),
        accept_hint()
    ))
}

fn accept_hint() -> &'static str {
    "If the change is intended, run the test again with UPDATE_SNAPSHOTS=1 and commit the PNG."
}

fn write_png(path: &Path, image: &RgbaImage) -> Result<(), String> {
    let mut bytes = Vec::new();
    image
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .map_err(|e| format!("cannot encode {}: {e}", path.display()))?;
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent)
            .map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
    }
    dbuffer::fsutil::write_atomic(path, &bytes)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Remove the outputs of an earlier failure, so a diff lying around always belongs to a failure.
fn remove_stale(new_path: &Path, diff_path: &Path) {
    let _ = std::fs::remove_file(new_path);
    let _ = std::fs::remove_file(diff_path);
}
