//! The `dbuffer` binary as a user runs it (cargo builds it for this test binary): `render`,
//! `animate`, `compare`, `bench`, `inspect`, and hostile inputs; and the method registry walked
//! whole, down to each knob's flag in the binary's help. Every case runs the binary in a folder
//! of its own, so the cases share nothing but the build.

mod support;

mod adapters;
mod animate_cli;
mod bad_inputs;
mod bench_cli;
mod compare_reference;
mod geometry_path;
mod large_frames;
mod registry;
mod render_cli;
mod study_cli;
mod tutorial;
mod user_methods;
