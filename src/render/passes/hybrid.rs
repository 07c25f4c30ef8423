//! Shadow volumes reconstructed from a depth map (`shaders/passes/hybrid.wgsl`; McCool 2000):
//! a compute pass finds the discontinuities of the light's distance map and writes a wall quad
//! for each piece of the reconstructed silhouette (CPU twin: `geometry::hybrid`), with the
//! indirect draw arguments; then, over the screen prepass of [`super::stencil_volumes`], the
//! walls in front of each pixel's surface invert one stencil bit (z-pass), and a resolve turns
//! the bit and the near plane's own shadow state (its point looked up in the map) into V.
//!
//! McCool read the depth map back and reconstructed on the CPU; here the GPU does it, so nothing
//! waits, and the walls are read back only for the lab's overlay, a frame or more later
//! ([`Hybrid::poll_walls`]).

use std::sync::Arc;

use glam::{Mat4, Vec3, Vec4};

use super::stencil_volumes::{
    depth_stencil, stencil_both, volume_vertex_layout, ScreenTargets, VISIBILITY_FORMAT,
};
use crate::geometry::hybrid::WallParams;
use crate::render::readback::{map_now, LateCopy};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, compute_pipeline, pipeline_layout, shader_module, texture_entry, uniform_buffer,
    uniform_entry, view_entry, GpuContext, RenderError,
};

/// At most this many cells of the map are looked at closely (as the WGSL's MAX_CANDIDATES);
/// maps up to 65536² (cells are packed in 16 + 16 bits).
pub const MAX_CANDIDATES: u32 = 1 << 18;

/// At most this many wall quads (96 bytes each); more are dropped and counted.
pub const MAX_HYBRID_WALLS: u32 = 1 << 16;
const WALL_BYTES: u64 = 6 * 16;

/// `HybridUniforms` of `shaders/passes/hybrid.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct HybridUniforms {
    pub inv_light_view_proj: [[f32; 4]; 4],
    pub light_view_proj: [[f32; 4]; 4],
    pub infinite_view_proj: [[f32; 4]; 4],
    pub inv_infinite_view_proj: [[f32; 4]; 4],
    /// xyz: the light point; w: the bottom of a wall where nothing was seen.
    pub light: [f32; 4],
    /// Map size, τ, templates (1/0), the walls' top bias.
    pub params: [f32; 4],
    /// The walls' bottom margin, the most walls, the near cap's lookup bias, the slope test
    /// (1/0).
    pub limits: [f32; 4],
    /// The camera image's width and height, the map copy's row stride in floats.
    pub screen: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<HybridUniforms>() == 320);

/// What a frame's hybrid passes are made from.
pub struct HybridFrame {
    pub light_view_proj: Mat4,
    pub infinite_view_proj: Mat4,
    pub light: Vec3,
    pub map_size: u32,
    pub walls: WallParams,
    pub top_bias: f32,
    pub bottom_margin: f32,
    pub lookup_bias: f32,
    pub width: u32,
    pub height: u32,
}

impl HybridUniforms {
    pub fn new(f: &HybridFrame) -> HybridUniforms {
        HybridUniforms {
            inv_light_view_proj: f.light_view_proj.inverse().to_cols_array_2d(),
            light_view_proj: f.light_view_proj.to_cols_array_2d(),
            infinite_view_proj: f.infinite_view_proj.to_cols_array_2d(),
            inv_infinite_view_proj: f.infinite_view_proj.inverse().to_cols_array_2d(),
            light: f.light.extend(f.walls.far).to_array(),
            params: [
                f.map_size as f32,
                f.walls.threshold,
                if f.walls.templates { 1.0 } else { 0.0 },
                f.top_bias,
            ],
            limits: [
                f.bottom_margin,
                MAX_HYBRID_WALLS as f32,
                f.lookup_bias,
                if f.walls.slope_test { 1.0 } else { 0.0 },
            ],
            screen: [
                f.width as f32,
                f.height as f32,
                (padded_row(f.map_size) / 4) as f32,
                0.0,
            ],
        }
    }
}

/// The pipelines, built once per device (for one depth-stencil format).
pub struct HybridPass {
    inputs_layout: wgpu::BindGroupLayout,
    walls_layout: wgpu::BindGroupLayout,
    dispatch_layout: wgpu::BindGroupLayout,
    find: wgpu::ComputePipeline,
    dispatch: wgpu::ComputePipeline,
    extract: wgpu::ComputePipeline,
    finish: wgpu::ComputePipeline,
    wall: wgpu::RenderPipeline,
    even: wgpu::RenderPipeline,
    odd: wgpu::RenderPipeline,
}

