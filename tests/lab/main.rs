//! The lab as a user drives it: the whole eframe app headless on the wgpu (lavapipe) adapter
//! through egui_kittest, its widgets, the mouse and dropped files. Snapshot thresholds are in
//! `kittest.toml`; the images are in `tests/snapshots/`.

mod support;

mod app_area_lights;
mod app_fused;
mod app_lab;
mod app_live;
mod app_raytraced;
mod app_stats;
mod app_study;
