//! `linear-ssm`'s skins and visibility channels (Heidrich et al. 2000, §3.2): for each light sample `j`, a
//! compute pass extracts the skins of its distance map (`shaders/passes/ssm_skins.wgsl`, CPU twin
//! [`crate::geometry::ssm::skins`]) into one skin buffer, and two small render passes draw them
//! into the visibility channels of its neighbours `j − 1` and `j + 1`
//! (`shaders/passes/ssm_visibility.wgsl`).
//!
//! The channels are one `Rg32Float` array texture, a layer per sample: R holds the pair (k − 1,
//! k), G the pair (k, k + 1). Each starts at half its pair's share of the light (0 where there is
//! no such pair), so a point every sample sees sums to 1; a skin overwrites its channel where the
//! sample sees it. One skin buffer serves every map in turn (a map's skins are drawn before the
//! next map's are extracted); it holds [`MAX_SSM_SKINS`] triangles, and a map with more loses
//! the rest (its penumbrae get holes; [`Ssm::skin_count`] tells).

use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::{next_generation, LayeredTargets};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, compute_pipeline, pipeline_layout, render_pipeline, shader_module, texture_entry,
    uniform_entry, view_entry, GpuContext, PipelineSpec, RenderError,
};

/// The most light samples on the segment (ends included).
pub const MAX_SSM_SAMPLES: u32 = 16;
/// Skin triangles one map may yield (the skin buffer's capacity: 32 bytes a corner).
pub const MAX_SSM_SKINS: u32 = 1 << 17;
/// A skin fragment farther from the sample than its own nearest surface by this fraction is
/// hidden behind real geometry.
pub const SKIN_BIAS: f32 = 2e-3;
pub const VISIBILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// `SsmSample` of `shaders/shared/ssm_sample.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SsmSample {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub point: [f32; 3],
    pub layer: u32,
    pub size: u32,
    pub capacity: u32,
    pub far: f32,
    pub tau: f32,
    pub weight: f32,
    pub skin_bias: f32,
    /// Floats per row of the map's copy the skin extraction reads (rows padded to 256 bytes).
    pub pitch: u32,
    pub _pad1: f32,
}

const _: () = assert!(std::mem::size_of::<SsmSample>() == 176);

impl SsmSample {
    /// Sample `layer` of `count` at `point`, drawn with `view_proj` into `size`² maps whose
    /// empty texels lie `far` away.
    pub fn new(view_proj: Mat4, point: Vec3, layer: u32, count: u32, size: u32, far: f32) -> Self {
        SsmSample {
            view_proj: view_proj.to_cols_array_2d(),
            inv_view_proj: view_proj.inverse().to_cols_array_2d(),
            point: point.to_array(),
            layer,
            size,
            capacity: MAX_SSM_SKINS,
            far,
            tau: crate::geometry::ssm::SKIN_TAU,
            weight: 1.0 / (count.max(2) - 1) as f32,
            skin_bias: SKIN_BIAS,
            pitch: pitch(size),
            _pad1: 0.0,
        }
    }
}

/// Floats per row of a `size`-texel-wide map copied into a buffer (rows of 256-byte multiples).
pub fn pitch(size: u32) -> u32 {
    (size * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT / 4
}

/// `SkinVertex` of `shaders/shared/ssm_sample.wgsl`: one corner of a skin triangle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SkinVertex {
    pub position: [f32; 3],
    pub value: f32,
    /// The cell `y · size + x` it came from, and which of its four corners.
    pub cell: u32,
    pub corner: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

const _: () = assert!(std::mem::size_of::<SkinVertex>() == 32);

impl SkinVertex {
    const ATTRIBUTES: [wgpu::VertexAttribute; 2] = [
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32x3,
            offset: 0,
            shader_location: 0,
        },
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::Float32,
            offset: 12,
            shader_location: 1,
        },
    ];

    fn layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<SkinVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Self::ATTRIBUTES,
        }
    }
}

