//! Shadow rays on the GPU, by one of two paths ([`Path`]) with one result:
//!
//! - [`Path::RayQuery`]: hardware ray queries (`shaders/passes/trace_rq.wgsl`) through an
//!   acceleration structure the driver builds from the scene's triangles
//!   ([`super::trace_rq::Accel`]), where the device has them (`Features::EXPERIMENTAL_RAY_QUERY`);
//! - [`Path::WgslBvh`]: the scene's BVH, built on the CPU ([`crate::geometry::bvh::Bvh`]) and
//!   flattened ([`FlatBvh`]) into one storage buffer, traversed in WGSL by a port of the CPU's
//!   tolerant any-hit query (`shaders/passes/trace.wgsl`, `shaders/shared/bvh_trace.wgsl`),
//!   on any device with compute shaders.
//!
//! [`Path::auto`] takes ray queries where the device has them; a caller may name either
//! ([`TraceScene::new`]), so a test can run both on one device. Both answer the same questions on
//! the same rays: [`ReferenceRays`] counts, per pixel, the light samples its point sees, a batch
//! of samples per dispatch (the reference on the GPU); [`any_hit`] answers single rays (the
//! tests that hold the GPU's tracing to the CPU's). The ray-query path cannot count the boxes and
//! triangles the driver tests: its [`RayCounts`] leave them at 0.
//!
//! The tracer needs compute shaders and [`STORAGE_BUFFERS`] storage buffers in the compute
//! stage; its callers check that before any work (`render::gpu_reference::NEEDS`).

use std::ops::Range;
use std::sync::{Arc, Mutex};

use glam::Vec3;

use super::trace_rq::Accel;
use crate::geometry::bvh::{Bvh, FlatBvh};
use crate::render::adapter::Capabilities;
use crate::render::readback::{copy_to_staging, read_u32s};
use crate::render::{
    compute_pipeline, pipeline_layout, shader_module, storage_buffer, storage_entry, uniform_entry,
    GpuContext, RenderError,
};

/// How the shadow rays are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Path {
    /// Hardware ray queries through the driver's acceleration structure.
    RayQuery,
    /// The CPU's BVH traversed in a WGSL compute shader.
    WgslBvh,
}

/// `DBUFFER_TRACE_PATH=wgsl|rayquery`: the path [`Path::auto`] takes instead of the best one
/// (to time both on one device; `rayquery` where the device has none is an error).
pub const PATH_ENV: &str = "DBUFFER_TRACE_PATH";

impl Path {
    /// Both paths, the preferred first.
    pub const ALL: [Path; 2] = [Path::RayQuery, Path::WgslBvh];

    /// The best path on a device with `caps`: ray queries where it has them.
    pub fn best(caps: &Capabilities) -> Path {
        if Path::RayQuery.runs_on(caps) {
            Path::RayQuery
        } else {
            Path::WgslBvh
        }
    }

    /// The path on `ctx`'s device: [`PATH_ENV`] where set, else [`Path::best`].
    pub fn auto(ctx: &GpuContext) -> Result<Path, RenderError> {
        match std::env::var(PATH_ENV) {
            Ok(v) => {
                let path = Path::parse(&v).ok_or_else(|| {
                    RenderError::Request(format!("{PATH_ENV}={v}: expected 'rayquery' or 'wgsl'"))
                })?;
                if !path.runs_on(&ctx.caps) {
                    return Err(RenderError::Request(format!(
                        "{PATH_ENV}={v}: {} has no hardware ray queries",
                        ctx.adapter_description()
                    )));
                }
                Ok(path)
            }
            Err(_) => Ok(Path::best(&ctx.caps)),
        }
    }

    /// `rayquery` or `wgsl` (as [`PATH_ENV`] takes them).
    pub fn parse(text: &str) -> Option<Path> {
        match text.trim().to_ascii_lowercase().as_str() {
            "rayquery" | "ray-query" | "rq" => Some(Path::RayQuery),
            "wgsl" | "bvh" | "wgsl-bvh" => Some(Path::WgslBvh),
            _ => None,
        }
    }

    /// Whether a device with `caps` can trace this way (the BVH path's own needs, compute and
    /// storage buffers, are `gpu_reference::NEEDS`).
    pub fn runs_on(self, caps: &Capabilities) -> bool {
        match self {
            Path::RayQuery => {
                caps.ray_queries() && caps.limits.max_acceleration_structures_per_shader_stage >= 1
            }
            Path::WgslBvh => true,
        }
    }

