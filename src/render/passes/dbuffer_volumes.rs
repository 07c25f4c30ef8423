//! The D-buffer's volume channels (`shaders/passes/dbuffer_volumes.wgsl`), drawn from the light
//! centre after the shadow map: umbra `(|cx_uv|, |cx_s|)` and penumbra `(|cx_pv|, |cx_s|)`,
//! `size`² texels of Rg32Float each.
//!
//! - Penumbra: every caster's entry faces (the pipeline culls the faces turned away from `c`)
//!   over a copy of the shadow map's depth, nearest wins: an entry behind the nearest surface is
//!   never looked up (only points visible from `c` read this channel), so those fragments die in
//!   the early depth test.
//! - Umbra: per caster the nearest exit face (front faces culled), then the farthest over
//!   casters. Casters whose volumes do not overlap in the light's view are drawn together, since
//!   "farthest over casters" has nothing to decide there; only overlapping groups go through a
//!   scratch target merged with the depth test Greater, each inside its own rectangle.

use std::sync::Arc;

use super::next_generation;
use super::shadow_map::{light_layout, LightUniforms, DEPTH_FORMAT};
use crate::render::gpu_scene::VertexChunks;
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, depth_attachment, opaque, pipeline_layout, render_pipeline,
    shader_module, texture_entry, uniform_buffer, view_entry, GpuContext, PipelineSpec, Texture,
    VolumeVertex,
};

pub const VOLUME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// The pipelines, built once per device.
pub struct DBufferVolumesPass {
    penumbra: wgpu::RenderPipeline,
    umbra: wgpu::RenderPipeline,
    merge: wgpu::RenderPipeline,
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
    pub fn get(ctx: &GpuContext) -> Arc<DBufferVolumesPass> {
        ctx.shared(|device| {
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
            let layout = pipeline_layout(device, "DBufferVolumesPass::layout", &[&light_layout]);
            let merge_pipeline_layout = pipeline_layout(
                device,
                "DBufferVolumesPass::merge_layout",
                &[&light_layout, &merge_layout],
            );
            let volume = |label, cull, bias| {
                render_pipeline(
                    device,
                    &PipelineSpec {
                        label,
                        module: &module,
                        layout: &layout,
                        vs: "vs_volume",
                        fs: Some("fs_volume"),
                        buffers: &[Some(VolumeVertex::layout())],
                        targets: &[opaque(VOLUME_FORMAT)],
                        cull: Some(cull),
                        depth: depth_state(wgpu::CompareFunction::Less, bias),
                    },
                )
            };
            // Umbra faces are wound with their normal away from c, penumbra faces toward it; the
            // light view is right-handed, so a face turned toward c is counter-clockwise (front).
            let penumbra = volume(
                "DBufferVolumesPass::penumbra",
                wgpu::Face::Back,
                // An entry a texel's slope behind the surface still counts (texel-sized rounding
                // of the surface's depth must not hide an entry just in front of it).
                wgpu::DepthBiasState {
                    constant: 0,
                    slope_scale: -1.0,
                    clamp: 0.0,
                },
            );
            let umbra = volume(
                "DBufferVolumesPass::umbra",
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
                    targets: &[opaque(VOLUME_FORMAT)],
                    cull: None,
                    depth: depth_state(
                        wgpu::CompareFunction::Greater,
                        wgpu::DepthBiasState::default(),
                    ),
                },
            );
            DBufferVolumesPass {
                penumbra,
                umbra,
                merge,
                light_layout,
                merge_layout,
            }
        })
    }
}

/// One caster's umbra on the GPU, and where it falls in the light view.
pub struct CasterVolumes {
    pub umbra: VertexChunks,
    /// `[x0, y0, x1, y1]` in `[0, 1]²` of the light view's image (y down) that its umbra can
    /// cover.
    pub rect: [f32; 4],
}

/// The volume channels' textures.
pub struct VolumeTargets {
    pub size: u32,
    pub umbra: Texture,
    pub penumbra: Texture,
    depth: Texture,
    /// Only when umbrae overlap: each group's nearest exits, and the merge's depth.
    scratch: Option<(Texture, Texture, wgpu::BindGroup)>,
    pub generation: u64,
}

