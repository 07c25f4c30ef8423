//! Screen-space stencil shadows (`shaders/passes/stencil_volumes.wgsl`), the machinery every
//! method that counts shadow volumes over the camera's pixels shares (`shadow-volume`,
//! `hybrid`, the hard part of penumbra wedges) and that `planar` draws into:
//!
//! 1. **prepass** ([`ScreenPass::record_prepass`]): every surface from the camera, with the far
//!    plane at infinity and reversed depth ([`ScreenView::infinite_view_proj`]), into a
//!    depth-stencil target (stencil cleared to 0) and a world-position target (w = 1 where a
//!    surface is);
//! 2. **z-fail volumes** ([`ScreenPass::record_zfail`]): closed volume triangles (homogeneous,
//!    w = 0 at infinity, outward-wound: `geometry::hard_volume`) counted where they lie *behind*
//!    the visible surface: back faces increment, front faces decrement (Carmack's reverse; Everitt
//!    and Kilgard 2002 made it robust with both caps and the far plane at infinity). The count is
//!    then right wherever the camera is, inside a volume included;
//! 3. **resolve** ([`ScreenPass::record_resolve`]): V = 0 where the count is not zero, 1
//!    elsewhere, into a visibility texture the camera pass reads at its pixel.
//!
//! Targets are the camera image's size ([`ScreenTargets`]). The depth-stencil format is
//! `Depth32FloatStencil8` where the device has it (reversed float depth resolves about 1e-7 of
//! the distance at any range), else `Depth24PlusStencil8`, which every adapter has (24-bit depth
//! resolves about `2⁻²⁴·D²/near`: millimetres at a few metres). Volumes whose caps lie on
//! surfaces the camera sees (lit caps: open meshes) are pushed away from the light by
//! [`StencilVolumePass::push`], a share of their distance to it that each format resolves.
//!
//! For a second user: make a [`ScreenPass`] per method state, call [`ScreenPass::begin`] each
//! frame, then record the prepass, any number of volume draws (counts add), and the resolve (or
//! read `targets().depth_stencil` with a pass of one's own). [`ScreenPass::measure_fill`] is the
//! volumes' overdraw for the bench.

use std::sync::Arc;

use super::camera::ScreenView;
use super::next_generation;
use crate::render::gpu_scene::{GpuScene, VertexChunks};
use crate::render::readback::{Readback, TextureRead};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, pipeline_layout, shader_module, uniform_buffer, uniform_entry,
    GpuContext, RenderError, SurfaceVertex, Texture,
};

pub const POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const VISIBILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// The overdraw count of [`ScreenPass::measure_fill`]: additive blending, exact integers to 2048.
const FILL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;

/// `ScreenUniforms` of `shaders/passes/stencil_volumes.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ScreenUniforms {
    pub infinite_view_proj: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub size: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<ScreenUniforms>() == 96);

impl ScreenUniforms {
    pub fn new(view: &ScreenView) -> ScreenUniforms {
        ScreenUniforms {
            infinite_view_proj: view.infinite_view_proj.to_cols_array_2d(),
            eye: view.eye.extend(1.0).to_array(),
            size: [view.width as f32, view.height as f32, 0.0, 0.0],
        }
    }
}

/// A volume vertex: a homogeneous point (w = 0 at infinity), 16 bytes.
pub fn volume_vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    const ATTRIBUTES: [wgpu::VertexAttribute; 1] = [wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x4,
        offset: 0,
        shader_location: 0,
    }];
    wgpu::VertexBufferLayout {
        array_stride: 16,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &ATTRIBUTES,
    }
}

/// A depth-stencil state over `format` (the pass's [`StencilVolumePass::format`]).
pub fn depth_stencil(
    format: wgpu::TextureFormat,
    depth_write: bool,
    depth_compare: wgpu::CompareFunction,
    stencil: wgpu::StencilState,
) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(depth_write),
        depth_compare: Some(depth_compare),
        stencil,
        bias: wgpu::DepthBiasState::default(),
    })
}

/// The stencil test alone, the same on both faces.
pub fn stencil_both(face: wgpu::StencilFaceState, write_mask: u32) -> wgpu::StencilState {
    wgpu::StencilState {
        front: face,
        back: face,
        read_mask: 0xff,
        write_mask,
    }
}