/// The pipelines, built once per device.
pub struct SsmPass {
    find: wgpu::ComputePipeline,
    size_extract: wgpu::ComputePipeline,
    extract: wgpu::ComputePipeline,
    finish: wgpu::ComputePipeline,
    compute_layout: wgpu::BindGroupLayout,
    dispatch_layout: wgpu::BindGroupLayout,
    /// Skins into the R channel (the pair with the previous sample) and into G (the next).
    draw: [wgpu::RenderPipeline; 2],
    draw_layout: wgpu::BindGroupLayout,
}

impl SsmPass {
    pub fn get(ctx: &GpuContext) -> Arc<SsmPass> {
        ctx.shared(|device| {
            let skins = shader_module(device, "passes/ssm_skins.wgsl");
            let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            };
            let compute_layout =
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("SsmPass::compute_layout"),
                    entries: &[
                        uniform_entry(0, wgpu::ShaderStages::COMPUTE),
                        storage(1, true),
                        storage(2, false),
                        storage(3, false),
                        storage(4, false),
                        storage(5, false),
                    ],
                });
            let dispatch_layout =
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("SsmPass::dispatch_layout"),
                    entries: &[storage(0, false)],
                });
            let one = pipeline_layout(device, "SsmPass::compute", &[&compute_layout]);
            let two = pipeline_layout(
                device,
                "SsmPass::size_extract",
                &[&compute_layout, &dispatch_layout],
            );
            let compute = |entry: &str, layout: &wgpu::PipelineLayout| {
                compute_pipeline(device, entry, layout, &skins, entry)
            };
            let (find, size_extract) = (compute("find", &one), compute("size_extract", &two));
            let (extract, finish) = (compute("extract", &one), compute("finish", &one));

            let module = shader_module(device, "passes/ssm_visibility.wgsl");
            let draw_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("SsmPass::draw_layout"),
                entries: &[
                    uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT),
                    texture_entry(
                        1,
                        wgpu::ShaderStages::FRAGMENT,
                        wgpu::TextureViewDimension::D2Array,
                    ),
                ],
            });
            let layout = pipeline_layout(device, "SsmPass::draw", &[&draw_layout]);
            let draw = [wgpu::ColorWrites::RED, wgpu::ColorWrites::GREEN].map(|mask| {
                render_pipeline(
                    device,
                    &PipelineSpec {
                        label: "SsmPass::draw",
                        module: &module,
                        layout: &layout,
                        vs: "vs_main",
                        fs: Some("fs_main"),
                        buffers: &[Some(SkinVertex::layout())],
                        targets: &[Some(wgpu::ColorTargetState {
                            format: VISIBILITY_FORMAT,
                            blend: None,
                            write_mask: mask,
                        })],
                        cull: None,
                        depth: crate::render::depth_test(wgpu::CompareFunction::Less),
                    },
                )
            });
            SsmPass {
                find,
                size_extract,
                extract,
                finish,
                compute_layout,
                dispatch_layout,
                draw,
                draw_layout,
            }
        })
    }
}

/// The visibility channels: one array texture, a layer per sample.
pub struct SsmTargets {
    pub size: u32,
    pub layers: u32,
    pub texture: wgpu::Texture,
    /// The whole array, for the camera pass.
    pub array_view: wgpu::TextureView,
    layer_views: Vec<wgpu::TextureView>,
    depth: wgpu::TextureView,
    pub generation: u64,
}

/// A session's skins and channels.
pub struct Ssm {
    pass: Arc<SsmPass>,
    samples: Vec<wgpu::Buffer>,
    /// The map being searched for skins, copied out of its layer (grown to the map size).
    map: wgpu::Buffer,
    skins: wgpu::Buffer,
    /// Skin triangles appended, cells listed.
    counts: wgpu::Buffer,
    /// The skins' draw arguments.
    args: wgpu::Buffer,
    /// The discontinuous cells of the map being triangulated, and `extract`'s dispatch size.
    cells: wgpu::Buffer,
    dispatch: wgpu::Buffer,
    dispatch_group: wgpu::BindGroup,
    targets: Option<SsmTargets>,
    /// Per sample: the compute and the draw bind groups, and the maps' generation they bind.
    groups: Option<(Vec<(wgpu::BindGroup, wgpu::BindGroup)>, u64)>,
}

