//! `dbuffer-fused`'s per-texel edge lists (`shaders/passes/fused_lists.wgsl`), after its layers
//! (`passes::fused_layers`), once per light or caster move. CPU twin: `geometry::fused`
//! (`FusedTwin::texel_ray_of`, `edge_in_texel`, `proxy_hull`, `FusedTwin::crossings_of`).
//!
//! 1. `fused_merge` (a fragment shader over the list grid, scissored to what the proxies can
//!    cover): per list texel its ray and where its receivers can be, from the 3×3 texels around
//!    it: [`TEXEL_RAY_BYTES`] each.
//! 2. `fused_lists` (render): per candidate edge its proxy hull, instanced; per texel the list
//!    test; an edge that passes is counted (`atomicAdd`) and its id stored while the count is
//!    below the cap. Storage: `list_size`² counters and `list_size`² × cap ids (`u32`).
//! 3. `fused_maps` (a fragment shader over the `map_size`² target): per D-buffer texel the
//!    caster crossings along its ray, the largest crossing height over the 3×3 around it, its
//!    list's count and whether it overflowed (Rgba32Float): the method's light maps, and `L(c)`
//!    for the camera pass. Outside the casters and the proxies every texel is 0, so only their
//!    rectangle and the last one are drawn again.
//!
//! Both whole-grid passes are kept to the light view's rectangle that the casters and the
//! proxies cover (about half of the view on Table 1 and the fusion scenes, whose light view is
//! fitted to the casters' penumbrae).
//!
//! **Overflow rule.** Every edge that passes is counted; a list whose count exceeds the cap is
//! not used at all, whichever ids the GPU happened to store: the camera pass walks every candidate
//! edge for that pixel instead (the same V as a list long enough, at more cost), or gives it the
//! paper's `dbuffer` V where there are more than `geometry::fused::WHOLE_WALK_EDGES` of them. Below the cap the set of ids does not depend on the order in which
//! fragments ran, and neither does V.

use std::sync::Arc;

use super::fused_layers::{uniforms_layout, LayerTargets};
use super::{bounding, next_generation, scissor};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, opaque, pipeline_layout, render_pipeline, shader_module, view_entry,
    GpuContext, PipelineSpec, Texture,
};

/// Bytes of one list texel's ray (`TexelRay` of `shaders/shared/fused.wgsl`).
pub const TEXEL_RAY_BYTES: u64 = 128;
/// Bytes of one candidate edge (`FusedEdge`).
pub const EDGE_BYTES: u64 = 112;
/// One candidate edge as the GPU reads it (`geometry::fused::FusedEdge::gpu_record`).
pub type EdgeRecord = [[f32; 4]; 7];
/// Corners of one proxy hull (`geometry::fused::proxy_hull` has at most 16).
pub const HULL_CORNERS: usize = 16;
/// Bytes of one proxy hull.
pub const HULL_BYTES: u64 = (HULL_CORNERS * 8) as u64;
/// Vertices drawn per edge: a fan of 14 triangles over 16 corners.
const PROXY_VERTICES: u32 = 3 * (HULL_CORNERS as u32 - 2);
/// The per-texel light maps.
pub const MAPS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// The list pass writes no colour; a render pass needs an attachment.
const NO_COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

