//! What a bench run times: the scenes, sizes and frame counts, and one [`Case`] per method of
//! the registry, labelled and configured by its module ([`MethodSpec::bench`]).
//!
//! [`MethodSpec::bench`]: crate::render::methods::MethodSpec

use crate::render::{Knobs, Method};
use crate::scene::{LightKind, SceneError};

/// The Table 1 scenes of Jakobsen et al. 2004, in the paper's order.
pub const TABLE1_SCENES: [&str; 4] = ["table1-224", "table1-960", "table1-5760", "table1-1440"];

/// The scenes where occluders fuse, timed by the full run after Table 1's.
pub const FUSION_SCENES: [&str; 3] = ["fusion-cross", "fusion-links", "fusion-many"];
/// The scenes of many casters (the content engines face), timed by the full run last.
pub const MANY_CASTER_SCENES: [&str; 3] = ["pergola", "cluster", "blinds"];
/// The Table 1 image sizes (square).
pub const TABLE1_SIZES: [u32; 3] = [300, 600, 1024];
/// Caster triangle counts of the geometry-scaling curve (spheres, 4·n² triangles).
pub const SCALING_TRIANGLES: [u32; 6] = [1 << 10, 1 << 12, 1 << 14, 1 << 16, 1 << 18, 1 << 20];
/// Image size the targets of the issue are stated at.
pub const TARGET_SIZE: u32 = 1024;

/// What can stop a bench run. A method that cannot render is not one of them: its rows say why.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    // The cause is the source (printed after it by anyhow's chain), not repeated here.
    #[error("cannot load scene '{name}'")]
    Scene {
        name: String,
        #[source]
        source: Box<SceneError>,
    },
    #[error("{0}")]
    Config(String),
    #[error("drawing the scaling plot failed: {0}")]
    Plot(String),
}

/// One timed configuration of a method: the label it is reported under and its knobs.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    pub label: String,
    pub method: Method,
    pub knobs: Knobs,
    /// Timed under this kind of light in place of the scene's (`run::scene_for`); `None`: the
    /// scene's own, or the kind the method takes.
    pub light: Option<LightKind>,
}

impl Case {
    /// Every method of the registry, with the knobs its module names for the bench (PCSS with 16
    /// blocker and 32 filter taps, 16 light samples, the reference as a single
    /// 1-sample-per-pixel pass).
    ///
    /// And once more the D-buffer under the regular 16-gon inscribed in each scene's disk
    /// ([`Case::polygon_dbuffer`]): the polygon D-buffer's cost against the disk's, on the same
    /// casters. It runs right after the disk's D-buffer in every round, so the two frames of the
    /// ratio are timed back to back (after the CPU-side references, every pass of the next frame
    /// ran about 1 ms slower on lavapipe).
    pub fn all() -> Vec<Case> {
        let mut cases = Vec::new();
        for &m in Method::all() {
            cases.push(Case::for_method(m));
            if m == Method::DBUFFER {
                cases.push(Case::polygon_dbuffer());
            }
        }
        cases
    }

    /// The D-buffer timed under the 16-gon in each disk's place.
    pub fn polygon_dbuffer() -> Case {
        Case {
            light: Some(LightKind::Polygon),
            ..Case::for_method(Method::DBUFFER)
        }
    }

    /// The method as its [`MethodSpec::bench`](crate::render::methods::MethodSpec) says: its
    /// label and the knobs it sets, the others at their defaults.
    pub fn for_method(method: Method) -> Case {
        let bench = &method.spec().bench;
        let knobs = bench
            .knobs
            .iter()
            .fold(Knobs::default(), |k, &(knob, value)| k.with(knob, value));
        Case {
            label: bench.label.unwrap_or(method.name()).to_string(),
            method,
            knobs,
            light: None,
        }
    }