impl HybridPass {
    pub fn get(ctx: &GpuContext, format: wgpu::TextureFormat) -> Arc<HybridPass> {
        let name = if format == wgpu::TextureFormat::Depth32FloatStencil8 {
            "d32s8"
        } else {
            "d24s8"
        };
        ctx.shared_named(name, |device| {
            use wgpu::ShaderStages as S;
            let module = shader_module(device, "passes/hybrid.wgsl");
            let inputs_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("HybridPass::inputs"),
                entries: &[
                    uniform_entry(0, S::VERTEX_FRAGMENT | S::COMPUTE),
                    texture_entry(1, S::FRAGMENT | S::COMPUTE, wgpu::TextureViewDimension::D2),
                ],
            });
            let storage = |binding| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: S::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: false },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            };
            let mut map_copy = storage(3);
            map_copy.ty = wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            };
            let walls_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("HybridPass::walls"),
                entries: &[
                    storage(0),
                    storage(1),
                    storage(2),
                    map_copy,
                    storage(4),
                    storage(5),
                ],
            });
            // cs_dispatch alone writes the indirect arguments of cs_extract: in a group of its
            // own, so no dispatch that reads them indirectly has them bound as storage.
            let dispatch_layout =
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("HybridPass::dispatch"),
                    entries: &[storage(5), storage(6)],
                });
            let compute_layout = pipeline_layout(
                device,
                "HybridPass::compute_layout",
                &[&inputs_layout, &walls_layout],
            );
            let dispatch_pipeline_layout = pipeline_layout(
                device,
                "HybridPass::dispatch_layout",
                &[&inputs_layout, &dispatch_layout],
            );
            let compute = |label: &str, entry: &str, layout: &wgpu::PipelineLayout| {
                compute_pipeline(device, label, layout, &module, entry)
            };
            let render_layout =
                pipeline_layout(device, "HybridPass::render_layout", &[&inputs_layout]);
            let render = |label: &str,
                          vs: &str,
                          fs: Option<&str>,
                          buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                          stencil: wgpu::StencilState,
                          depth: wgpu::CompareFunction| {
                let targets = [Some(wgpu::ColorTargetState {
                    format: VISIBILITY_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })];
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&render_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(vs),
                        compilation_options: Default::default(),
                        buffers,
                    },
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: depth_stencil(format, false, depth, stencil),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: fs.map(|fs| wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fs),
                        compilation_options: Default::default(),
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
            // One bit, z-pass: every wall fragment in front of the surface flips it.
            let flip = wgpu::StencilState {
                write_mask: 0x01,
                ..stencil_both(
                    wgpu::StencilFaceState {
                        compare: wgpu::CompareFunction::Always,
                        fail_op: wgpu::StencilOperation::Keep,
                        depth_fail_op: wgpu::StencilOperation::Keep,
                        pass_op: wgpu::StencilOperation::Invert,
                    },
                    0x01,
                )
            };
            let wall = render(
                "HybridPass::walls",
                "vs_wall",
                None,
                &[Some(volume_vertex_layout())],
                flip,
                // Reversed depth: in front of the surface is greater.
                wgpu::CompareFunction::Greater,
            );
            let bit = wgpu::StencilState {
                read_mask: 0x01,
                ..stencil_both(
                    wgpu::StencilFaceState {
                        compare: wgpu::CompareFunction::Equal,
                        fail_op: wgpu::StencilOperation::Keep,
                        depth_fail_op: wgpu::StencilOperation::Keep,
                        pass_op: wgpu::StencilOperation::Keep,
                    },
                    0,
                )
            };
            let even = render(
                "HybridPass::even",
                "vs_main",
                Some("fs_even"),
                &[],
                bit.clone(),
                wgpu::CompareFunction::Always,
            );
            let odd = render(
                "HybridPass::odd",
                "vs_main",
                Some("fs_odd"),
                &[],
                bit,
                wgpu::CompareFunction::Always,
            );
            HybridPass {
                inputs_layout,
                walls_layout,
                find: compute("HybridPass::find", "cs_find", &compute_layout),
                dispatch: compute(
                    "HybridPass::dispatch",
                    "cs_dispatch",
                    &dispatch_pipeline_layout,
                ),
                extract: compute("HybridPass::extract", "cs_extract", &compute_layout),
                finish: compute("HybridPass::finish", "cs_finish", &compute_layout),
                dispatch_layout,
                wall,
                even,
                odd,
            }
        })
    }
}

/// A method state's hybrid passes: uniforms, the walls, their draw arguments.
pub struct Hybrid {
    pass: Arc<HybridPass>,
    uniforms: wgpu::Buffer,
    walls: wgpu::Buffer,
    count: wgpu::Buffer,
    args: wgpu::Buffer,
    candidates: wgpu::Buffer,
    candidate_count: wgpu::Buffer,
    extract_args: wgpu::Buffer,
    dispatch_group: wgpu::BindGroup,
    /// Group 1 over the walls and the map's copy, and the map size the copy holds.
    walls_group: Option<(wgpu::BindGroup, u32)>,
    /// The distance map copied into a buffer (rows padded to wgpu's copy alignment): lavapipe
    /// reads a storage buffer in a compute shader far faster than a texture.
    map_copy: Option<wgpu::Buffer>,
    /// Group 0 and the generation of the map it binds.
    inputs_group: Option<(wgpu::BindGroup, u64)>,
    /// The walls copied back for the overlay, and the revision they were made for.
    copy: LateCopy,
    copy_revision: u64,
}