impl Ssm {
    pub fn new(ctx: &GpuContext) -> Ssm {
        use wgpu::BufferUsages as U;
        let device = &ctx.device;
        let buffer = |label: &str, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let pass = SsmPass::get(ctx);
        let dispatch = buffer("Ssm::dispatch", 12, U::STORAGE | U::INDIRECT);
        let dispatch_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Ssm::dispatch_group"),
            layout: &pass.dispatch_layout,
            entries: &[buffer_entry(0, &dispatch)],
        });
        Ssm {
            pass,
            samples: (0..MAX_SSM_SAMPLES)
                .map(|_| crate::render::uniform_buffer::<SsmSample>(device, "Ssm::sample"))
                .collect(),
            skins: buffer(
                "Ssm::skins",
                u64::from(MAX_SSM_SKINS) * 3 * std::mem::size_of::<SkinVertex>() as u64,
                U::STORAGE | U::VERTEX | U::COPY_SRC,
            ),
            map: buffer("Ssm::map", 4, U::STORAGE | U::COPY_DST),
            counts: buffer("Ssm::counts", 8, U::STORAGE | U::COPY_DST | U::COPY_SRC),
            args: buffer("Ssm::args", 16, U::STORAGE | U::INDIRECT),
            // A cell yields at most two skins: as many cells as skin triangles is enough.
            cells: buffer("Ssm::cells", u64::from(MAX_SSM_SKINS) * 4, U::STORAGE),
            dispatch,
            dispatch_group,
            targets: None,
            groups: None,
        }
    }

    pub fn targets(&self) -> Option<&SsmTargets> {
        self.targets.as_ref()
    }

    /// The skin buffer and its counters (skin triangles the last map yielded before the
    /// capacity's clamp, and its discontinuous cells): for tests.
    pub fn skin_buffers(&self) -> (&wgpu::Buffer, &wgpu::Buffer) {
        (&self.skins, &self.counts)
    }

    fn ensure_targets(&mut self, device: &wgpu::Device, size: u32, layers: u32) {
        if self
            .targets
            .as_ref()
            .is_some_and(|t| t.size == size && t.layers == layers)
        {
            return;
        }
        let LayeredTargets {
            texture,
            array_view,
            layer_views,
            depth,
        } = LayeredTargets::new(
            device,
            "SsmTargets::visibility",
            size,
            layers,
            (VISIBILITY_FORMAT, DEPTH_FORMAT),
        );
        self.targets = Some(SsmTargets {
            size,
            layers,
            texture,
            array_view,
            layer_views,
            depth,
            generation: next_generation(),
        });
    }

    /// Record the skins and channels of `samples` (at least 2, at most [`MAX_SSM_SAMPLES`],
    /// layer `k` of `maps` (whose view is `maps_view`) being sample `k`'s distance map,
    /// `maps_generation` changing whenever that texture is made again).
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        (maps, maps_view, maps_generation): (&wgpu::Texture, &wgpu::TextureView, u64),
        samples: &[SsmSample],
    ) -> Result<(), RenderError> {
        let n = samples.len();
        if !(2..=MAX_SSM_SAMPLES as usize).contains(&n) {
            return Err(RenderError::Request(format!(
                "linear-ssm takes 2 to {MAX_SSM_SAMPLES} samples, found {n}"
            )));
        }
        let size = samples[0].size;
        self.ensure_targets(&ctx.device, size, n as u32);
        let map_bytes = u64::from(pitch(size)) * u64::from(size) * 4;
        let mut regroup = false;
        if self.map.size() < map_bytes {
            self.map = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("Ssm::map"),
                size: map_bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            regroup = true;
        }
        for (buffer, s) in self.samples.iter().zip(samples) {
            ctx.queue.write_buffer(buffer, 0, bytemuck::bytes_of(s));
        }
        if regroup
            || self
                .groups
                .as_ref()
                .is_none_or(|(_, g)| *g != maps_generation)
        {
            let device = &ctx.device;
            let groups = self
                .samples
                .iter()
                .map(|uniform| {
                    let compute = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("Ssm::compute_group"),
                        layout: &self.pass.compute_layout,
                        entries: &[
                            buffer_entry(0, uniform),
                            buffer_entry(1, &self.map),
                            buffer_entry(2, &self.skins),
                            buffer_entry(3, &self.counts),
                            buffer_entry(4, &self.args),
                            buffer_entry(5, &self.cells),
                        ],
                    });
                    let draw = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("Ssm::draw_group"),
                        layout: &self.pass.draw_layout,
                        entries: &[buffer_entry(0, uniform), view_entry(1, maps_view)],
                    });
                    (compute, draw)
                })
                .collect();
            self.groups = Some((groups, maps_generation));
        }
        let (Some(t), Some((groups, _))) = (&self.targets, &self.groups) else {
            return Ok(());
        };
        let span = rec.span("ssm_skins");
        // Every channel at half its pair's share (none at the ends of the segment).
        let half = 0.5 * f64::from(samples[0].weight);
        for (k, view) in t.layer_views.iter().enumerate() {
            let clear = wgpu::Color {
                r: if k > 0 { half } else { 0.0 },
                g: if k + 1 < n { half } else { 0.0 },
                b: 0.0,
                a: 0.0,
            };
            let pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("Ssm::clear"),
                color_attachments: &[crate::render::cleared(view, clear)],
                depth_stencil_attachment: None,
                timestamp_writes: span.writes(rec.timer, k == 0, false),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            drop(pass);
        }
        // One invocation per 2×2 block of cells, 8×8 invocations a workgroup.
        let groups_per_side = size.saturating_sub(1).div_ceil(16);
        for j in 0..n {
            rec.encoder.clear_buffer(&self.counts, 0, None);
            rec.encoder.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    texture: maps,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: j as u32,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::TexelCopyBufferInfo {
                    buffer: &self.map,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(pitch(size) * 4),
                        rows_per_image: Some(size),
                    },
                },
                wgpu::Extent3d {
                    width: size,
                    height: size,
                    depth_or_array_layers: 1,
                },
            );
            // Three passes: a buffer may not be written by a dispatch's bindings and read as
            // its indirect arguments in one usage scope.
            let group = &groups[j].0;
            {
                let mut pass = compute_pass(rec.encoder, "Ssm::find", group);
                pass.set_pipeline(&self.pass.find);
                pass.dispatch_workgroups(groups_per_side, groups_per_side, 1);
            }
            {
                let mut pass = compute_pass(rec.encoder, "Ssm::size_extract", group);
                pass.set_bind_group(1, &self.dispatch_group, &[]);
                pass.set_pipeline(&self.pass.size_extract);
                pass.dispatch_workgroups(1, 1, 1);
            }
            {
                let mut pass = compute_pass(rec.encoder, "Ssm::extract", group);
                pass.set_pipeline(&self.pass.extract);
                pass.dispatch_workgroups_indirect(&self.dispatch, 0);
                pass.set_pipeline(&self.pass.finish);
                pass.dispatch_workgroups(1, 1, 1);
            }
            // Skins of map j into sample j − 1's G (the pair (j − 1, j)) and j + 1's R.
            let targets = [
                (j.checked_sub(1), 1usize),
                (Some(j + 1).filter(|&k| k < n), 0),
            ];
            for (k, channel) in targets {
                let Some(k) = k else { continue };
                // The last map has one neighbour: its pass ends the span.
                let last = j + 1 == n;
                let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("Ssm::draw"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &t.layer_views[k],
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: crate::render::depth_attachment(
                        &t.depth,
                        wgpu::LoadOp::Clear(1.0),
                        false,
                    ),
                    timestamp_writes: span.writes(rec.timer, false, last),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(&self.pass.draw[channel]);
                pass.set_bind_group(0, &groups[k].1, &[]);
                pass.set_vertex_buffer(0, self.skins.slice(..));
                pass.draw_indirect(&self.args, 0);
            }
        }
        Ok(())
    }
}

/// A compute pass with `group` as its group 0.
fn compute_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    group: &wgpu::BindGroup,
) -> wgpu::ComputePass<'e> {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    pass.set_bind_group(0, group, &[]);
    pass
}
