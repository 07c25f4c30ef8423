//! The D-buffer's volume channels (`shaders/passes/dbuffer_volumes.wgsl`), drawn from the light
//! centre after the shadow map: umbra `(|cx_uv|, |cx_s|)` and penumbra `(|cx_pv|, |cx_s|)`,
//! `size`² texels each, as `Rg32Float` — or `Rgba32Float` with the winning triangle's lit side
//! in the light's plane, which only `V exact` reads ([`VolumeLayout`]: the narrower texel took a
//! quarter off the volume pass on Table 1).
//!
//! - Penumbra: every caster's entry faces (the pipeline culls the faces turned away from `c`)
//!   over a copy of the shadow map's depth, nearest wins: an entry behind the nearest surface is
//!   never looked up (only points visible from `c` read this channel), so those fragments die in
//!   the early depth test.
//! - Umbra: per caster the nearest exit face (front faces culled), then the farthest over
//!   casters. Casters whose volumes do not overlap in the light's view are drawn together, since
//!   "farthest over casters" has nothing to decide there; only overlapping groups go through a
//!   scratch target merged with the depth test Greater, each inside its own rectangle.
//!
//! Neither target is cleared from frame to frame: each texel drawn carries the frame's
//! [`FrameTag`], and a texel of an earlier frame reads as "no crossing" (clearing what the last
//! frame drew was 35–45 % of this pass on lavapipe). Only the exits' depth is reset, over the
//! rectangle this frame's umbrae can cover.

use std::sync::Arc;

use super::shadow_map::{light_layout, LightUniforms, DEPTH_FORMAT};
use super::{next_generation, scissor};
use crate::geometry::volume_vertices::{disjoint_groups, union_all};
use crate::render::frame_tag::FrameTag;
use crate::render::gpu_scene::VolumeDraw;
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, depth_attachment, opaque, pipeline_layout, render_pipeline,
    shader_module, texture_entry, uniform_buffer, view_entry, GpuContext, PipelineSpec, Texture,
    VolumeVertex,
};

/// What a volume texel holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeLayout {
    /// `(distance, |cx_s|)`: all that `V(t)` reads but `V exact`.
    Distances,
    /// `(distance, |cx_s|, lit side)`: what `V exact` reads (the chord's direction under a
    /// polygon light, a closing fan's corner marker).
    WithSides,
}

impl VolumeLayout {
    /// The layout `V(t)` of `vt` reads.
    pub fn for_vt(vt: crate::geometry::VtVariant) -> VolumeLayout {
        if vt == crate::geometry::VtVariant::Exact {
            VolumeLayout::WithSides
        } else {
            VolumeLayout::Distances
        }
    }

    pub const fn format(self) -> wgpu::TextureFormat {
        match self {
            VolumeLayout::Distances => wgpu::TextureFormat::Rg32Float,
            VolumeLayout::WithSides => wgpu::TextureFormat::Rgba32Float,
        }
    }
}

/// Every format the volume channels may take (what an adapter must render to).
/// The pipelines of one [`VolumeLayout`], built once per device.
pub struct DBufferVolumesPass {
    layout: VolumeLayout,
    /// Penumbra entries and umbra exits in one pass with both targets.
    penumbra: wgpu::RenderPipeline,
    umbra: wgpu::RenderPipeline,
    /// Umbra exits of one group of casters into the scratch target (umbrae merged over casters).
    umbra_alone: wgpu::RenderPipeline,
    merge: wgpu::RenderPipeline,
    /// Depth 1 over a rectangle, the colours left: where the exits are drawn next.
    reset_depth: wgpu::RenderPipeline,
    light_layout: wgpu::BindGroupLayout,
    merge_layout: wgpu::BindGroupLayout,
}

fn depth_state(
    compare: wgpu::CompareFunction,
    bias: wgpu::DepthBiasState,
) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(true),
        depth_compare: Some(compare),
        stencil: wgpu::StencilState::default(),
        bias,
    })
}