/// The pipelines, built once per device.
pub struct StencilVolumePass {
    /// The depth-stencil format of the targets.
    pub format: wgpu::TextureFormat,
    /// Group 0 of every pipeline here: the [`ScreenUniforms`].
    pub layout: wgpu::BindGroupLayout,
    /// The pipeline layout over `layout` alone.
    pub pipeline_layout: wgpu::PipelineLayout,
    /// The module, for passes that add their own entry points' pipelines.
    pub module: wgpu::ShaderModule,
    prepass: wgpu::RenderPipeline,
    zfail: wgpu::RenderPipeline,
    resolve: wgpu::RenderPipeline,
    fill: wgpu::RenderPipeline,
}

impl StencilVolumePass {
    pub fn get(ctx: &GpuContext) -> Arc<StencilVolumePass> {
        ctx.shared(|device| {
            let format = if device
                .features()
                .contains(wgpu::Features::DEPTH32FLOAT_STENCIL8)
            {
                wgpu::TextureFormat::Depth32FloatStencil8
            } else {
                wgpu::TextureFormat::Depth24PlusStencil8
            };
            let module = shader_module(device, "passes/stencil_volumes.wgsl");
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("StencilVolumePass::layout"),
                entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
            });
            let pl = pipeline_layout(device, "StencilVolumePass::pipeline_layout", &[&layout]);
            let make = |label: &str,
                        vs: &str,
                        fs: Option<(&str, wgpu::ColorTargetState)>,
                        buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                        ds: Option<wgpu::DepthStencilState>| {
                let targets = [fs.as_ref().map(|(_, t)| t.clone())];
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&pl),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(vs),
                        compilation_options: Default::default(),
                        buffers,
                    },
                    // Volumes are counted from both sides; surfaces are two-sided.
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: ds,
                    multisample: wgpu::MultisampleState::default(),
                    fragment: fs.as_ref().map(|(entry, _)| wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
            let plain = |format| wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            };
            let prepass = make(
                "StencilVolumePass::prepass",
                "vs_prepass",
                Some(("fs_prepass", plain(POSITION_FORMAT))),
                &[Some(SurfaceVertex::layout())],
                // Reversed depth: nearer is greater.
                depth_stencil(
                    format,
                    true,
                    wgpu::CompareFunction::Greater,
                    Default::default(),
                ),
            );
            let counting = wgpu::StencilState {
                front: wgpu::StencilFaceState {
                    compare: wgpu::CompareFunction::Always,
                    fail_op: wgpu::StencilOperation::Keep,
                    depth_fail_op: wgpu::StencilOperation::DecrementWrap,
                    pass_op: wgpu::StencilOperation::Keep,
                },
                back: wgpu::StencilFaceState {
                    compare: wgpu::CompareFunction::Always,
                    fail_op: wgpu::StencilOperation::Keep,
                    depth_fail_op: wgpu::StencilOperation::IncrementWrap,
                    pass_op: wgpu::StencilOperation::Keep,
                },
                read_mask: 0xff,
                write_mask: 0xff,
            };
            let zfail = make(
                "StencilVolumePass::zfail",
                "vs_volume",
                None,
                &[Some(volume_vertex_layout())],
                // Counted where the volume is not in front of the surface: behind it, or at its
                // very depth (a cap on the surface it copies lies behind it).
                depth_stencil(format, false, wgpu::CompareFunction::Greater, counting),
            );
            let shadowed = stencil_both(
                wgpu::StencilFaceState {
                    compare: wgpu::CompareFunction::NotEqual,
                    fail_op: wgpu::StencilOperation::Keep,
                    depth_fail_op: wgpu::StencilOperation::Keep,
                    pass_op: wgpu::StencilOperation::Keep,
                },
                0,
            );
            let resolve = make(
                "StencilVolumePass::resolve",
                "vs_main",
                Some(("fs_shadowed", plain(VISIBILITY_FORMAT))),
                &[],
                depth_stencil(format, false, wgpu::CompareFunction::Always, shadowed),
            );
            let add = wgpu::ColorTargetState {
                format: FILL_FORMAT,
                blend: Some(wgpu::BlendState {
                    color: wgpu::BlendComponent {
                        src_factor: wgpu::BlendFactor::One,
                        dst_factor: wgpu::BlendFactor::One,
                        operation: wgpu::BlendOperation::Add,
                    },
                    alpha: wgpu::BlendComponent::REPLACE,
                }),
                write_mask: wgpu::ColorWrites::RED,
            };
            let fill = make(
                "StencilVolumePass::fill",
                "vs_volume",
                Some(("fs_one", add)),
                &[Some(volume_vertex_layout())],
                None,
            );
            StencilVolumePass {
                format,
                layout,
                pipeline_layout: pl,
                module,
                prepass,
                zfail,
                resolve,
                fill,
            }
        })
    }
}

