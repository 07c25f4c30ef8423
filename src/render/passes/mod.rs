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
pub mod geometry_gpu;
pub mod hybrid;
pub mod micro_patches;
pub mod moment_sat;
pub mod moments;
pub mod planar;
pub mod probe;
pub mod raytraced;
pub mod sample_maps;
pub mod shadow_map;
pub mod ssm;
pub mod stencil_volumes;
pub mod trace;
pub mod trace_rq;
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

/// The bounding box of two texel rectangles `[x0, y0, x1, y1]` (an empty one adds nothing).
pub fn bounding(a: [u32; 4], b: [u32; 4]) -> [u32; 4] {
    let empty = |r: [u32; 4]| r[0] >= r[2] || r[1] >= r[3];
    match (empty(a), empty(b)) {
        (true, _) => b,
        (_, true) => a,
        _ => [
            a[0].min(b[0]),
            a[1].min(b[1]),
            a[2].max(b[2]),
            a[3].max(b[3]),
        ],
    }
}

/// A rectangle of `[0, 1]²` (y down, as `geometry::volume_vertices::light_view_rect` makes
/// them) as whole texels `[x0, y0, x1, y1]` of a `size`² target, one texel of margin; empty
/// (`x0 == x1`) for an empty rectangle.
pub fn scissor(rect: [f32; 4], size: u32) -> [u32; 4] {
    if !(rect[0] < rect[2] && rect[1] < rect[3]) {
        return [0; 4];
    }
    let n = size as f32;
    let lo = |v: f32| ((v * n).floor() - 1.0).clamp(0.0, n) as u32;
    let hi = |v: f32| ((v * n).ceil() + 1.0).clamp(0.0, n) as u32;
    [lo(rect[0]), lo(rect[1]), hi(rect[2]), hi(rect[3])]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scissor_covers_the_rect_with_a_margin_and_stays_inside() {
        assert_eq!(scissor([0.0, 0.0, 1.0, 1.0], 100), [0, 0, 100, 100]);
        assert_eq!(scissor([0.25, 0.5, 0.5, 0.75], 100), [24, 49, 51, 76]);
        assert_eq!(scissor([0.5, 0.5, 0.5, 0.9], 100), [0; 4], "empty");
        let r = scissor([0.999, 0.999, 1.0, 1.0], 10);
        assert!(r[0] < r[2] && r[1] < r[3] && r[2] <= 10 && r[3] <= 10);
        assert_eq!(bounding([0; 4], [1, 2, 3, 4]), [1, 2, 3, 4]);
        assert_eq!(bounding([0, 5, 2, 6], [1, 2, 3, 4]), [0, 2, 3, 6]);
    }
}