    /// "hardware ray queries", "the BVH traversed in WGSL".
    pub fn describe(self) -> &'static str {
        match self {
            Path::RayQuery => "hardware ray queries",
            Path::WgslBvh => "the BVH traversed in WGSL",
        }
    }

    /// The name [`PATH_ENV`] takes.
    pub fn name(self) -> &'static str {
        match self {
            Path::RayQuery => "rayquery",
            Path::WgslBvh => "wgsl",
        }
    }
}

impl std::fmt::Display for Path {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.describe())
    }
}

/// `TraceUniforms` of `shaders/passes/trace.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TraceUniforms {
    /// Pixels (or rays) to answer.
    pub count: u32,
    /// The batch of samples: `first .. first + samples`.
    pub first: u32,
    pub samples: u32,
    /// Invocations per row of the dispatch.
    pub row: u32,
    pub node_count: u32,
    pub triangle_count: u32,
    /// The first pixel of a reference dispatch: it answers pixels `offset .. count`.
    pub offset: u32,
    pub _pad1: u32,
}

/// Storage buffers the tracer binds in the compute stage: the BVH, the items (points or rays),
/// the light's samples and the results.
pub const STORAGE_BUFFERS: u32 = 4;

/// Invocations per workgroup (`@workgroup_size` of both entry points).
const WORKGROUP: u32 = 64;

/// The scene on the GPU, as one [`Path`] traces it: the flattened BVH (nodes, then triangles)
/// in one storage buffer, or the driver's acceleration structure of its triangles.
pub struct TraceScene {
    shape: Shape,
    node_count: u32,
    triangle_count: u32,
}

enum Shape {
    Bvh(wgpu::Buffer),
    Accel(Accel),
}

impl TraceScene {
    /// `bvh`'s triangles on the GPU for `path`: its flattened nodes and triangles
    /// ([`Path::WgslBvh`]), or an acceleration structure of the same triangles
    /// ([`Path::RayQuery`]). An error (before anything is made) when the device cannot hold them
    /// or has no ray queries for [`Path::RayQuery`].
    pub fn new(ctx: &GpuContext, bvh: &Bvh, path: Path) -> Result<TraceScene, RenderError> {
        match path {
            Path::WgslBvh => TraceScene::from_flat(ctx, &bvh.flatten()),
            Path::RayQuery => Ok(TraceScene {
                shape: Shape::Accel(Accel::new(ctx, bvh.triangles())?),
                node_count: 0,
                triangle_count: count(bvh.len(), "triangles")?,
            }),
        }
    }

    /// The flattened BVH `flat` for [`Path::WgslBvh`]; an error (before anything is made) when
    /// it is larger than one storage binding of the device.
    pub fn from_flat(ctx: &GpuContext, flat: &FlatBvh) -> Result<TraceScene, RenderError> {
        let mut words: Vec<[f32; 4]> = Vec::with_capacity(flat.nodes.len() + flat.triangles.len());
        words.extend_from_slice(&flat.nodes);
        words.extend_from_slice(&flat.triangles);
        if words.is_empty() {
            // A binding is never empty; with no triangles the traversal reads nothing.
            words.push([0.0; 4]);
        }
        fits(ctx, "the scene's BVH", words.len() as u64 * 16)?;
        Ok(TraceScene {
            shape: Shape::Bvh(storage_buffer(&ctx.device, "TraceScene::bvh", &words)),
            node_count: count(flat.node_count(), "nodes")?,
            triangle_count: count(flat.triangle_count(), "triangles")?,
        })
    }

    /// How this scene is traced.
    pub fn path(&self) -> Path {
        match self.shape {
            Shape::Bvh(_) => Path::WgslBvh,
            Shape::Accel(_) => Path::RayQuery,
        }
    }

    /// The BVH's nodes ([`Path::WgslBvh`]; 0 for [`Path::RayQuery`]).
    pub fn node_count(&self) -> u32 {
        self.node_count
    }

    pub fn triangle_count(&self) -> u32 {
        self.triangle_count
    }

    /// What a shader binds to trace it: the BVH's buffer (`bvh` of
    /// `shaders/shared/bvh_trace.wgsl`) or the TLAS.
    pub fn resource(&self) -> wgpu::BindingResource<'_> {
        match &self.shape {
            Shape::Bvh(buffer) => buffer.as_entire_binding(),
            Shape::Accel(accel) => wgpu::BindingResource::AccelerationStructure(&accel.tlas),
        }
    }
}

/// `n` as a `u32` count of `what`, or an error.
fn count(n: usize, what: &str) -> Result<u32, RenderError> {
    u32::try_from(n)
        .map_err(|_| RenderError::Request(format!("the scene has {n} {what}: too many")))
}

