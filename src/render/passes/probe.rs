//! The probe (`shaders/passes/probe.wgsl`): what the lab reads back of a frame instead of the
//! frame. A compute pass writes into a small storage buffer, a copy puts it in one of two
//! persistent staging buffers, and the result is picked up a frame later without waiting:
//! - [`ProbeRequest::Pixel`]: every value under the cursor ([`PIXEL_FLOATS`] floats, 112 bytes);
//! - [`ProbeRequest::Fit`]: the shown scalar at [`FIT_GRID`]² samples of a grid, for the display
//!   range's auto-fit (2.3 KiB), instead of reading the whole image;
//! - [`ProbeRequest::Motion`]: V at [`MOTION_GRID`]² pixels of a grid (2.3 KiB), for the lab's
//!   motion meter while the light or a caster is dragged (`app::motion`);
//! - [`ProbeRequest::Range`]: the pixels whose V or t is NaN, infinite or outside [0, 1] (what
//!   the range view marks), counted on the GPU: [`COUNT_GROUPS`] partial counts (256 bytes).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use glam::Mat4;

use super::camera::CameraTargets;
use super::view::{ViewBindings, ViewInputs, ViewParams, ViewUniforms};
use crate::render::light_maps::LightMaps;
use crate::render::timer::Recorder;
use crate::render::{buffer_entry, compute_pipeline, pipeline_layout, shader_module, GpuContext};

/// Floats of a pixel probe (`PIXEL_FLOATS` of the shader): 0–3 colour (sRGB bytes / 255), 4 V,
/// 5 t + 2·branch, 6 depth, 7 hit, 8 reference V, 9–11 world position, 12–13 the method's
/// cost (work, path), 14–15 the light-map texel,
/// 16–27 the three light-map textures' RGBA there. NaN where a value does not exist.
pub const PIXEL_FLOATS: usize = 28;
/// The auto-fit samples a grid of this many squared.
pub const FIT_GRID: u32 = 24;
/// `PROBE_*` of the shader: what a dispatch reads.
pub const PROBE_PIXEL: u32 = 0;
pub const PROBE_FIT: u32 = 1;
pub const PROBE_MOTION: u32 = 2;
pub const PROBE_COUNT: u32 = 3;
/// The range count runs this many workgroups of 64, each counting every `COUNT_GROUPS · 64`-th
/// pixel; their counts come back and add up to the frame's.
pub const COUNT_GROUPS: u32 = 64;
/// The motion probe reads V at a grid of this many squared pixels (the fit's grid).
pub const MOTION_GRID: u32 = FIT_GRID;

/// The pixel of a `width`×`height` image that sample `i` of a `grid`² grid reads (the fit's and
/// the motion probe's `grid_pixel` in `probe.wgsl`).
pub fn grid_pixel(i: u32, grid: u32, width: u32, height: u32) -> (u32, u32) {
    let at = |g: u32, n: u32| ((g as f32 + 0.5) / grid as f32 * n as f32) as u32;
    (at(i % grid, width), at(i / grid, height))
}

/// What to read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProbeRequest {
    /// Everything at pixel (`x`, `y`) of the camera image, or texel (`x`, `y`) of the light maps
    /// in the light-space view.
    Pixel { x: u32, y: u32, params: ViewParams },
    /// The shown scalar over a grid, for [`super::view::Mapping::fit`].
    Fit { params: ViewParams },
    /// V over a grid of [`MOTION_GRID`]² pixels (NaN where no surface), whatever the view;
    /// `tag` comes back with the answer.
    Motion { tag: u64, params: ViewParams },
    /// The pixels the range view marks, counted ([`range_count`] of the answer); `serial`
    /// (the frame's, as the caller numbers them) comes back with the answer.
    Range { params: ViewParams, serial: u64 },
}

/// The count a [`ProbeRequest::Range`] answer holds: its workgroups' counts added up.
pub fn range_count(values: &[f32]) -> u64 {
    values
        .iter()
        .filter(|v| v.is_finite() && **v > 0.0)
        .map(|v| *v as u64)
        .sum()
}

impl ProbeRequest {
    fn params(&self) -> &ViewParams {
        match self {
            ProbeRequest::Pixel { params, .. }
            | ProbeRequest::Fit { params }
            | ProbeRequest::Motion { params, .. }
            | ProbeRequest::Range { params, .. } => params,
        }
    }

    fn floats(&self) -> usize {
        match self {
            ProbeRequest::Pixel { .. } => PIXEL_FLOATS,
            ProbeRequest::Fit { .. } => (FIT_GRID * FIT_GRID) as usize,
            ProbeRequest::Motion { .. } => (MOTION_GRID * MOTION_GRID) as usize,
            ProbeRequest::Range { .. } => COUNT_GROUPS as usize,
        }
    }
}

/// A probe's answer.
#[derive(Clone, Debug, PartialEq)]
pub struct ProbeResult {
    pub request: ProbeRequest,
    pub values: Vec<f32>,
}