impl StencilVolumePass {
    /// How far finite volume vertices are pushed away from the light, as a share of their
    /// distance to it, so that a lit cap lies behind the surface it copies by more than the depth
    /// format resolves (a few units of its last place at the scene's distances).
    pub fn push(&self) -> f32 {
        if self.format == wgpu::TextureFormat::Depth32FloatStencil8 {
            1e-4
        } else {
            2e-3
        }
    }
}

/// The screen-space targets, the camera image's size.
pub struct ScreenTargets {
    pub width: u32,
    pub height: u32,
    /// Depth by the infinite projection, and the stencil counts.
    pub depth_stencil: Texture,
    /// World position of what each pixel shows, w = 1 (0 where nothing is).
    pub position: Texture,
    /// V per pixel: what the camera pass reads.
    pub visibility: Texture,
    /// Changes whenever the textures are made again.
    pub generation: u64,
}

impl ScreenTargets {
    pub fn new(
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
    ) -> ScreenTargets {
        use wgpu::TextureUsages as U;
        let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
        ScreenTargets {
            width,
            height,
            depth_stencil: Texture::new(
                device,
                "ScreenTargets::depth_stencil",
                (width, height),
                format,
                U::RENDER_ATTACHMENT | U::COPY_SRC,
            ),
            position: Texture::new(
                device,
                "ScreenTargets::position",
                (width, height),
                POSITION_FORMAT,
                usage,
            ),
            visibility: Texture::new(
                device,
                "ScreenTargets::visibility",
                (width, height),
                VISIBILITY_FORMAT,
                usage,
            ),
            generation: next_generation(),
        }
    }

    /// The depth-stencil target kept as it is: stencil tests and depth tests without writes.
    pub fn read_only_depth_stencil(&self) -> Option<wgpu::RenderPassDepthStencilAttachment<'_>> {
        Some(wgpu::RenderPassDepthStencilAttachment {
            view: &self.depth_stencil.view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            }),
        })
    }
}

/// One method state's screen-space passes: its uniforms and its targets.
pub struct ScreenPass {
    pub pass: Arc<StencilVolumePass>,
    uniforms: wgpu::Buffer,
    pub bind_group: wgpu::BindGroup,
    targets: Option<ScreenTargets>,
}

