//! `dbuffer bench`: the D-buffer paper's Table 1 reproduced (casters of 224, 960, 5760 and 1440 triangles at
//! 300², 600² and 1024²), every other method of [`Method::ALL`] timed in the same run as a ratio
//! to the D-buffer, the steady frame with the geometry cached and rebuilt every frame (Jakobsen et al.
//! 2004, §6.1), and the geometry stage from 1k to 1M caster triangles (docs/results/performance.md).
//!
//! Everything is measured through the same calls the lab makes: a [`Session`] per scene, one
//! [`FrameRequest`] per method. Frames are timed after warm-up ones (the first includes the
//! driver's shader compilation); each figure is the median (and minimum) of the steady frames.
//! Nothing here asserts a time: the report says what was measured and on which adapter.

pub mod plot;
pub mod table;

mod config;
mod report;
mod run;
mod targets;

pub use config::{
    BenchError, Case, Config, FUSION_SCENES, MANY_CASTER_SCENES, SCALING_TRIANGLES, TABLE1_SCENES,
    TABLE1_SIZES, TARGET_SIZE,
};
pub use report::{
    Coherence, Display, DisplayRun, FrameSource, PassTime, Report, Run, ScalingPoint, SceneInfo,
    Stat, Target, Timing,
};
pub use run::{load_scenes, run, scaling_scene, scene_for, time_frames, Progress};
pub use targets::targets;