/// The pipeline, built once per device.
pub struct ProbePass {
    pipeline: wgpu::ComputePipeline,
    out_layout: wgpu::BindGroupLayout,
}

impl ProbePass {
    pub fn get(ctx: &GpuContext) -> Arc<ProbePass> {
        ctx.shared(|device| {
            let view = super::view::ViewLayout::get(ctx);
            let out_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("ProbePass::out_layout"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: false },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                }],
            });
            let module = shader_module(device, "passes/probe.wgsl");
            let layout = pipeline_layout(device, "ProbePass::layout", &[&view.layout, &out_layout]);
            let pipeline =
                compute_pipeline(device, "ProbePass::pipeline", &layout, &module, "cs_main");
            ProbePass {
                pipeline,
                out_layout,
            }
        })
    }
}

/// One kind of probe: its uniforms, output, and a staging buffer in flight.
struct Slot {
    bindings: ViewBindings,
    out: wgpu::Buffer,
    out_group: wgpu::BindGroup,
    staging: wgpu::Buffer,
    /// The request copied into `staging` and not yet read.
    pending: Option<ProbeRequest>,
    mapped: Arc<AtomicBool>,
    map_requested: bool,
}

impl Slot {
    fn new(ctx: &GpuContext, pass: &ProbePass, floats: usize) -> Slot {
        let size = (floats * 4) as u64;
        let out = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("Probe::out"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let out_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Probe::out_group"),
            layout: &pass.out_layout,
            entries: &[buffer_entry(0, &out)],
        });
        Slot {
            bindings: ViewBindings::new(ctx, "Probe::uniforms"),
            out,
            out_group,
            staging: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("Probe::staging"),
                size,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }),
            pending: None,
            mapped: Arc::new(AtomicBool::new(false)),
            map_requested: false,
        }
    }
}

/// A view's probes.
pub struct Probe {
    pass: Arc<ProbePass>,
    pixel: Slot,
    fit: Slot,
    motion: Slot,
    range: Slot,
    /// Answers that arrived and were not taken yet.
    arrived: Vec<ProbeResult>,
}

impl Probe {
    pub fn new(ctx: &GpuContext) -> Probe {
        let pass = ProbePass::get(ctx);
        Probe {
            pixel: Slot::new(ctx, &pass, PIXEL_FLOATS),
            fit: Slot::new(ctx, &pass, (FIT_GRID * FIT_GRID) as usize),
            motion: Slot::new(ctx, &pass, (MOTION_GRID * MOTION_GRID) as usize),
            range: Slot::new(ctx, &pass, COUNT_GROUPS as usize),
            pass,
            arrived: Vec::new(),
        }
    }

    /// Whether an answer is still on its way.
    pub fn pending(&self) -> bool {
        [&self.pixel, &self.fit, &self.motion, &self.range]
            .iter()
            .any(|s| s.pending.is_some())
    }

    /// Whether a range count is on its way (another asked for meanwhile would be skipped).
    pub fn range_pending(&self) -> bool {
        self.range.pending.is_some()
    }

    /// Ask for the staging buffers copied into by the last submit to be mapped.
    pub fn request_map(&mut self) {
        for slot in [
            &mut self.pixel,
            &mut self.fit,
            &mut self.motion,
            &mut self.range,
        ] {
            if slot.pending.is_some() && !slot.map_requested {
                slot.map_requested = true;
                let mapped = slot.mapped.clone();
                slot.staging
                    .slice(..)
                    .map_async(wgpu::MapMode::Read, move |r| {
                        mapped.store(r.is_ok(), Ordering::Release)
                    });
            }
        }
    }

    /// Answers that have arrived, without waiting.
    pub fn poll(&mut self, ctx: &GpuContext) -> Vec<ProbeResult> {
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        for slot in [
            &mut self.pixel,
            &mut self.fit,
            &mut self.motion,
            &mut self.range,
        ] {
            if !slot.mapped.load(Ordering::Acquire) {
                continue;
            }
            if let (Some(request), Ok(view)) =
                (slot.pending, slot.staging.slice(..).get_mapped_range())
            {
                let values = super::super::readback::f32s(&view);
                self.arrived.push(ProbeResult { request, values });
            }
            slot.staging.unmap();
            slot.pending = None;
            slot.map_requested = false;
            slot.mapped.store(false, Ordering::Release);
        }
        std::mem::take(&mut self.arrived)
    }

    /// Wait for every answer in flight.
    pub fn wait(&mut self, ctx: &GpuContext) -> Vec<ProbeResult> {
        let _ = super::super::readback::map_now(&ctx.device);
        self.poll(ctx)
    }
}

/// Where a probe reads and keeps its state: a frame's targets (`frame::FrameTargets` gives them).
pub trait ProbeTargets {
    /// The camera pass's targets and the world → clip transform they were drawn with (`None`
    /// before anything was drawn into them), and the probe's own state.
    fn probe_parts(&mut self) -> (Option<(&CameraTargets, Mat4)>, &mut Option<Probe>);
}

