//! The moment map's summed-area table (`shaders/passes/moment_sat.wgsl`), for `msm` and
//! `msm-soft`: each texel of the centre's shadow map as four quantization-optimized power
//! moments of its normalized depth (Peters & Klein 2015) in fixed point, summed along rows then
//! columns by compute dispatches (after one that finds the map's nearest and farthest surface, the range the depths are normalized over) into one storage buffer of `vec4<u32>`. A filter of any
//! size is then four reads; the `u32` sums wrap and stay exact for boxes up to
//! [`moments::MAX_RADIUS`] (the arithmetic and its tests: `geometry::moments`).

use crate::geometry::moments;
use crate::render::storage_entry;
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, compute_pipeline, pipeline_layout, shader_module, texture_entry, uniform_entry,
    view_entry, GpuContext,
};

use super::next_generation;
use super::shadow_map::MapFrame;

/// `SatUniforms` of `shaders/passes/moment_sat.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SatUniforms {
    pub inv_light_view_proj: [[f32; 4]; 4],
    pub light_center: [f32; 4],
    pub light_normal: [f32; 4],
    pub size: u32,
    pub scale: f32,
    pub _pad0: f32,
    pub _pad1: f32,
}

/// The range buffer's reset: no surface seen yet (`f32::MAX`, 0 as bits).
const RANGE_RESET: [u32; 2] = [0x7f7f_ffff, 0];

struct SatPipelines {
    layout: wgpu::BindGroupLayout,
    range: wgpu::ComputePipeline,
    rows: wgpu::ComputePipeline,
    columns: wgpu::ComputePipeline,
}

/// The table, and a number that changes whenever it is made again.
pub struct MomentTable {
    pub size: u32,
    pub buffer: wgpu::Buffer,
    /// The nearest and farthest surface's distance the depths are normalized between (two
    /// `u32`s, the floats' bits).
    pub range: wgpu::Buffer,
    pub generation: u64,
}

pub struct MomentSat {
    uniforms: wgpu::Buffer,
    table: Option<MomentTable>,
}

impl MomentSat {
    pub fn new(ctx: &GpuContext) -> MomentSat {
        MomentSat {
            uniforms: crate::render::uniform_buffer::<SatUniforms>(&ctx.device, "MomentSat"),
            table: None,
        }
    }

    pub fn table(&self) -> Option<&MomentTable> {
        self.table.as_ref()
    }

    /// Make the table of `distance` (the centre's `size`² distance map, seen as `frame` says).
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        distance: &wgpu::TextureView,
        size: u32,
        frame: &MapFrame,
    ) {
        let pipes = ctx.shared(|device| {
            use wgpu::ShaderStages as S;
            let module = shader_module(device, "passes/moment_sat.wgsl");
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("MomentSat::layout"),
                entries: &[
                    uniform_entry(0, S::COMPUTE),
                    texture_entry(1, S::COMPUTE, wgpu::TextureViewDimension::D2),
                    storage_entry(2, S::COMPUTE, false),
                    storage_entry(3, S::COMPUTE, false),
                ],
            });
            let pl = pipeline_layout(device, "MomentSat", &[&layout]);
            let compute = |entry: &str| compute_pipeline(device, entry, &pl, &module, entry);
            SatPipelines {
                range: compute("cs_range"),
                rows: compute("cs_rows"),
                columns: compute("cs_columns"),
                layout,
            }
        });
        if self.table.as_ref().is_none_or(|t| t.size != size) {
            self.table = Some(MomentTable {
                size,
                buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("MomentSat::table"),
                    size: size as u64 * size as u64 * 16,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                }),
                range: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("MomentSat::range"),
                    size: 8,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                generation: 0,
            });
        }
        let Some(t) = &mut self.table else { return };
        t.generation = next_generation();
        let u = SatUniforms {
            inv_light_view_proj: frame.inv_light_view_proj.to_cols_array_2d(),
            light_center: frame.center.extend(0.0).to_array(),
            light_normal: frame.normal.extend(0.0).to_array(),
            size,
            scale: moments::SAT_SCALE,
            _pad0: 0.0,
            _pad1: 0.0,
        };
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        ctx.queue
            .write_buffer(&t.range, 0, bytemuck::cast_slice(&RANGE_RESET));
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("MomentSat::group"),
            layout: &pipes.layout,
            entries: &[
                buffer_entry(0, &self.uniforms),
                view_entry(1, distance),
                buffer_entry(2, &t.buffer),
                buffer_entry(3, &t.range),
            ],
        });
        let span = rec.span("msm_table");
        let mut pass = rec
            .encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("MomentSat"),
                timestamp_writes: span.compute_writes(rec.timer),
            });
        pass.set_bind_group(0, &group, &[]);
        for pipeline in [&pipes.range, &pipes.rows, &pipes.columns] {
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(size.div_ceil(64), 1, 1);
        }
    }
}