/// A session's D-buffer volume channels.
pub struct DBufferVolumes {
    pass: Arc<DBufferVolumesPass>,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    targets: Option<VolumeTargets>,
}

/// Groups of casters whose umbra rectangles do not overlap (greedy, in order).
fn disjoint_groups(casters: &[CasterVolumes]) -> Vec<(Vec<usize>, [f32; 4])> {
    let overlap =
        |a: [f32; 4], b: [f32; 4]| a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3];
    let mut groups: Vec<(Vec<usize>, Vec<[f32; 4]>)> = Vec::new();
    for (i, c) in casters.iter().enumerate() {
        if c.umbra.is_empty() {
            continue;
        }
        match groups
            .iter_mut()
            .find(|(_, rects)| rects.iter().all(|r| !overlap(*r, c.rect)))
        {
            Some(g) => {
                g.0.push(i);
                g.1.push(c.rect);
            }
            None => groups.push((vec![i], vec![c.rect])),
        }
    }
    groups
        .into_iter()
        .map(|(members, rects)| {
            let hull = rects.iter().fold([1.0f32, 1.0, 0.0, 0.0], |h, r| {
                [
                    h[0].min(r[0]),
                    h[1].min(r[1]),
                    h[2].max(r[2]),
                    h[3].max(r[3]),
                ]
            });
            (members, hull)
        })
        .collect()
}