/// A texture read with `textureLoad`; a depth texture is bound as an unfilterable float one
/// too, which every backend can load (GLSL has no `textureLoad` of a depth texture).
fn texture(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// The pipelines, built once per device.
pub struct FusedListsPass {
    merge: wgpu::RenderPipeline,
    list: wgpu::RenderPipeline,
    maps: wgpu::RenderPipeline,
    uniforms_layout: wgpu::BindGroupLayout,
    merge_layout: wgpu::BindGroupLayout,
    list_layout: wgpu::BindGroupLayout,
    maps_layout: wgpu::BindGroupLayout,
}

impl FusedListsPass {
    pub fn get(ctx: &GpuContext) -> Arc<FusedListsPass> {
        ctx.shared(|device| {
            use wgpu::ShaderStages as S;
            let module = shader_module(device, "passes/fused_lists.wgsl");
            let uniforms_layout = uniforms_layout(device, "FusedListsPass::uniforms_layout");
            let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(label),
                    entries,
                })
            };
            let merge_layout = layout(
                "FusedListsPass::merge_layout",
                &[
                    texture(0, S::FRAGMENT),
                    texture(1, S::FRAGMENT),
                    texture(2, S::FRAGMENT),
                    texture(3, S::FRAGMENT),
                    texture(4, S::FRAGMENT),
                    crate::render::storage_entry(5, S::FRAGMENT, false),
                ],
            );
            let list_layout = layout(
                "FusedListsPass::list_layout",
                &[
                    crate::render::storage_entry(6, S::FRAGMENT, true),
                    crate::render::storage_entry(7, S::VERTEX, true),
                    crate::render::storage_entry(8, S::VERTEX, true),
                    crate::render::storage_entry(9, S::FRAGMENT, false),
                    crate::render::storage_entry(10, S::FRAGMENT, false),
                ],
            );
            let maps_layout = layout(
                "FusedListsPass::maps_layout",
                &[
                    texture(11, S::FRAGMENT),
                    texture(12, S::FRAGMENT),
                    crate::render::storage_entry(13, S::FRAGMENT, true),
                ],
            );
            let no_color = [Some(wgpu::ColorTargetState {
                format: NO_COLOR_FORMAT,
                blend: None,
                write_mask: wgpu::ColorWrites::empty(),
            })];
            let merge = render_pipeline(
                device,
                &PipelineSpec {
                    label: "FusedListsPass::merge",
                    module: &module,
                    layout: &pipeline_layout(
                        device,
                        "FusedListsPass::merge_pipeline_layout",
                        &[&uniforms_layout, &merge_layout],
                    ),
                    vs: "vs_main",
                    fs: Some("fs_merge"),
                    buffers: &[],
                    targets: &no_color,
                    cull: None,
                    depth: None,
                },
            );
            let list = render_pipeline(
                device,
                &PipelineSpec {
                    label: "FusedListsPass::list",
                    module: &module,
                    layout: &pipeline_layout(
                        device,
                        "FusedListsPass::list_pipeline_layout",
                        &[&uniforms_layout, &list_layout],
                    ),
                    vs: "vs_proxy",
                    fs: Some("fs_list"),
                    buffers: &[],
                    targets: &no_color,
                    cull: None,
                    depth: None,
                },
            );
            let maps = render_pipeline(
                device,
                &PipelineSpec {
                    label: "FusedListsPass::maps",
                    module: &module,
                    layout: &pipeline_layout(
                        device,
                        "FusedListsPass::maps_pipeline_layout",
                        &[&uniforms_layout, &maps_layout],
                    ),
                    vs: "vs_main",
                    fs: Some("fs_maps"),
                    buffers: &[],
                    targets: &[opaque(MAPS_FORMAT)],
                    cull: None,
                    depth: None,
                },
            );
            FusedListsPass {
                merge,
                list,
                maps,
                uniforms_layout,
                merge_layout,
                list_layout,
                maps_layout,
            }
        })
    }
}

/// The candidate edges on the GPU: their records and proxy hulls.
pub struct EdgeBuffers {
    pub edges: wgpu::Buffer,
    pub hulls: wgpu::Buffer,
    pub count: u32,
    pub generation: u64,
}

impl EdgeBuffers {
    /// `records`: [`crate::geometry::fused::FusedEdge::gpu_record`] per edge; `hulls`: each
    /// edge's proxy corners, padded to [`HULL_CORNERS`] by repeating the last.
    pub fn new(
        device: &wgpu::Device,
        records: &[EdgeRecord],
        hulls: &[[[f32; 2]; HULL_CORNERS]],
    ) -> EdgeBuffers {
        use wgpu::util::DeviceExt;
        // Storage bindings may not be empty.
        let records: Vec<EdgeRecord> = if records.is_empty() {
            vec![[[0.0; 4]; 7]]
        } else {
            records.to_vec()
        };
        let hull_data: Vec<[[f32; 2]; HULL_CORNERS]> = if hulls.is_empty() {
            vec![[[0.0; 2]; HULL_CORNERS]]
        } else {
            hulls.to_vec()
        };
        let buffer = |label, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        EdgeBuffers {
            edges: buffer("EdgeBuffers::edges", bytemuck::cast_slice(&records)),
            hulls: buffer("EdgeBuffers::hulls", bytemuck::cast_slice(&hull_data)),
            count: hulls.len().min(records.len()) as u32,
            generation: next_generation(),
        }
    }
}

