//! The passes, one file each, each with its WGSL twin of the same name in `shaders/passes/`
//! (the camera pass's shared half is `shaders/shared/camera.wgsl`, completed by each method's
//! `shaders/methods/NAME.wgsl`). A pass owns its pipelines (built once per device and shared
//! through [`super::GpuContext::shared`]) and, where it has any, its size-dependent targets; it
//! takes views and buffers, never another pass.

pub mod camera;
pub mod dbuffer_volumes;
pub mod extended_light_map;
pub mod floor;
pub mod fused_layers;
pub mod fused_lists;
pub mod hybrid;
pub mod planar;
pub mod probe;
pub mod sample_maps;
pub mod shadow_map;
pub mod ssm;
pub mod stencil_volumes;
pub mod view;
pub mod view_twin;
pub mod wedges;

use std::sync::atomic::{AtomicU64, Ordering};

/// A number no earlier set of targets had: whoever bound the old ones binds again.
pub fn next_generation() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}