impl ScreenPass {
    pub fn new(ctx: &GpuContext) -> ScreenPass {
        let pass = StencilVolumePass::get(ctx);
        let uniforms = uniform_buffer::<ScreenUniforms>(&ctx.device, "ScreenPass::uniforms");
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ScreenPass::bind_group"),
            layout: &pass.layout,
            entries: &[buffer_entry(0, &uniforms)],
        });
        ScreenPass {
            pass,
            uniforms,
            bind_group,
            targets: None,
        }
    }

    /// The targets, once [`ScreenPass::begin`] made them.
    pub fn targets(&self) -> Option<&ScreenTargets> {
        self.targets.as_ref()
    }

    /// Size the targets for `view` (made again when it changed) and write its uniforms.
    pub fn begin(&mut self, ctx: &GpuContext, view: &ScreenView) -> &ScreenTargets {
        if self
            .targets
            .as_ref()
            .is_none_or(|t| (t.width, t.height) != (view.width, view.height))
        {
            self.targets = Some(ScreenTargets::new(
                &ctx.device,
                self.pass.format,
                view.width,
                view.height,
            ));
        }
        ctx.queue.write_buffer(
            &self.uniforms,
            0,
            bytemuck::bytes_of(&ScreenUniforms::new(view)),
        );
        let format = self.pass.format;
        self.targets
            .get_or_insert_with(|| ScreenTargets::new(&ctx.device, format, view.width, view.height))
    }

    /// The prepass: depth (infinite projection) and world position of every surface, the stencil
    /// cleared to 0.
    pub fn record_prepass(&self, rec: &mut Recorder<'_>, surfaces: &GpuScene) {
        let Some(t) = &self.targets else { return };
        let span = rec.span("screen_prepass");
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("ScreenPass::prepass"),
            color_attachments: &[cleared(&t.position.view, wgpu::Color::TRANSPARENT)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &t.depth_stencil.view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0),
                    store: wgpu::StoreOp::Store,
                }),
            }),
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pass.prepass);
        pass.set_bind_group(0, &self.bind_group, &[]);
        surfaces.draw(&mut pass);
    }

    /// Count `volumes` (closed, outward-wound, homogeneous triangles) in the stencil by z-fail;
    /// several calls add their counts (8 bits, wrapping).
    pub fn record_zfail(&self, rec: &mut Recorder<'_>, volumes: &VertexChunks) {
        let Some(t) = &self.targets else { return };
        let span = rec.span("stencil_volumes");
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("ScreenPass::zfail"),
            color_attachments: &[],
            depth_stencil_attachment: t.read_only_depth_stencil(),
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pass.zfail);
        pass.set_bind_group(0, &self.bind_group, &[]);
        volumes.draw(&mut pass);
    }

    /// V into the visibility target: 0 where the stencil count is not zero, 1 elsewhere.
    pub fn record_resolve(&self, rec: &mut Recorder<'_>) {
        let Some(t) = &self.targets else { return };
        let span = rec.span("stencil_resolve");
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("ScreenPass::resolve"),
            color_attachments: &[cleared(&t.visibility.view, crate::render::red(1.0))],
            depth_stencil_attachment: t.read_only_depth_stencil(),
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pass.resolve);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_stencil_reference(0);
        pass.draw(0..3, 0..1);
    }

    /// The volumes' fill: how many volume fragments the rasteriser makes per pixel of the image,
    /// on average (every triangle over its whole screen footprint, no test): what a stencil
    /// method pays in fill rate. Its own submit and wait (untimed, for the bench and `compare`).
    pub fn measure_fill(
        &self,
        ctx: &GpuContext,
        volumes: &VertexChunks,
    ) -> Result<f64, RenderError> {
        let Some(t) = &self.targets else {
            return Err(RenderError::Request(
                "the fill of the shadow volumes is measured after a frame".into(),
            ));
        };
        let counts = Texture::new(
            &ctx.device,
            "ScreenPass::fill",
            (t.width, t.height),
            FILL_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("ScreenPass::measure_fill"),
            });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("ScreenPass::fill"),
                color_attachments: &[cleared(&counts.view, wgpu::Color::TRANSPARENT)],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pass.fill);
            pass.set_bind_group(0, &self.bind_group, &[]);
            volumes.draw(&mut pass);
        }
        ctx.queue.submit([encoder.finish()]);
        let bytes = Readback::default().read(ctx, &[TextureRead::color(&counts.texture, 2)])?;
        let total: f64 = bytes
            .first()
            .map(|b| {
                b.chunks_exact(2)
                    .map(|h| f64::from(f16_to_f32(u16::from_le_bytes([h[0], h[1]]))))
                    .sum()
            })
            .unwrap_or(0.0);
        Ok(total / (f64::from(t.width) * f64::from(t.height)).max(1.0))
    }
}

/// A half-precision float's value (normal and subnormal numbers, infinities as such).
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = i32::from((h >> 10) & 0x1f);
    let frac = f32::from(h & 0x3ff);
    match exp {
        0 => sign * frac * 2f32.powi(-24),
        31 if frac == 0.0 => sign * f32::INFINITY,
        31 => f32::NAN,
        _ => sign * (1.0 + frac / 1024.0) * 2f32.powi(exp - 15),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_floats_decode() {
        assert_eq!(f16_to_f32(0x0000), 0.0);
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0x4000), 2.0);
        assert_eq!(f16_to_f32(0x6800), 2048.0);
        assert_eq!(f16_to_f32(0xc500), -5.0);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
        assert!(f16_to_f32(0x7c00).is_infinite());
    }
}
