//! The passes, one file each, each with its WGSL twin of the same name in `shaders/passes/`
//! (the camera pass's shared half is `shaders/shared/camera.wgsl`, completed by each method's
//! `shaders/methods/NAME.wgsl`). A pass owns its pipelines (built once per device and shared
//! through [`super::GpuContext::shared`]) and, where it has any, its size-dependent targets; it
//! takes views and buffers, never another pass.

pub mod camera;
pub mod dbuffer_volumes;
pub mod depth_copy;
pub mod extended_light_map;
pub mod floor;
pub mod fused_layers;
pub mod fused_lists;
pub mod hybrid;
pub mod micro_patches;
pub mod moment_sat;
pub mod moments;
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

/// A square colour texture of `layers` layers (one map per light sample), its array view, a view
/// of each layer to render into, and one depth target of `depth_format` shared by the layers.
pub struct LayeredTargets {
    pub texture: wgpu::Texture,
    pub array_view: wgpu::TextureView,
    pub layer_views: Vec<wgpu::TextureView>,
    pub depth: wgpu::TextureView,
}

impl LayeredTargets {
    pub fn new(
        device: &wgpu::Device,
        label: &str,
        size: u32,
        layers: u32,
        (format, depth_format): (wgpu::TextureFormat, wgpu::TextureFormat),
    ) -> LayeredTargets {
        use wgpu::TextureUsages as U;
        let extent = |layers| wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: layers,
        };
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: extent(layers),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
            view_formats: &[],
        });
        let depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: extent(1),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: depth_format,
            usage: U::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let array_view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some(label),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let layer_views = (0..layers)
            .map(|layer| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    label: Some(label),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        LayeredTargets {
            texture,
            array_view,
            layer_views,
            depth: depth.create_view(&wgpu::TextureViewDescriptor::default()),
        }
    }
}

/// A number no earlier set of targets had: whoever bound the old ones binds again.
pub fn next_generation() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}