    /// Whether the method's per-frame work is done on the CPU (so only wall time measures it).
    pub fn cpu_side(&self) -> bool {
        self.method.cpu_side()
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct Config {
    pub quick: bool,
    pub scenes: Vec<String>,
    pub sizes: Vec<u32>,
    pub cases: Vec<Case>,
    /// Frames rendered and thrown away before timing, per (scene, size, method).
    pub warmup: usize,
    /// Frames timed per (scene, size, method).
    pub frames: usize,
    /// The D-buffer (and every shadow map) is this many texels square.
    pub dbuffer_size: u32,
    /// Runs of the geometry stage per Table 1 scene.
    pub geometry_runs: usize,
    /// Caster triangle counts of the scaling curve; empty for none.
    pub scaling: Vec<u32>,
    /// Runs of the geometry stage per scaling point.
    pub scaling_runs: usize,
    /// Time the steady frame with the geometry cached and rebuilt every frame.
    pub coherence: bool,
    /// A case whose first timed frame takes longer (wall) is timed on that frame alone.
    pub slow_frame_ms: Option<f64>,
}

impl Config {
    /// The full run: Table 1's scenes and the fusion scenes, 3 warm-up and 15 timed frames,
    /// scaling up to 1M triangles.
    pub fn full() -> Config {
        Config {
            quick: false,
            scenes: TABLE1_SCENES
                .iter()
                .chain(&FUSION_SCENES)
                .chain(&MANY_CASTER_SCENES)
                .map(|s| s.to_string())
                .collect(),
            sizes: TABLE1_SIZES.to_vec(),
            cases: Case::all(),
            warmup: 3,
            frames: 15,
            // bitmask on pergola's slats takes minutes a frame at 1024² on lavapipe.
            slow_frame_ms: Some(crate::study::SLOW_FRAME_MS),
            dbuffer_size: 1024,
            geometry_runs: 31,
            scaling: SCALING_TRIANGLES.to_vec(),
            scaling_runs: 7,
            coherence: true,
        }
    }

    /// Every row of the full run with fewer frames, scaling up to 256k triangles: under two
    /// minutes on a 2-core CPU adapter.
    pub fn quick() -> Config {
        Config {
            quick: true,
            warmup: 1,
            frames: 3,
            geometry_runs: 11,
            scaling: SCALING_TRIANGLES[..5].to_vec(),
            scaling_runs: 3,
            scenes: TABLE1_SCENES.iter().map(|s| s.to_string()).collect(),
            slow_frame_ms: None,
            ..Config::full()
        }
    }

    pub fn validate(&self) -> Result<(), BenchError> {
        let bad = |m: String| Err(BenchError::Config(m));
        if self.scenes.is_empty() {
            return bad("no scene to bench".into());
        }
        if self.sizes.is_empty() {
            return bad("no image size to bench".into());
        }
        if let Some(s) = self.sizes.iter().find(|s| !(8..=8192).contains(*s)) {
            return bad(format!("image size {s}: expected 8 to 8192 pixels"));
        }
        if !(1..=8192).contains(&self.dbuffer_size) {
            return bad(format!(
                "D-buffer size {}: expected 1 to 8192 texels",
                self.dbuffer_size
            ));
        }
        if self.frames == 0 || self.frames > 10_000 {
            return bad(format!("{} timed frames: expected 1 to 10000", self.frames));
        }
        if self.warmup > 1000 {
            return bad(format!(
                "{} warm-up frames: expected 0 to 1000",
                self.warmup
            ));
        }
        if let Some(t) = self.scaling.iter().find(|t| !(64..=4_000_000).contains(*t)) {
            return bad(format!(
                "scaling point of {t} triangles: expected 64 to 4000000"
            ));
        }
        for case in &self.cases {
            case.knobs
                .validate()
                .map_err(|e| BenchError::Config(format!("{}: {e}", case.label)))?;
        }
        Ok(())
    }

    /// A rough run time in seconds on a 2-core CPU adapter (lavapipe), for the progress line.
    pub fn estimate_s(&self) -> f64 {
        let per_frame: f64 = self
            .sizes
            .iter()
            .map(|&s| 0.03 + 1.0e-7 * f64::from(s) * f64::from(s))
            .sum::<f64>()
            * 2.2;
        let frames = (self.warmup + self.frames) as f64;
        let render = self.scenes.len() as f64 * self.cases.len() as f64 * frames * per_frame;
        let scaling: f64 = self
            .scaling
            .iter()
            .map(|&t| f64::from(t) * (0.3e-6 + 0.03e-6 * self.scaling_runs as f64))
            .sum();
        render + scaling + 2.0 * self.scenes.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::methods::reference::{MAX_SAMPLES, SAMPLES};

    #[test]
    fn every_method_has_a_case() {
        let cases = Case::all();
        for &m in Method::all() {
            assert!(cases.iter().any(|c| c.method == m), "{m} has no case");
        }
        for c in &cases {
            assert!(c.knobs.validate().is_ok(), "{}", c.label);
        }
        let r = Case::for_method(crate::render::truth::SOFT);
        assert_eq!(r.knobs.get(&SAMPLES), MAX_SAMPLES);
        assert_eq!(r.label, "reference 1 spp");
        assert!(r.cpu_side());
        assert_eq!(Case::for_method(Method::HARD).label, Method::HARD.name());
    }

    #[test]
    fn configs_validate() {
        assert!(Config::full().validate().is_ok());
        assert!(Config::quick().validate().is_ok());
        let bad = Config {
            frames: 0,
            ..Config::quick()
        };
        assert!(bad.validate().is_err());
        let bad = Config {
            sizes: vec![4],
            ..Config::quick()
        };
        assert!(bad.validate().is_err());
        assert!(Config::quick().estimate_s() < Config::full().estimate_s());
    }
}