/// The full-screen triangle of `pipeline` with bind groups 0 and 1, inside texel rectangle `r`
/// `[x0, y0, x1, y1]` (nothing where it is empty).
fn full_screen_in(
    p: &mut wgpu::RenderPass<'_>,
    r: [u32; 4],
    pipeline: &wgpu::RenderPipeline,
    groups: [&wgpu::BindGroup; 2],
) {
    let [x0, y0, x1, y1] = r;
    if x0 < x1 && y0 < y1 {
        p.set_scissor_rect(x0, y0, x1 - x0, y1 - y0);
        p.set_pipeline(pipeline);
        p.set_bind_group(0, groups[0], &[]);
        p.set_bind_group(1, groups[1], &[]);
        p.draw(0..3, 0..1);
    }
}

/// A render pass over one colour target and no depth, timed as `span` (its label).
fn timed_pass<'e>(
    rec: &'e mut Recorder<'_>,
    span: &'static str,
    color: Option<wgpu::RenderPassColorAttachment<'e>>,
) -> wgpu::RenderPass<'e> {
    let timer = rec.span(span);
    rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(span),
        color_attachments: &[color],
        depth_stencil_attachment: None,
        timestamp_writes: timer.writes(rec.timer, true, true),
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// The lists' storage and the maps, for one (map size, list size, cap).
pub struct ListTargets {
    pub map_size: u32,
    pub list_size: u32,
    pub cap: u32,
    rays: wgpu::Buffer,
    /// Per list texel, how many edges passed (`u32`).
    pub counts: wgpu::Buffer,
    /// Per list texel, `cap` edge ids (`u32`).
    pub lists: wgpu::Buffer,
    /// Per D-buffer texel: crossings, farthest crossing height, list count, overflow.
    pub maps: Texture,
    /// The maps' texels drawn last, outside of which every texel is 0 (none yet: all of it).
    maps_drawn: Option<[u32; 4]>,
    no_color: Texture,
    pub generation: u64,
}

/// Bytes of the lists' storage at a list grid of `list_size`² and `cap` ids per list: the
/// counters and the ids.
pub fn list_bytes(list_size: u32, cap: u32) -> u64 {
    let texels = u64::from(list_size) * u64::from(list_size);
    texels * 4 * (u64::from(cap) + 1)
}

/// A session's `dbuffer-fused` lists.
pub struct FusedLists {
    pass: Arc<FusedListsPass>,
    uniforms_group: wgpu::BindGroup,
    targets: Option<ListTargets>,
}