/// The most points one [`ReferenceRays`] takes on `ctx`'s device: as many as its largest
/// storage binding holds (16 bytes a point); a larger image is traced in pieces.
pub fn max_points(ctx: &GpuContext) -> usize {
    let limits = ctx.device.limits();
    let max = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    usize::try_from(max / 16).unwrap_or(usize::MAX).max(1)
}

/// An error when a storage binding of `bytes` is larger than the device takes.
pub fn fits(ctx: &GpuContext, what: &str, bytes: u64) -> Result<(), RenderError> {
    let limits = ctx.device.limits();
    let max = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    if bytes > max {
        return Err(RenderError::Request(format!(
            "{what} needs {bytes} bytes in one storage buffer; this adapter ({}) binds at most {max}",
            ctx.adapter_description()
        )));
    }
    Ok(())
}

struct TracePipelines {
    layout: wgpu::BindGroupLayout,
    reference: wgpu::ComputePipeline,
    any_hit: wgpu::ComputePipeline,
}

impl TracePipelines {
    /// The bind group of one trace: the uniforms, the scene, the items (points or rays), the
    /// light's samples and the results, bindings 0 to 4 as both trace shaders declare them.
    fn group(
        &self,
        ctx: &GpuContext,
        label: &str,
        scene: &TraceScene,
        [uniforms, items, light, results]: [&wgpu::Buffer; 4],
    ) -> wgpu::BindGroup {
        let entry = |binding, resource| wgpu::BindGroupEntry { binding, resource };
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &self.layout,
            entries: &[
                entry(0, uniforms.as_entire_binding()),
                entry(1, scene.resource()),
                entry(2, items.as_entire_binding()),
                entry(3, light.as_entire_binding()),
                entry(4, results.as_entire_binding()),
            ],
        })
    }
}

/// The pipelines of `path` on `ctx`'s device, made once.
fn pipelines(ctx: &GpuContext, path: Path) -> std::sync::Arc<TracePipelines> {
    ctx.shared_named(path.name(), |device| {
        use wgpu::ShaderStages as S;
        let (shader, scene) = match path {
            Path::WgslBvh => ("passes/trace.wgsl", storage_entry(1, S::COMPUTE, true)),
            Path::RayQuery => (
                "passes/trace_rq.wgsl",
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: S::COMPUTE,
                    ty: wgpu::BindingType::AccelerationStructure {
                        vertex_return: false,
                    },
                    count: None,
                },
            ),
        };
        let module = shader_module(device, shader);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("Trace::layout"),
            entries: &[
                uniform_entry(0, S::COMPUTE),
                scene,
                storage_entry(2, S::COMPUTE, true),
                storage_entry(3, S::COMPUTE, true),
                storage_entry(4, S::COMPUTE, false),
            ],
        });
        let pl = pipeline_layout(device, "Trace", &[&layout]);
        let compute = |entry: &str| compute_pipeline(device, entry, &pl, &module, entry);
        TracePipelines {
            reference: compute("cs_reference"),
            any_hit: compute("cs_any_hit"),
            layout,
        }
    })
}

/// The workgroups of a dispatch over `count` items, as (x, y) within the device's limit per
/// dimension, and the invocations per row (`TraceUniforms::row`).
fn grid(ctx: &GpuContext, count: u32) -> (u32, u32, u32) {
    let groups = count.div_ceil(WORKGROUP).max(1);
    let max = ctx
        .device
        .limits()
        .max_compute_workgroups_per_dimension
        .max(1);
    let x = groups.min(max);
    (x, groups.div_ceil(x), x * WORKGROUP)
}

/// A buffer the shader writes and the CPU reads back (after a copy into a mappable one).
fn results_buffer(ctx: &GpuContext, label: &str, words: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (words * 4).max(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Records one dispatch of `pipeline` over `count` items and submits it.
fn dispatch(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    grid: (u32, u32),
) {
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("Trace"),
        });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("Trace"),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(grid.0, grid.1, 1);
    }
    ctx.queue.submit([encoder.finish()]);
}

/// Per pixel, how many of the light's samples its point sees, accumulated over batches of
/// samples: the ray-cast reference traced on the GPU.
pub struct ReferenceRays {
    path: Path,
    node_count: u32,
    triangle_count: u32,
    uniforms: wgpu::Buffer,
    results: wgpu::Buffer,
    group: wgpu::BindGroup,
    pixels: u32,
    total: u32,
    done: u32,
}

