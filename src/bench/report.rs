//! What a bench run measured, as `bench.json` holds it: per (scene, size, method) timings, the
//! scenes' geometry stage, the display path, frame coherence, the scaling curve and the targets.

use serde::{Deserialize, Serialize};

use crate::render::Method;

/// Median and minimum of a set of timings, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stat {
    pub median: f64,
    pub min: f64,
}

impl Stat {
    /// `None` for no samples.
    pub fn of(samples: &[f64]) -> Option<Stat> {
        let mut v: Vec<f64> = samples.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        Some(Stat { median, min: v[0] })
    }
}

/// Where a frame's figure comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameSource {
    /// The sum of the passes' GPU timestamp queries.
    GpuTimestamps,
    /// Wall time of the whole frame, fenced by the readback (the adapter has no timestamp
    /// queries, or the method works on the CPU).
    FencedWall,
}

/// One pass's GPU time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PassTime {
    pub pass: String,
    pub ms: Stat,
}

/// The steady frames of one (scene, size, method).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// The figure ratios and fps are taken from, and where it comes from.
    pub frame_ms: Stat,
    pub frame_source: FrameSource,
    pub fps: f64,
    /// GPU ms per pass (timestamp queries); empty without them.
    pub passes: Vec<PassTime>,
    /// Sum of the passes, per frame.
    pub gpu_total_ms: Option<Stat>,
    /// Sum of the light-space passes (every pass but the camera pass), per frame.
    #[serde(default)]
    pub light_ms: Option<Stat>,
    /// `Session::frame` wall time: encoding, the GPU, the readback of the camera targets.
    pub wall_ms: Stat,
    /// Pixels of the image that hit a surface.
    pub hit_pixels: usize,
    /// The reference only: one more sample per pixel without rendering a frame
    /// (`Session::advance_reference`), i.e. the ray casting alone.
    #[serde(default)]
    pub rays_ms: Option<Stat>,
    /// Frames timed (the figures are their medians); absent in older reports.
    #[serde(default)]
    pub frames: usize,
}

impl Timing {
    pub fn pass(&self, name: &str) -> Option<Stat> {
        self.passes.iter().find(|p| p.pass == name).map(|p| p.ms)
    }

    /// The frame figure measured the way `source` says (wall time is always there).
    pub fn frame_by(&self, source: FrameSource) -> Option<Stat> {
        match source {
            FrameSource::GpuTimestamps => self.gpu_total_ms,
            FrameSource::FencedWall => Some(self.wall_ms),
        }
    }
}

/// One (scene, size, method): its timings, or why the method did not render.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Run {
    pub scene: String,
    pub size: u32,
    /// The case's label, e.g. "pcss 16/32".
    pub label: String,
    /// The method's command-line name.
    pub method: String,
    pub timing: Option<Timing>,
    pub error: Option<String>,
    /// For a method that counts volumes in the stencil: volume fragments per pixel of its last
    /// frame (`Session::stencil_fill`), the fill rate it pays.
    #[serde(default)]
    pub fill: Option<f64>,
    /// What its cost view counted per pixel that shows a surface, the mean (its `Cost` unit:
    /// shadow-map taps, listed edges, the BVH nodes its rays visited…), from one untimed frame.
    #[serde(default)]
    pub work: Option<f64>,
}

/// A Table 1 scene and its geometry stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneInfo {
    pub name: String,
    pub caster_triangles: usize,
    /// Welding and adjacency, once per mesh.
    pub prepare_ms: f64,
    /// Classes, silhouettes and volumes for the scene's light (per light move).
    pub geometry_ms: Stat,
    pub umbra_triangles: usize,
    pub penumbra_triangles: usize,
}

/// The steady frame with the geometry cached against rebuilt every frame (Jakobsen et al. 2004, §6.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Coherence {
    pub scene: String,
    pub size: u32,
    /// How "rebuilt" was forced.
    pub rebuild_by: String,
    pub cached_wall_ms: Stat,
    pub rebuilt_wall_ms: Stat,
    pub cached_gpu_ms: Option<Stat>,
    pub rebuilt_gpu_ms: Option<Stat>,
    /// The geometry stage inside the rebuilt frames (`Session::geometry_ms`).
    pub rebuilt_geometry_ms: Option<Stat>,
    /// Geometry builds during the timed rebuilt frames (one per frame when it worked).
    pub rebuilds: u64,
    /// Timed frames of each kind (cached and rebuilt alternate).
    pub frames: usize,
}

/// One point of the geometry-scaling curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScalingPoint {
    pub triangles: usize,
    /// Welding and adjacency (once per mesh).
    pub prepare_ms: f64,
    /// Classes, silhouettes and volumes (per light move).
    pub build_ms: Stat,
    pub volume_triangles: usize,
    /// A light move until the light pass could draw, on the CPU (the stage, the volumes laid
    /// out and uploaded) and on the GPU (the stage's compute passes), on the bench's adapter
    /// (`render::methods::dbuffer::light_move_ms`); `None` where that path did not run.
    #[serde(default)]
    pub cpu_move_ms: Option<Stat>,
    #[serde(default)]
    pub gpu_move_ms: Option<Stat>,
}