impl FusedLists {
    /// `uniforms`: the method's `FusedUniforms` buffer (written before each record).
    pub fn new(ctx: &GpuContext, uniforms: &wgpu::Buffer) -> FusedLists {
        let pass = FusedListsPass::get(ctx);
        let uniforms_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("FusedLists::uniforms_group"),
            layout: &pass.uniforms_layout,
            entries: &[buffer_entry(0, uniforms)],
        });
        FusedLists {
            pass,
            uniforms_group,
            targets: None,
        }
    }

    pub fn targets(&self) -> Option<&ListTargets> {
        self.targets.as_ref()
    }

    fn ensure_targets(&mut self, device: &wgpu::Device, map_size: u32, list_size: u32, cap: u32) {
        if self
            .targets
            .as_ref()
            .is_some_and(|t| (t.map_size, t.list_size, t.cap) == (map_size, list_size, cap))
        {
            return;
        }
        use wgpu::BufferUsages as B;
        use wgpu::TextureUsages as U;
        let texels = u64::from(list_size) * u64::from(list_size);
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            })
        };
        self.targets = Some(ListTargets {
            map_size,
            list_size,
            cap,
            rays: buffer("ListTargets::rays", texels * TEXEL_RAY_BYTES, B::STORAGE),
            counts: buffer(
                "ListTargets::counts",
                texels * 4,
                B::STORAGE | B::COPY_DST | B::COPY_SRC,
            ),
            lists: buffer(
                "ListTargets::lists",
                texels * u64::from(cap) * 4,
                B::STORAGE | B::COPY_SRC,
            ),
            maps: Texture::new(
                device,
                "ListTargets::maps",
                (map_size, map_size),
                MAPS_FORMAT,
                U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
            ),
            maps_drawn: None,
            no_color: Texture::new(
                device,
                "ListTargets::no_color",
                (list_size, list_size),
                NO_COLOR_FORMAT,
                U::RENDER_ATTACHMENT,
            ),
            generation: next_generation(),
        });
    }

    /// Record the merge, the lists of `edges` and the maps from `layers` (drawn for the same
    /// light, sizes and uniforms just before), with `cap` ids per list.
    /// `rect`: the part of the light view (`[0, 1]²`, y down) that the casters and the edges'
    /// proxies cover.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        layers: &LayerTargets,
        edges: &EdgeBuffers,
        cap: u32,
        rect: [f32; 4],
    ) {
        let (map_size, list_size) = (layers.map_size, layers.list_size);
        self.ensure_targets(&ctx.device, map_size, list_size, cap);
        let Some(t) = self.targets.as_mut() else {
            return;
        };
        // The maps: this rectangle grown by a list texel (a list texel partly inside it has
        // D-buffer texels outside), and the last one, which may hold values this frame has not.
        let grow = 1.0 / list_size.max(1) as f32;
        let maps_now = scissor(
            [
                rect[0] - grow,
                rect[1] - grow,
                rect[2] + grow,
                rect[3] + grow,
            ],
            map_size,
        );
        let maps_rect = bounding(
            t.maps_drawn
                .replace(maps_now)
                .unwrap_or([0, 0, map_size, map_size]),
            maps_now,
        );
        let t = &*t;
        let device = &ctx.device;
        let pass = &self.pass;
        let group = |label, layout, entries: &[wgpu::BindGroupEntry<'_>]| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout,
                entries,
            })
        };
        let merge_group = group(
            "FusedLists::merge_group",
            &pass.merge_layout,
            &[
                view_entry(0, &layers.first.view),
                view_entry(1, &layers.second.view),
                view_entry(2, &layers.last.view),
                view_entry(3, &layers.last_caster.view),
                view_entry(4, &layers.receivers.view),
                buffer_entry(5, &t.rays),
            ],
        );
        let list_group = group(
            "FusedLists::list_group",
            &pass.list_layout,
            &[
                buffer_entry(6, &t.rays),
                buffer_entry(7, &edges.edges),
                buffer_entry(8, &edges.hulls),
                buffer_entry(9, &t.counts),
                buffer_entry(10, &t.lists),
            ],
        );
        let maps_group = group(
            "FusedLists::maps_group",
            &pass.maps_layout,
            &[
                view_entry(11, &layers.crossings.view),
                view_entry(12, &layers.crossing_far.view),
                buffer_entry(13, &t.counts),
            ],
        );
        let no_color = || cleared(&t.no_color.view, wgpu::Color::TRANSPARENT);
        {
            let mut p = timed_pass(rec, "fused_merge", no_color());
            // Only the texels a proxy can cover: the list pass reads no other ray.
            let groups = [&self.uniforms_group, &merge_group];
            full_screen_in(&mut p, scissor(rect, list_size), &pass.merge, groups);
        }
        rec.encoder.clear_buffer(&t.counts, 0, None);
        {
            let mut p = timed_pass(rec, "fused_lists", no_color());
            if edges.count > 0 {
                p.set_pipeline(&pass.list);
                p.set_bind_group(0, &self.uniforms_group, &[]);
                p.set_bind_group(1, &list_group, &[]);
                p.draw(0..PROXY_VERTICES, 0..edges.count);
            }
        }
        let maps = Some(wgpu::RenderPassColorAttachment {
            view: &t.maps.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                // Outside the rectangle drawn the texels hold 0 already.
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        });
        let mut p = timed_pass(rec, "fused_maps", maps);
        let groups = [&self.uniforms_group, &maps_group];
        full_screen_in(&mut p, maps_rect, &pass.maps, groups);
    }
}