/// Record `request` over what `targets` hold. Returns the bytes it will read back (0 when the
/// previous answer of that kind is still in flight: it is skipped).
pub fn record(
    ctx: &GpuContext,
    targets: &mut dyn ProbeTargets,
    request: &ProbeRequest,
    reference: Option<(&wgpu::TextureView, u64)>,
    maps: Option<LightMaps<'_>>,
    rec: &mut Recorder<'_>,
) -> u64 {
    let (Some((camera, view_proj)), probe) = targets.probe_parts() else {
        return 0;
    };
    let probe = probe.get_or_insert_with(|| Probe::new(ctx));
    let slot = match request {
        ProbeRequest::Pixel { .. } => &mut probe.pixel,
        ProbeRequest::Fit { .. } => &mut probe.fit,
        ProbeRequest::Motion { .. } => &mut probe.motion,
        ProbeRequest::Range { .. } => &mut probe.range,
    };
    if slot.pending.is_some() {
        return 0;
    }
    let inputs = ViewInputs {
        camera,
        camera_view_proj: view_proj,
        reference,
        maps,
    };
    let mut uniforms = ViewUniforms::new(
        request.params(),
        view_proj,
        inputs.maps.as_ref().map(|m| (m, m.size)),
        reference.is_some(),
    );
    // probe: x, y, PROBE_* mode, grid.
    let groups = match *request {
        ProbeRequest::Pixel { x, y, .. } => {
            uniforms.probe = [x, y, PROBE_PIXEL, 0];
            1
        }
        ProbeRequest::Fit { .. } => {
            uniforms.probe = [0, 0, PROBE_FIT, FIT_GRID];
            (FIT_GRID * FIT_GRID).div_ceil(64)
        }
        ProbeRequest::Motion { .. } => {
            uniforms.probe = [0, 0, PROBE_MOTION, MOTION_GRID];
            (MOTION_GRID * MOTION_GRID).div_ceil(64)
        }
        ProbeRequest::Range { .. } => {
            uniforms.probe = [0, 0, PROBE_COUNT, 0];
            COUNT_GROUPS
        }
    };
    let group = slot.bindings.bind(ctx, &inputs, &uniforms);
    let span = rec.span("probe");
    {
        let mut pass = rec
            .encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("Probe::pass"),
                timestamp_writes: span.compute_writes(rec.timer),
            });
        pass.set_pipeline(&probe.pass.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.set_bind_group(1, &slot.out_group, &[]);
        pass.dispatch_workgroups(groups, 1, 1);
    }
    let bytes = (request.floats() * 4) as u64;
    rec.encoder
        .copy_buffer_to_buffer(&slot.out, 0, &slot.staging, 0, bytes);
    slot.pending = Some(*request);
    bytes
}

/// A light-map texel's coordinates and its three textures' RGBA.
pub type MapTexel = ((u32, u32), [[f32; 4]; 3]);

/// A pixel probe's values, decoded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelValues {
    /// Shaded colour, sRGB bytes / 255.
    pub color: [f32; 4],
    pub visibility: f32,
    pub t: f32,
    /// [`crate::geometry::Branch::code`].
    pub branch: u8,
    /// The surface's world position; `None` where the pixel shows none.
    pub position: Option<glam::Vec3>,
    /// The reference V there, when the GPU holds the reference of this view.
    pub reference: Option<f32>,
    /// The method's work there and the path it took (its cost view).
    pub cost: [f32; 2],
    /// The light-map texel under the point (or under the cursor in the light-space view) and
    /// the three textures' RGBA there.
    pub texel: Option<MapTexel>,
}

impl PixelValues {
    /// The values of a [`ProbeRequest::Pixel`] answer (`PIXEL_FLOATS` long).
    pub fn decode(v: &[f32]) -> Option<PixelValues> {
        if v.len() < PIXEL_FLOATS {
            return None;
        }
        let finite = |x: f32| x.is_finite().then_some(x);
        let hit = v[7] > 0.5;
        let td = v[5];
        let branch = if td.is_finite() {
            ((td - 0.5) / 2.0).round().clamp(0.0, 3.0) as u8
        } else {
            0
        };
        let texel = match (finite(v[14]), finite(v[15])) {
            (Some(x), Some(y)) if x >= 0.0 && y >= 0.0 => {
                let mut maps = [[0.0f32; 4]; 3];
                for (t, m) in maps.iter_mut().enumerate() {
                    m.copy_from_slice(&v[16 + 4 * t..20 + 4 * t]);
                }
                Some(((x as u32, y as u32), maps))
            }
            _ => None,
        };
        Some(PixelValues {
            color: [v[0], v[1], v[2], v[3]],
            visibility: v[4],
            t: td - 2.0 * f32::from(branch),
            branch,
            position: hit.then(|| glam::Vec3::new(v[9], v[10], v[11])),
            reference: finite(v[8]),
            cost: [v[12], v[13]],
            texel,
        })
    }
}
