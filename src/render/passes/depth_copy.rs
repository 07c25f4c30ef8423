//! The camera's depth as an `R32Float` colour texture, for a device that cannot copy a depth
//! texture into a buffer (`DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES`, missing on GL) and
//! for a depth too large to copy whole into one staging buffer (a colour texture is read in
//! bands of rows, a depth texture only whole: [`read_frame`](crate::render::frame::read_frame)
//! decides): a fullscreen triangle loads each texel and writes the same 32-bit float, so what
//! readback gets is the depth exactly (`shaders/passes/depth_copy.wgsl`).

use crate::render::{cleared, fullscreen_pass, texture_entry, GpuContext};
use crate::render::{RenderError, Texture};

/// The pipeline and layout, once per device.
struct DepthCopyPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

/// `depth` (a `Depth32Float` texture bindable as a texture) copied into a new `R32Float` one.
pub fn copy(ctx: &GpuContext, depth: &Texture) -> Result<Texture, RenderError> {
    let pass = ctx.shared(|device| {
        let (pipeline, layout) = fullscreen_pass(
            device,
            "DepthCopyPass",
            "passes/depth_copy.wgsl",
            &[texture_entry(
                0,
                wgpu::ShaderStages::FRAGMENT,
                wgpu::TextureViewDimension::D2,
            )],
            wgpu::TextureFormat::R32Float,
        );
        DepthCopyPass { pipeline, layout }
    });
    let size = depth.texture.size();
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out = Texture::new(
        &ctx.device,
        "DepthCopy::target",
        (size.width, size.height),
        wgpu::TextureFormat::R32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("DepthCopy::bind_group"),
        layout: &pass.layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::TextureView(&depth.view),
        }],
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("DepthCopy::encoder"),
        });
    {
        let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("DepthCopy::pass"),
            color_attachments: &[cleared(&out.view, wgpu::Color::TRANSPARENT)],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rp.set_pipeline(&pass.pipeline);
        rp.set_bind_group(0, &group, &[]);
        rp.draw(0..3, 0..1);
    }
    ctx.queue.submit([encoder.finish()]);
    match pollster::block_on(scope.pop()) {
        Some(e) => Err(RenderError::Gpu(e.to_string())),
        None => Ok(out),
    }
}
