//! dbuffer: a lab for boundary-correct real-time soft shadows from a disk light.
//!
//! Layers, each depending only on those below ([`budget`], the resource limits, and [`fsutil`]
//! sit under all of them):
//! - [`scene`]: scene files, built-in shapes and scenes, meshes;
//! - [`geometry`]: face classes, silhouettes, umbra/penumbra volumes, the CPU twin of the
//!   D-buffer lookup and the ray-cast visibility oracle (plain Rust, no GPU types);
//! - [`render`]: the wgpu render core (light pass, camera pass), headless or in the lab;
//! - [`output`]: writing one render's files (PNG, EXR, JSON), all or nothing.
//! - [`animation`]: an orbit recorded as PNG frames and an APNG (`dbuffer animate`, the lab).
//! - [`app`]: the lab window (eframe), around the same render core;
//! - [`shader_source`]: WGSL sources from `shaders/` with their `// #include` lines expanded.
//! - [`bench`]: `dbuffer bench` (Table 1, the competition, coherence, geometry scaling).
//! - [`study`]: `dbuffer study` (error against cost over every method's quality knobs).
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

pub mod animation;
pub mod app;
pub mod bench;
pub mod budget;
pub mod compare;
pub mod fsutil;
pub mod geometry;
pub mod output;
pub mod render;
pub mod scene;
pub mod shader_source;
pub mod study;