/// A target of the issue, measured (or a figure it asks the report to give).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Target {
    pub name: String,
    /// The measured ratio or time; `None` where it could not be measured.
    pub measured: Option<f64>,
    /// Pass when `measured <= limit` (`< limit` when `strict`, `>= limit` when `at_least`);
    /// `None`: a figure to report, not a target.
    pub limit: Option<f64>,
    pub strict: bool,
    #[serde(default)]
    pub at_least: bool,
    pub unit: String,
    /// Where the figure comes from (the worst scene, the size).
    pub detail: String,
}

impl Target {
    pub fn pass(&self) -> Option<bool> {
        let (m, limit) = (self.measured?, self.limit?);
        Some(if self.at_least {
            m >= limit
        } else if self.strict {
            m < limit
        } else {
            m <= limit
        })
    }
}

/// The display path against the readback path on one scene and size (the D-buffer).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DisplayRun {
    pub scene: String,
    pub size: u32,
    /// The scene in flat colour into Rgba8 + depth: the cheapest image of it (GPU).
    pub floor_gpu_ms: Option<Stat>,
    /// The lab's frame, headless: camera pass and view pass into the display texture, fenced
    /// (the D-buffer cached: a still light).
    pub lab_still: Display,
    /// The same with the light moved before every frame: geometry, light pass, camera, view.
    pub lab_moving: Display,
    /// `Session::frame` as `dbuffer render` uses it: the camera targets and the D-buffer read
    /// back (what the lab did every frame before), light still.
    pub readback: Display,
}

/// Wall and GPU time of one kind of frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Display {
    pub wall_ms: Stat,
    pub gpu_ms: Option<Stat>,
}

/// The whole run, as written to `bench.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// The adapter's name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub adapter: String,
    pub backend: String,
    pub device_type: String,
    pub timestamps: bool,
    /// The CPU model and core count.
    pub host: String,
    pub quick: bool,
    pub warmup: usize,
    pub frames: usize,
    pub dbuffer_size: u32,
    /// Seconds since the Unix epoch when the run ended.
    pub unix_time: u64,
    pub seconds: f64,
    pub scenes: Vec<SceneInfo>,
    pub runs: Vec<Run>,
    /// The display path, per scene and size.
    #[serde(default)]
    pub display: Vec<DisplayRun>,
    pub coherence: Option<Coherence>,
    pub scaling: Vec<ScalingPoint>,
    /// Shadow rays per second of the 1-spp reference frames (their whole wall time).
    pub reference_rays_per_s: Option<f64>,
    pub targets: Vec<Target>,
}

impl Report {
    pub fn run(&self, scene: &str, size: u32, method: Method) -> Option<&Run> {
        self.runs
            .iter()
            .find(|r| r.scene == scene && r.size == size && r.method == method.name())
    }

    pub fn timing(&self, scene: &str, size: u32, method: Method) -> Option<&Timing> {
        self.run(scene, size, method)?.timing.as_ref()
    }

    /// `method`'s frame over the D-buffer's, the same scene and size, measured alike.
    pub fn ratio_to_dbuffer(&self, scene: &str, size: u32, method: Method) -> Option<f64> {
        self.ratio_to(scene, size, method, Method::DBUFFER)
    }

    /// `method`'s frame over `base`'s, the same scene and size, measured alike.
    pub fn ratio_to(&self, scene: &str, size: u32, method: Method, base: Method) -> Option<f64> {
        let m = self.timing(scene, size, method)?;
        let d = self.timing(scene, size, base)?;
        let base = d.frame_by(m.frame_source)?.median;
        (base > 0.0).then(|| m.frame_ms.median / base)
    }

    pub fn sizes(&self) -> Vec<u32> {
        let mut sizes: Vec<u32> = self.runs.iter().map(|r| r.size).collect();
        sizes.sort_unstable();
        sizes.dedup();
        sizes
    }

    /// The case labels in the order they ran.
    pub fn labels(&self) -> Vec<(String, String)> {
        let mut out: Vec<(String, String)> = Vec::new();
        for r in &self.runs {
            if !out.iter().any(|(l, _)| *l == r.label) {
                out.push((r.label.clone(), r.method.clone()));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stat_median_and_min() {
        let s = Stat::of(&[3.0, 1.0, 2.0]).unwrap();
        assert_eq!((s.median, s.min), (2.0, 1.0));
        let s = Stat::of(&[4.0, 1.0, 2.0, 3.0]).unwrap();
        assert_eq!((s.median, s.min), (2.5, 1.0));
        assert!(Stat::of(&[]).is_none());
        assert!(Stat::of(&[f64::NAN]).is_none());
    }
}