impl DBufferVolumes {
    pub fn new(ctx: &GpuContext) -> DBufferVolumes {
        let pass = DBufferVolumesPass::get(ctx);
        let uniforms = uniform_buffer::<LightUniforms>(&ctx.device, "DBufferVolumes::uniforms");
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("DBufferVolumes::bind_group"),
            layout: &pass.light_layout,
            entries: &[buffer_entry(0, &uniforms)],
        });
        DBufferVolumes {
            pass,
            uniforms,
            bind_group,
            targets: None,
        }
    }

    pub fn targets(&self) -> Option<&VolumeTargets> {
        self.targets.as_ref()
    }

    fn ensure_targets(&mut self, device: &wgpu::Device, size: u32, scratch: bool) {
        use wgpu::TextureUsages as U;
        let color = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
        if self.targets.as_ref().is_none_or(|t| t.size != size) {
            self.targets = Some(VolumeTargets {
                size,
                umbra: Texture::new(
                    device,
                    "VolumeTargets::umbra",
                    (size, size),
                    VOLUME_FORMAT,
                    color,
                ),
                penumbra: Texture::new(
                    device,
                    "VolumeTargets::penumbra",
                    (size, size),
                    VOLUME_FORMAT,
                    color,
                ),
                depth: Texture::new(
                    device,
                    "VolumeTargets::depth",
                    (size, size),
                    DEPTH_FORMAT,
                    U::RENDER_ATTACHMENT | U::COPY_DST,
                ),
                scratch: None,
                generation: next_generation(),
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
                VOLUME_FORMAT,
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
                layout: &self.pass.merge_layout,
                entries: &[view_entry(0, &texture.view)],
            });
            t.scratch = Some((texture, merge_depth, bind_group));
        }
    }

    /// Record the volume channels for `light` at `size`² texels, over the shadow map's `depth`
    /// (drawn for the same light view just before).
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        light: &LightUniforms,
        shadow_depth: &wgpu::Texture,
        casters: &[CasterVolumes],
        penumbra: &VertexChunks,
    ) {
        let size = shadow_depth.width();
        let groups = disjoint_groups(casters);
        self.ensure_targets(&ctx.device, size, groups.len() > 1);
        let Some(t) = &self.targets else { return };
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(light));
        let span = rec.span("dbuffer_volumes");
        let no_volume = wgpu::Color::TRANSPARENT;

        // |cx_pv|: the nearest entry in front of the nearest surface.
        rec.encoder.copy_texture_to_texture(
            shadow_depth.as_image_copy(),
            t.depth.texture.as_image_copy(),
            shadow_depth.size(),
        );
        {
            let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("DBufferVolumes::penumbra"),
                color_attachments: &[cleared(&t.penumbra.view, no_volume)],
                depth_stencil_attachment: depth_attachment(
                    &t.depth.view,
                    wgpu::LoadOp::Load,
                    false,
                ),
                timestamp_writes: span.writes(rec.timer, true, false),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pass.penumbra);
            pass.set_bind_group(0, &self.bind_group, &[]);
            penumbra.draw(&mut pass);
        }

        // |cx_uv|: each caster's nearest exit, the farthest over casters.
        match (groups.as_slice(), &t.scratch) {
            ([_, _, ..], Some((scratch, merge_depth, merge_group))) => {
                // Overlapping umbrae: group by group through the scratch target.
                {
                    // The merged target starts empty (0: no exit) with depth 0 for "farthest wins".
                    rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some("DBufferVolumes::umbra_clear"),
                        color_attachments: &[cleared(&t.umbra.view, no_volume)],
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
                        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                            label: Some("DBufferVolumes::umbra_group"),
                            color_attachments: &[cleared(&scratch.view, no_volume)],
                            depth_stencil_attachment: depth_attachment(
                                &t.depth.view,
                                wgpu::LoadOp::Clear(1.0),
                                false,
                            ),
                            timestamp_writes: None,
                            occlusion_query_set: None,
                            multiview_mask: None,
                        });
                        pass.set_pipeline(&self.pass.umbra);
                        pass.set_bind_group(0, &self.bind_group, &[]);
                        for &i in members {
                            casters[i].umbra.draw(&mut pass);
                        }
                    }
                    let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some("DBufferVolumes::umbra_merge"),
                        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                            view: &t.umbra.view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load: wgpu::LoadOp::Load,
                                store: wgpu::StoreOp::Store,
                            },
                        })],
                        depth_stencil_attachment: depth_attachment(
                            &merge_depth.view,
                            wgpu::LoadOp::Load,
                            true,
                        ),
                        timestamp_writes: span.writes(rec.timer, false, g == last),
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    let (x0, y0, x1, y1) = scissor(*rect, size);
                    pass.set_scissor_rect(x0, y0, x1 - x0, y1 - y0);
                    pass.set_pipeline(&self.pass.merge);
                    pass.set_bind_group(0, &self.bind_group, &[]);
                    pass.set_bind_group(1, merge_group, &[]);
                    pass.draw(0..3, 0..1);
                }
            }
            _ => {
                // One group: every exit straight into the target, nearest wins.
                let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("DBufferVolumes::umbra"),
                    color_attachments: &[cleared(&t.umbra.view, no_volume)],
                    depth_stencil_attachment: depth_attachment(
                        &t.depth.view,
                        wgpu::LoadOp::Clear(1.0),
                        false,
                    ),
                    timestamp_writes: span.writes(rec.timer, false, true),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.pass.umbra);
                pass.set_bind_group(0, &self.bind_group, &[]);
                for c in casters {
                    c.umbra.draw(&mut pass);
                }
            }
        }
    }
}

/// A rectangle of `[0, 1]²` as whole texels of a `size`² target, one texel of margin.
fn scissor(rect: [f32; 4], size: u32) -> (u32, u32, u32, u32) {
    let n = size as f32;
    let lo = |v: f32| ((v * n).floor() - 1.0).clamp(0.0, n) as u32;
    let hi = |v: f32| ((v * n).ceil() + 1.0).clamp(0.0, n) as u32;
    let (x0, y0) = (lo(rect[0]), lo(rect[1]));
    let (x1, y1) = (
        hi(rect[2]).max(x0 + 1).min(size),
        hi(rect[3]).max(y0 + 1).min(size),
    );
    (x0.min(size - 1), y0.min(size - 1), x1, y1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scissor_covers_the_rect_with_a_margin_and_stays_inside() {
        assert_eq!(scissor([0.0, 0.0, 1.0, 1.0], 100), (0, 0, 100, 100));
        assert_eq!(scissor([0.25, 0.5, 0.5, 0.75], 100), (24, 49, 51, 76));
        let (x0, y0, x1, y1) = scissor([0.999, 0.999, 1.0, 1.0], 10);
        assert!(x0 < x1 && y0 < y1 && x1 <= 10 && y1 <= 10);
    }
}