/// What the tracer counted for one item: a pixel of [`ReferenceRays`], a ray of [`any_hit`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// A pixel's samples seen (not blocked) so far; a ray's 1 where it is blocked, else 0.
    pub count: u32,
    /// Boxes tested by its rays so far ([`Path::WgslBvh`]; 0 on [`Path::RayQuery`], where the
    /// driver does not say).
    pub box_tests: u32,
    /// Triangles tested by its rays so far ([`Path::WgslBvh`]; 0 on [`Path::RayQuery`]).
    pub triangle_tests: u32,
}

impl ReferenceRays {
    /// Rays from each of `points` (`None`: no rays, V = 0) to each of `samples` (taken in this
    /// order), against `scene`, by its path; nothing is traced yet.
    pub fn new(
        ctx: &GpuContext,
        scene: &TraceScene,
        points: &[Option<Vec3>],
        samples: &[Vec3],
    ) -> Result<ReferenceRays, RenderError> {
        let too_many = |what: &str, n: usize| {
            RenderError::Request(format!("the GPU reference takes {n} {what}: too many"))
        };
        let pixels = u32::try_from(points.len()).map_err(|_| too_many("pixels", points.len()))?;
        let total = u32::try_from(samples.len()).map_err(|_| too_many("samples", samples.len()))?;
        fits(ctx, "the reference's points", points.len() as u64 * 16)?;
        fits(ctx, "the reference's counts", points.len() as u64 * 12)?;
        fits(ctx, "the light's samples", samples.len() as u64 * 16)?;
        let mut items: Vec<[f32; 4]> = points
            .iter()
            .map(|p| p.map_or([0.0; 4], |x| x.extend(1.0).to_array()))
            .collect();
        if items.is_empty() {
            items.push([0.0; 4]);
        }
        let mut light: Vec<[f32; 4]> = samples.iter().map(|s| s.extend(0.0).to_array()).collect();
        if light.is_empty() {
            light.push([0.0; 4]);
        }
        let items = storage_buffer(&ctx.device, "ReferenceRays::points", &items);
        let light = storage_buffer(&ctx.device, "ReferenceRays::samples", &light);
        let results = results_buffer(ctx, "ReferenceRays::results", u64::from(pixels) * 3);
        let uniforms = crate::render::uniform_buffer::<TraceUniforms>(&ctx.device, "Trace");
        let pipes = pipelines(ctx, scene.path());
        let group = pipes.group(
            ctx,
            "ReferenceRays::group",
            scene,
            [&uniforms, &items, &light, &results],
        );
        Ok(ReferenceRays {
            path: scene.path(),
            node_count: scene.node_count,
            triangle_count: scene.triangle_count,
            uniforms,
            results,
            group,
            pixels,
            total: if samples.is_empty() { 0 } else { total },
            done: 0,
        })
    }

    /// Trace up to `n` more samples per pixel (one dispatch, submitted, not waited for);
    /// returns how many.
    pub fn step(&mut self, ctx: &GpuContext, n: u32) -> u32 {
        let take = n.min(self.total - self.done);
        if take == 0 {
            return 0;
        }
        self.trace(ctx, self.done..self.done + take, 0..self.pixels);
        self.done += take;
        take
    }

    /// Trace the samples `samples` (positions in the order given to [`ReferenceRays::new`])
    /// from the pixels `pixels` alone: one dispatch, submitted, not waited for, its counts added
    /// to theirs. [`ReferenceRays::step`] is this over every pixel; the lab traces a batch in
    /// slices of pixels where one dispatch over all of them would run long (on a CPU's Vulkan the
    /// submit itself runs the dispatch). Leaves [`ReferenceRays::samples_done`] alone.
    pub fn trace(&self, ctx: &GpuContext, samples: Range<u32>, pixels: Range<u32>) {
        let end = pixels.end.min(self.pixels);
        let start = pixels.start.min(end);
        let take = samples.end.min(self.total).saturating_sub(samples.start);
        if take == 0 || start == end {
            return;
        }
        let (x, y, row) = grid(ctx, end - start);
        let u = TraceUniforms {
            count: end,
            first: samples.start,
            samples: take,
            row,
            node_count: self.node_count,
            triangle_count: self.triangle_count,
            offset: start,
            ..TraceUniforms::default()
        };
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        let pipes = pipelines(ctx, self.path);
        dispatch(ctx, &pipes.reference, &self.group, (x, y));
    }

    /// Pixels (points) it traces from.
    pub fn pixels(&self) -> u32 {
        self.pixels
    }

    /// Samples per pixel traced (submitted) so far.
    pub fn samples_done(&self) -> u32 {
        self.done
    }

    /// Samples per pixel when complete.
    pub fn samples_total(&self) -> u32 {
        self.total
    }

