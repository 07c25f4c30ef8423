//! Helpers of the render tests: snapshot images compared within a tolerance, and WGSL struct
//! layouts read from naga to hold the Rust side's against.

pub mod snapshot;
pub mod wgsl_layout;