impl DBufferVolumesPass {
    pub fn get(ctx: &GpuContext, layout: VolumeLayout) -> Arc<DBufferVolumesPass> {
        let name = match layout {
            VolumeLayout::Distances => "distances",
            VolumeLayout::WithSides => "with sides",
        };
        ctx.shared_named(name, |device| {
            let format = layout.format();
            let module = shader_module(device, "passes/dbuffer_volumes.wgsl");
            let light_layout = light_layout(device, "DBufferVolumesPass::light_layout");
            let merge_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("DBufferVolumesPass::merge_layout"),
                entries: &[texture_entry(
                    0,
                    wgpu::ShaderStages::FRAGMENT,
                    wgpu::TextureViewDimension::D2,
                )],
            });
            let pipelines = pipeline_layout(device, "DBufferVolumesPass::layout", &[&light_layout]);
            let merge_pipeline_layout = pipeline_layout(
                device,
                "DBufferVolumesPass::merge_layout",
                &[&light_layout, &merge_layout],
            );
            // One pass draws both channels: the penumbra target first, the umbra one second,
            // each pipeline writing one of them.
            let mask = |m| {
                Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: m,
                })
            };
            let only_penumbra = [
                mask(wgpu::ColorWrites::ALL),
                mask(wgpu::ColorWrites::empty()),
            ];
            let only_umbra = [
                mask(wgpu::ColorWrites::empty()),
                mask(wgpu::ColorWrites::ALL),
            ];
            let volume = |label, fs, targets: &[Option<wgpu::ColorTargetState>], cull, bias| {
                render_pipeline(
                    device,
                    &PipelineSpec {
                        label,
                        module: &module,
                        layout: &pipelines,
                        vs: "vs_volume",
                        fs: Some(fs),
                        buffers: &[Some(VolumeVertex::layout())],
                        targets,
                        cull: Some(cull),
                        depth: depth_state(wgpu::CompareFunction::Less, bias),
                    },
                )
            };
            // Umbra faces are wound with their normal away from c, penumbra faces toward it; the
            // light view is right-handed, so a face turned toward c is counter-clockwise (front).
            // An entry a texel's slope behind the surface still counts (texel-sized rounding of
            // the surface's depth must not hide an entry just in front of it).
            let entry_bias = wgpu::DepthBiasState {
                constant: 0,
                slope_scale: -1.0,
                clamp: 0.0,
            };
            let penumbra = volume(
                "DBufferVolumesPass::penumbra",
                "fs_volume_both",
                &only_penumbra,
                wgpu::Face::Back,
                entry_bias,
            );
            let umbra = volume(
                "DBufferVolumesPass::umbra",
                "fs_volume_both",
                &only_umbra,
                wgpu::Face::Front,
                wgpu::DepthBiasState::default(),
            );
            let umbra_alone = volume(
                "DBufferVolumesPass::umbra_alone",
                "fs_volume",
                &[opaque(format)],
                wgpu::Face::Front,
                wgpu::DepthBiasState::default(),
            );
            let merge = render_pipeline(
                device,
                &PipelineSpec {
                    label: "DBufferVolumesPass::merge",
                    module: &module,
                    layout: &merge_pipeline_layout,
                    vs: "vs_fullscreen",
                    fs: Some("fs_merge"),
                    buffers: &[],
                    targets: &[opaque(format)],
                    cull: None,
                    depth: depth_state(
                        wgpu::CompareFunction::Greater,
                        wgpu::DepthBiasState::default(),
                    ),
                },
            );
            let reset_depth = render_pipeline(
                device,
                &PipelineSpec {
                    label: "DBufferVolumesPass::reset_depth",
                    module: &module,
                    layout: &pipelines,
                    vs: "vs_reset",
                    fs: Some("fs_reset"),
                    buffers: &[],
                    targets: &[
                        mask(wgpu::ColorWrites::empty()),
                        mask(wgpu::ColorWrites::empty()),
                    ],
                    cull: None,
                    depth: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(wgpu::CompareFunction::Always),
                        stencil: wgpu::StencilState::default(),
                        bias: wgpu::DepthBiasState::default(),
                    }),
                },
            );
            DBufferVolumesPass {
                layout,
                penumbra,
                umbra,
                umbra_alone,
                merge,
                reset_depth,
                light_layout,
                merge_layout,
            }
        })
    }
}

/// One caster's umbra on the GPU, and where it falls in the light view.
pub struct CasterVolumes {
    pub umbra: VolumeDraw,
    /// `[x0, y0, x1, y1]` in `[0, 1]²` of the light view's image (y down) that its umbra can
    /// cover.
    pub rect: [f32; 4],
}