impl Hybrid {
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat) -> Hybrid {
        use wgpu::BufferUsages as B;
        let device = &ctx.device;
        let pass = HybridPass::get(ctx, format);
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let walls = buffer(
            "Hybrid::walls",
            u64::from(MAX_HYBRID_WALLS) * WALL_BYTES,
            B::STORAGE | B::VERTEX | B::COPY_SRC,
        );
        let count = buffer("Hybrid::count", 4, B::STORAGE | B::COPY_DST | B::COPY_SRC);
        let args = buffer("Hybrid::args", 16, B::STORAGE | B::INDIRECT);
        let candidates = buffer(
            "Hybrid::candidates",
            4 * u64::from(MAX_CANDIDATES),
            B::STORAGE,
        );
        let candidate_count = buffer("Hybrid::candidate_count", 4, B::STORAGE | B::COPY_DST);
        let extract_args = buffer("Hybrid::extract_args", 12, B::STORAGE | B::INDIRECT);
        let dispatch_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Hybrid::dispatch_group"),
            layout: &pass.dispatch_layout,
            entries: &[
                buffer_entry(5, &candidate_count),
                buffer_entry(6, &extract_args),
            ],
        });
        Hybrid {
            copy: LateCopy::new(
                &ctx.device,
                "Hybrid::copy",
                16 + u64::from(MAX_HYBRID_WALLS) * WALL_BYTES,
            ),
            copy_revision: 0,
            pass,
            uniforms: uniform_buffer::<HybridUniforms>(device, "Hybrid::uniforms"),
            walls,
            count,
            args,
            candidates,
            candidate_count,
            extract_args,
            dispatch_group,
            walls_group: None,
            map_copy: None,
            inputs_group: None,
        }
    }

    /// This frame's uniforms, and group 0 over `map` (its generation `generation`).
    pub fn begin(
        &mut self,
        ctx: &GpuContext,
        uniforms: &HybridUniforms,
        map: &wgpu::TextureView,
        generation: u64,
    ) {
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
        if self
            .inputs_group
            .as_ref()
            .is_none_or(|(_, g)| *g != generation)
        {
            let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("Hybrid::inputs_group"),
                layout: &self.pass.inputs_layout,
                entries: &[buffer_entry(0, &self.uniforms), view_entry(1, map)],
            });
            self.inputs_group = Some((group, generation));
        }
    }

    /// Reconstruct the walls from the map (`map_size`²) bound by [`Hybrid::begin`]; copy them
    /// for the overlay when no copy is in flight (`revision` names them).
    pub fn record_extract(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        map: &wgpu::Texture,
        revision: u64,
    ) {
        let map_size = map.width();
        let row = padded_row(map_size);
        if self
            .walls_group
            .as_ref()
            .is_none_or(|(_, size)| *size != map_size)
        {
            let copy = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("Hybrid::map_copy"),
                size: row * u64::from(map_size.max(1)),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("Hybrid::walls_group"),
                layout: &self.pass.walls_layout,
                entries: &[
                    buffer_entry(0, &self.walls),
                    buffer_entry(1, &self.count),
                    buffer_entry(2, &self.args),
                    buffer_entry(3, &copy),
                    buffer_entry(4, &self.candidates),
                    buffer_entry(5, &self.candidate_count),
                ],
            });
            self.map_copy = Some(copy);
            self.walls_group = Some((group, map_size));
        }
        let (Some((group, _)), Some((walls_group, _)), Some(copy)) =
            (&self.inputs_group, &self.walls_group, &self.map_copy)
        else {
            return;
        };
        // The copy of the map the extraction reads belongs to its debug group.
        let span = rec.span("hybrid_extract");
        rec.encoder.copy_texture_to_buffer(
            map.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: copy,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row as u32),
                    rows_per_image: Some(map_size),
                },
            },
            map.size(),
        );
        ctx.queue.write_buffer(&self.count, 0, &0u32.to_le_bytes());
        ctx.queue
            .write_buffer(&self.candidate_count, 0, &0u32.to_le_bytes());
        {
            let mut pass = rec
                .encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("Hybrid::extract"),
                    timestamp_writes: span.compute_writes(rec.timer),
                });
            pass.set_bind_group(0, group, &[]);
            pass.set_bind_group(1, walls_group, &[]);
            let groups = map_size.saturating_sub(1).div_ceil(8);
            pass.set_pipeline(&self.pass.find);
            pass.dispatch_workgroups(groups, groups, 1);
            pass.set_pipeline(&self.pass.dispatch);
            pass.set_bind_group(1, &self.dispatch_group, &[]);
            pass.dispatch_workgroups(1, 1, 1);
            pass.set_bind_group(1, walls_group, &[]);
            pass.set_pipeline(&self.pass.extract);
            pass.dispatch_workgroups_indirect(&self.extract_args, 0);
            pass.set_pipeline(&self.pass.finish);
            pass.dispatch_workgroups(1, 1, 1);
        }
        if self.copy.free() {
            rec.encoder
                .copy_buffer_to_buffer(&self.count, 0, &self.copy.buffer, 0, 4);
            rec.encoder.copy_buffer_to_buffer(
                &self.walls,
                0,
                &self.copy.buffer,
                16,
                u64::from(MAX_HYBRID_WALLS) * WALL_BYTES,
            );
            self.copy.copied();
            self.copy_revision = revision;
        }
    }

    /// The walls in front of each pixel's surface flip one stencil bit of `targets` (holding
    /// this frame's prepass).
    pub fn record_walls(&self, rec: &mut Recorder<'_>, targets: &ScreenTargets) {
        let Some((group, _)) = &self.inputs_group else {
            return;
        };
        let span = rec.span("hybrid_walls");
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("Hybrid::walls"),
            color_attachments: &[],
            depth_stencil_attachment: targets.read_only_depth_stencil(),
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pass.wall);
        pass.set_bind_group(0, group, &[]);
        pass.set_vertex_buffer(0, self.walls.slice(..));
        pass.draw_indirect(&self.args, 0);
    }

    /// Draw the walls of the last extraction (vertex slot 0, indirect): for a pass of one's own
    /// (the fill measure).
    pub fn draw_walls(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_vertex_buffer(0, self.walls.slice(..));
        pass.draw_indirect(&self.args, 0);
    }

    /// V into `targets.visibility` from the bit and the near plane's shadow state.
    pub fn record_resolve(&self, rec: &mut Recorder<'_>, targets: &ScreenTargets) {
        let Some((group, _)) = &self.inputs_group else {
            return;
        };
        let span = rec.span("hybrid_resolve");
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("Hybrid::resolve"),
            color_attachments: &[crate::render::cleared(
                &targets.visibility.view,
                crate::render::red(1.0),
            )],
            depth_stencil_attachment: targets.read_only_depth_stencil(),
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, group, &[]);
        for (pipeline, bit) in [(&self.pass.even, 0), (&self.pass.odd, 1)] {
            pass.set_pipeline(pipeline);
            pass.set_stencil_reference(bit);
            pass.draw(0..3, 0..1);
        }
    }

    /// The walls of the last extraction copied back, once the GPU has them: `(revision, walls,
    /// how many were found)`, each wall its six vertices. Never waits: call once per frame (the
    /// first call after an extraction asks for the copy, a later one returns it).
    pub fn poll_walls(&mut self) -> Option<(u64, Vec<[Vec4; 6]>, u32)> {
        let bytes = self.copy.poll()?;
        let (walls, found) = decode_walls(&bytes);
        Some((self.copy_revision, walls, found))
    }

    /// Whether walls are being copied back (a later [`Hybrid::poll_walls`] returns them).
    pub fn walls_pending(&self) -> bool {
        self.copy.pending()
    }

    /// [`Hybrid::poll_walls`], waiting for the GPU (tests): everything submitted so far must
    /// include an extraction.
    pub fn read_walls(&mut self, ctx: &GpuContext) -> Result<(Vec<[Vec4; 6]>, u32), RenderError> {
        for _ in 0..3 {
            map_now(&ctx.device)?;
            if let Some((_, walls, found)) = self.poll_walls() {
                return Ok((walls, found));
            }
        }
        Err(RenderError::Readback("no walls were extracted".into()))
    }
}

/// Bytes per row of the map's copy: R32Float rows padded to wgpu's copy alignment.
fn padded_row(size: u32) -> u64 {
    let align = u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    (u64::from(size) * 4).div_ceil(align) * align
}

/// The copy's layout: the count (u32, padded to 16 bytes), then the walls.
fn decode_walls(bytes: &[u8]) -> (Vec<[Vec4; 6]>, u32) {
    let found = bytes
        .get(..4)
        .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let n = found.min(MAX_HYBRID_WALLS) as usize;
    let floats =
        crate::render::readback::f32s(bytes.get(16..16 + n * WALL_BYTES as usize).unwrap_or(&[]));
    let walls = floats
        .chunks_exact(24)
        .map(|w| std::array::from_fn(|k| Vec4::from_slice(&w[4 * k..4 * k + 4])))
        .collect();
    (walls, found)
}
