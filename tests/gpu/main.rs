//! The render core: every method and pass on the GPU (lavapipe, Mesa's CPU Vulkan, on CI)
//! against its CPU twin, the ray-cast reference and the snapshots in `tests/snapshots/`, and the
//! WGSL it is built from (every shader validated by naga, every shared struct's layout). One
//! module per topic; run one with `cargo test --test gpu render_accuracy` (export
//! `WGPU_BACKEND=vulkan NODEVICE_SELECT=1` on a machine without a GPU).

mod support;

mod compare_report;
mod cost_views;
mod dbuffer_knobs;
mod engine_methods;
mod geometry_gpu;
mod hard_methods;
mod linear_ssm;
mod methods_accuracy;
mod polygon_lights;
mod range_view;
mod raytraced;
mod readback;
mod reference_analytic;
mod reference_gpu_view;
mod render_accuracy;
mod render_fused;
mod render_gpu;
mod render_layout;
mod render_session;
mod render_snapshots;
mod shaders;
mod snapshot_harness;
mod study_resume;
mod temporal;
mod trace;
mod user_methods;
mod view_pass;
mod view_session;
mod wedges;
mod wgsl_layout_helper;