    /// Wait for the GPU and read every pixel's counts back.
    pub fn read(&self, ctx: &GpuContext) -> Result<Vec<RayCounts>, RenderError> {
        let words = read_u32s(ctx, &self.results)?;
        Ok(counts_of(&words, self.pixels as usize))
    }

    /// Ask for every pixel's counts as they stand after what was submitted so far (a copy into
    /// a staging buffer, submitted, its mapping requested) without waiting: the answer comes
    /// through [`PendingCounts::poll`] once the GPU has got there.
    pub fn start_read(&self, ctx: &GpuContext) -> PendingCounts {
        let staging = copy_to_staging(ctx, &self.results, "ReferenceRays::staging");
        let mapped = Arc::new(Mutex::new(None));
        let sink = mapped.clone();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            if let Ok(mut m) = sink.lock() {
                *m = Some(r.map_err(|e| e.to_string()));
            }
        });
        PendingCounts {
            staging,
            mapped,
            pixels: self.pixels as usize,
        }
    }
}

/// Counts asked for by [`ReferenceRays::start_read`], on their way back.
pub struct PendingCounts {
    staging: wgpu::Buffer,
    /// Set by the mapping's callback: whether the staging buffer could be mapped.
    mapped: Arc<Mutex<Option<Result<(), String>>>>,
    pixels: usize,
}

impl PendingCounts {
    /// The counts, if they have arrived: checks the device once, never waits.
    pub fn poll(&self, ctx: &GpuContext) -> Option<Result<Vec<RayCounts>, RenderError>> {
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        self.take()
    }

    /// The counts, if the mapping has completed (the device polled by someone else).
    pub fn take(&self) -> Option<Result<Vec<RayCounts>, RenderError>> {
        let outcome = self.mapped.lock().ok()?.take()?;
        Some(outcome.map_err(RenderError::Readback).and_then(|()| {
            let counts = {
                let view = self
                    .staging
                    .slice(..)
                    .get_mapped_range()
                    .map_err(|e| RenderError::Readback(e.to_string()))?;
                let words: Vec<u32> = view
                    .chunks_exact(4)
                    .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect();
                counts_of(&words, self.pixels)
            };
            self.staging.unmap();
            Ok(counts)
        }))
    }
}

/// The first `pixels` triples of `words` as counts.
fn counts_of(words: &[u32], pixels: usize) -> Vec<RayCounts> {
    words
        .chunks_exact(3)
        .take(pixels)
        .map(|w| RayCounts {
            count: w[0],
            box_tests: w[1],
            triangle_tests: w[2],
        })
        .collect()
}

/// One shadow ray: `origin + t·dir` for `t_min <= t <= t_max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub t_min: f32,
    pub t_max: f32,
}

/// Whether each of `rays` is blocked by a triangle of `scene`, traced on the GPU by its path
/// (waits for it).
pub fn any_hit(
    ctx: &GpuContext,
    scene: &TraceScene,
    rays: &[Ray],
) -> Result<Vec<RayCounts>, RenderError> {
    let count = u32::try_from(rays.len())
        .map_err(|_| RenderError::Request(format!("{} rays: too many", rays.len())))?;
    fits(ctx, "the rays", rays.len() as u64 * 32)?;
    let mut items: Vec<[f32; 4]> = rays
        .iter()
        .flat_map(|r| [r.origin.extend(r.t_min), r.dir.extend(r.t_max)])
        .map(|v| v.to_array())
        .collect();
    if items.is_empty() {
        items.push([0.0; 4]);
    }
    let items = storage_buffer(&ctx.device, "any_hit::rays", &items);
    let light = storage_buffer(&ctx.device, "any_hit::samples", &[[0.0f32; 4]]);
    let results = results_buffer(ctx, "any_hit::results", u64::from(count) * 3);
    let uniforms = crate::render::uniform_buffer::<TraceUniforms>(&ctx.device, "Trace");
    let (x, y, row) = grid(ctx, count);
    let u = TraceUniforms {
        count,
        row,
        node_count: scene.node_count,
        triangle_count: scene.triangle_count,
        ..TraceUniforms::default()
    };
    ctx.queue.write_buffer(&uniforms, 0, bytemuck::bytes_of(&u));
    let pipes = pipelines(ctx, scene.path());
    let group = pipes.group(
        ctx,
        "any_hit::group",
        scene,
        [&uniforms, &items, &light, &results],
    );
    dispatch(ctx, &pipes.any_hit, &group, (x, y));
    let words = read_u32s(ctx, &results)?;
    Ok(counts_of(&words, rays.len()))
}