/// The volume channels' textures.
pub struct VolumeTargets {
    pub size: u32,
    pub layout: VolumeLayout,
    pub umbra: Texture,
    pub penumbra: Texture,
    depth: Texture,
    /// Only when umbrae overlap: each group's nearest exits, and the merge's depth.
    scratch: Option<(Texture, Texture, wgpu::BindGroup)>,
    pub generation: u64,
    /// The frame tag of the texels drawn last ([`FrameTag::NONE`]: new targets, not yet drawn).
    pub tag: FrameTag,
}

/// A session's D-buffer volume channels.
pub struct DBufferVolumes {
    /// The pipelines of the layout last drawn, and the light uniforms bound for them.
    pass: Option<(Arc<DBufferVolumesPass>, wgpu::BindGroup)>,
    uniforms: wgpu::Buffer,
    targets: Option<VolumeTargets>,
}

impl DBufferVolumes {
    pub fn new(ctx: &GpuContext) -> DBufferVolumes {
        DBufferVolumes {
            pass: None,
            uniforms: uniform_buffer::<LightUniforms>(&ctx.device, "DBufferVolumes::uniforms"),
            targets: None,
        }
    }

    pub fn targets(&self) -> Option<&VolumeTargets> {
        self.targets.as_ref()
    }

    /// The pipelines of `layout` and the light uniforms bound for them.
    fn pass_for(&mut self, ctx: &GpuContext, layout: VolumeLayout) -> Arc<DBufferVolumesPass> {
        if let Some((pass, _)) = self.pass.as_ref().filter(|(p, _)| p.layout == layout) {
            return pass.clone();
        }
        let pass = DBufferVolumesPass::get(ctx, layout);
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("DBufferVolumes::bind_group"),
            layout: &pass.light_layout,
            entries: &[buffer_entry(0, &self.uniforms)],
        });
        self.pass = Some((pass.clone(), bind_group));
        pass
    }

    fn ensure_targets(
        &mut self,
        pass: &DBufferVolumesPass,
        device: &wgpu::Device,
        size: u32,
        scratch: bool,
    ) {
        use wgpu::TextureUsages as U;
        let color = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
        let format = pass.layout.format();
        if self
            .targets
            .as_ref()
            .is_none_or(|t| t.size != size || t.layout != pass.layout)
        {
            self.targets = Some(VolumeTargets {
                size,
                layout: pass.layout,
                umbra: Texture::new(device, "VolumeTargets::umbra", (size, size), format, color),
                penumbra: Texture::new(
                    device,
                    "VolumeTargets::penumbra",
                    (size, size),
                    format,
                    color,
                ),
                depth: Texture::new(
                    device,
                    "VolumeTargets::depth",
                    (size, size),
                    DEPTH_FORMAT,
                    U::RENDER_ATTACHMENT,
                ),
                scratch: None,
                generation: next_generation(),
                tag: FrameTag::NONE,
            });
        }
        if let Some(t) = self
            .targets
            .as_mut()
            .filter(|t| scratch && t.scratch.is_none())
        {
            let texture = Texture::new(
                device,
                "VolumeTargets::scratch",
                (size, size),
                format,
                color,
            );
            let merge_depth = Texture::new(
                device,
                "VolumeTargets::merge_depth",
                (size, size),
                DEPTH_FORMAT,
                U::RENDER_ATTACHMENT,
            );
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("VolumeTargets::merge_bind_group"),
                layout: &pass.merge_layout,
                entries: &[view_entry(0, &texture.view)],
            });
            t.scratch = Some((texture, merge_depth, bind_group));
        }
    }

    /// Record the volume channels for `light`, the penumbra over `surface_depth` (the shadow
    /// map's depth, drawn for the same light view just before; this pass draws into it), with
    /// the next [`FrameTag`]; `layout` is what a texel holds.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        light: &LightUniforms,
        surface_depth: &Texture,
        casters: &[CasterVolumes],
        penumbra: &[VolumeDraw],
        layout: VolumeLayout,
    ) {
        let size = surface_depth.texture.width();
        let rects: Vec<[f32; 4]> = casters.iter().map(|c| c.rect).collect();
        let groups = disjoint_groups(&rects);
        let pass = self.pass_for(ctx, layout);
        self.ensure_targets(&pass, &ctx.device, size, groups.len() > 1);
        let (Some(t), Some((_, bind_group))) = (self.targets.as_mut(), self.pass.as_ref()) else {
            return;
        };
        // This frame's tag; new targets, and every target when the tags start over, are cleared
        // whole.
        let (tag, fresh) = t.tag.next();
        t.tag = tag;
        let light = LightUniforms {
            tag: tag.bits(),
            ..*light
        };
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&light));
        let span = rec.span("dbuffer_volumes");
        let load = |fresh: bool| {
            if fresh {
                wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
            } else {
                wgpu::LoadOp::Load
            }
        };
        let keep_color = |view, fresh: bool| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: load(fresh),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let merged = groups.len() > 1;
        // One pass on the surfaces' depth. |cx_pv|: the nearest entry in front of the nearest
        // surface. Then, where umbrae are drawn straight in, the depth is reset to 1 over their
        // rectangle and |cx_uv| takes each texel's nearest exit.
        {
            let mut p = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("DBufferVolumes::channels"),
                color_attachments: &[
                    keep_color(&t.penumbra.view, fresh),
                    keep_color(&t.umbra.view, fresh),
                ],
                depth_stencil_attachment: depth_attachment(
                    &surface_depth.view,
                    wgpu::LoadOp::Load,
                    false,
                ),
                timestamp_writes: span.writes(rec.timer, true, !merged),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            p.set_pipeline(&pass.penumbra);
            p.set_bind_group(0, bind_group, &[]);
            for v in penumbra {
                v.draw(&mut p);
            }
            if !merged {
                // From here on the depth is the exits': it starts at 1 over their rectangle.
                let [x0, y0, x1, y1] = scissor(union_all(rects.iter().copied()), size);
                if x0 < x1 && y0 < y1 {
                    p.set_scissor_rect(x0, y0, x1 - x0, y1 - y0);
                    p.set_pipeline(&pass.reset_depth);
                    p.set_bind_group(0, bind_group, &[]);
                    p.draw(0..3, 0..1);
                    p.set_scissor_rect(0, 0, size, size);
                }
                p.set_pipeline(&pass.umbra);
                p.set_bind_group(0, bind_group, &[]);
                for c in casters {
                    c.umbra.draw(&mut p);
                }
            }
        }
        if let ([_, _, ..], Some((scratch, merge_depth, merge_group))) =
            (groups.as_slice(), &t.scratch)
        {
            // Overlapping umbrae: group by group through the scratch target into the umbra
            // target, farthest wins by the merge's depth (texels no group reaches keep an
            // earlier frame's tag: no crossing).
            {
                rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("DBufferVolumes::merge_depth"),
                    color_attachments: &[],
                    depth_stencil_attachment: depth_attachment(
                        &merge_depth.view,
                        wgpu::LoadOp::Clear(0.0),
                        true,
                    ),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
            }
            let last = groups.len() - 1;
            for (g, (members, rect)) in groups.iter().enumerate() {
                {
                    let mut p = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some("DBufferVolumes::umbra_group"),
                        color_attachments: &[cleared(&scratch.view, wgpu::Color::TRANSPARENT)],
                        depth_stencil_attachment: depth_attachment(
                            &t.depth.view,
                            wgpu::LoadOp::Clear(1.0),
                            false,
                        ),
                        timestamp_writes: None,
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    p.set_pipeline(&pass.umbra_alone);
                    p.set_bind_group(0, bind_group, &[]);
                    for &i in members {
                        casters[i].umbra.draw(&mut p);
                    }
                }
                let mut p = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("DBufferVolumes::umbra_merge"),
                    color_attachments: &[keep_color(&t.umbra.view, false)],
                    depth_stencil_attachment: depth_attachment(
                        &merge_depth.view,
                        wgpu::LoadOp::Load,
                        true,
                    ),
                    timestamp_writes: span.writes(rec.timer, false, g == last),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                let [x0, y0, x1, y1] = scissor(*rect, size);
                p.set_scissor_rect(x0, y0, (x1 - x0).max(1), (y1 - y0).max(1));
                p.set_pipeline(&pass.merge);
                p.set_bind_group(0, bind_group, &[]);
                p.set_bind_group(1, merge_group, &[]);
                p.draw(0..3, 0..1);
            }
        }
    }
}
