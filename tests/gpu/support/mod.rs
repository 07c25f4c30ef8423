//! Helpers of the render tests: snapshot images compared within a tolerance, WGSL struct
//! layouts read from naga to hold the Rust side's against, and scenes scored against the
//! ray-cast reference; a seeded generator for generated scenes.

pub mod rng;
pub mod scored;
pub mod snapshot;
pub mod wgsl_layout;
