//! `dbuffer study`: error against cost, per scene, for every method over its quality knobs
//! (docs/guide/study.md). A cell — a scene, a method, one setting of its quality knobs — is
//! measured twice over: its error against one reference per scene by `compare`'s metrics, its
//! cost by `bench`'s protocol. The report plots one against the other per scene, draws the
//! front no cell beats on both, and answers the two questions of a budget: the least error at
//! 1×, 2× and 4× the D-buffer's frame, and the cheapest cell within 2×, 5× and 10× of the
//! reference's own noise.

mod cache;
pub mod front;
pub mod plot;
pub mod report;
mod run;
pub mod spec;

pub use run::{
    run, Cell, CellCost, CellError, Flow, Machine, Progress, RunError, SceneStudy, Study,
    COST_BATCH, SLOW_FRAME_MS,
};
pub use spec::{MethodSweep, Setting, StudyError, StudySpec, FULL_SCENES, QUICK_SCENES};
