//! The `raytraced` method's passes before the camera pass (`shaders/passes/raytraced.wgsl`):
//! shadow rays against the scene's BVH ([`super::trace::GpuBvh`]) from every pixel's surface
//! point (the screen prepass's positions), then a denoiser in the manner of NVIDIA's SIGMA —
//! temporal accumulation with reprojection and history rejection, and a spatial filter whose
//! footprint follows the penumbra's size estimated from the rays' hit distances. Three compute
//! dispatches a frame (two with the denoiser off), every buffer one `vec4<f32>` per pixel; the
//! geometry and the history are kept for the next frame in two sets used in turn.

use glam::Mat4;

use super::camera::ScreenView;
use super::trace::TraceScene;
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, compute_pipeline, pipeline_layout, shader_module, storage_entry, texture_entry,
    uniform_buffer, uniform_entry, view_entry, GpuContext, RenderError,
};
use crate::scene::{Light, MAX_POLYGON_VERTICES};

/// Storage buffers the passes bind in the compute stage: the BVH, this frame's rays and
/// geometry, the previous frame's geometry and history, this frame's history and the output.
pub const STORAGE_BUFFERS: u32 = 7;

/// The light's kind as `RtUniforms::light_kind` (`shared/camera.wgsl`'s `LIGHT_*`).
const LIGHT_DISK: u32 = 0;
const LIGHT_LINE: u32 = 1;
const LIGHT_POLYGON: u32 = 2;

/// `RtUniforms::flags`: the previous frame's history may be reprojected.
pub const RT_HISTORY: u32 = 1;
/// `RtUniforms::flags`: the light or a caster moved since the previous frame.
pub const RT_MOTION: u32 = 2;

/// `RtUniforms` of `shaders/passes/raytraced.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RtUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub prev_view_proj: [[f32; 4]; 4],
    pub eye: [f32; 3],
    pub frame: u32,
    pub light_center: [f32; 3],
    pub light_kind: u32,
    pub light_normal: [f32; 3],
    pub light_corner_count: u32,
    pub light_u: [f32; 3],
    pub light_area: f32,
    pub light_w: [f32; 3],
    pub light_radius: f32,
    pub line_a: [f32; 3],
    pub rays: u32,
    pub line_b: [f32; 3],
    pub history: u32,
    pub width: u32,
    pub height: u32,
    pub tan_half_fov: f32,
    pub radius: f32,
    pub node_count: u32,
    pub triangle_count: u32,
    pub flags: u32,
    pub light_size: f32,
    pub light_corners: [[f32; 4]; MAX_POLYGON_VERTICES / 2],
}

const _: () = assert!(std::mem::size_of::<RtUniforms>() == 400);

/// What one frame traces and keeps, besides the view and the light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RtSettings {
    /// The frame's index: where each pixel's sequence of light samples goes on from.
    pub frame: u32,
    /// Shadow rays per pixel.
    pub rays: u32,
    /// Frames the running mean spans at most (1: no temporal accumulation).
    pub history: u32,
    /// The spatial filter's largest radius in pixels (0: none).
    pub radius: f32,
    /// Run the denoiser's passes (else only the rays).
    pub denoise: bool,
    /// The light or a caster moved since the previous frame.
    pub motion: bool,
}

impl RtUniforms {
    /// The uniforms of a frame of `view` under `light`, its previous frame seen through
    /// `prev_view_proj` (`None`: no history to reproject).
    pub fn new(
        light: &Light,
        view: &ScreenView,
        fov_y_deg: f32,
        prev_view_proj: Option<Mat4>,
        bvh: &TraceScene,
        s: &RtSettings,
    ) -> RtUniforms {
        let mut u = RtUniforms {
            view_proj: view.view_proj.to_cols_array_2d(),
            prev_view_proj: prev_view_proj.unwrap_or(view.view_proj).to_cols_array_2d(),
            eye: view.eye.to_array(),
            frame: s.frame,
            light_center: light.center().to_array(),
            rays: s.rays.max(1),
            history: s.history.max(1),
            width: view.width,
            height: view.height,
            tan_half_fov: (fov_y_deg.to_radians() * 0.5).tan(),
            radius: s.radius.max(0.0),
            node_count: bvh.node_count(),
            triangle_count: bvh.triangle_count(),
            flags: (u32::from(prev_view_proj.is_some()) * RT_HISTORY)
                | (u32::from(s.motion) * RT_MOTION),
            ..RtUniforms::default()
        };
        match light {
            Light::Line(l) => {
                u.light_kind = LIGHT_LINE;
                u.line_a = l.a.to_array();
                u.line_b = l.b.to_array();
                u.light_size = (l.b - l.a).length();
            }
            Light::Area(a) => {
                let (bu, bw) = a.basis();
                u.light_normal = a.normal.to_array();
                u.light_u = bu.to_array();
                u.light_w = bw.to_array();
                u.light_size = 2.0 * a.radius;
                u.light_area = a.area();
                match crate::geometry::outline::Outline2d::of(a) {
                    crate::geometry::outline::Outline2d::Polygon { corners, area } => {
                        u.light_kind = LIGHT_POLYGON;
                        u.light_area = area;
                        for (i, p) in corners.iter().enumerate().take(MAX_POLYGON_VERTICES) {
                            u.light_corners[i / 2][2 * (i % 2)] = p.x;
                            u.light_corners[i / 2][2 * (i % 2) + 1] = p.y;
                        }
                        u.light_corner_count = corners.len().min(MAX_POLYGON_VERTICES) as u32;
                    }
                    _ => {
                        u.light_kind = LIGHT_DISK;
                        u.light_radius = a.radius;
                    }
                }
            }
        }
        u
    }
}

/// The three pipelines and their one layout, made once per device.
struct RtPipelines {
    layout: wgpu::BindGroupLayout,
    trace: wgpu::ComputePipeline,
    temporal: wgpu::ComputePipeline,
    spatial: wgpu::ComputePipeline,
}

fn pipelines(ctx: &GpuContext) -> std::sync::Arc<RtPipelines> {
    ctx.shared(|device| {
        use wgpu::ShaderStages as S;
        let module = shader_module(device, "passes/raytraced.wgsl");
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("Raytraced::layout"),
            entries: &[
                uniform_entry(0, S::COMPUTE),
                storage_entry(1, S::COMPUTE, true),
                texture_entry(2, S::COMPUTE, wgpu::TextureViewDimension::D2),
                storage_entry(3, S::COMPUTE, false),
                storage_entry(4, S::COMPUTE, false),
                storage_entry(5, S::COMPUTE, true),
                storage_entry(6, S::COMPUTE, true),
                storage_entry(7, S::COMPUTE, false),
                storage_entry(8, S::COMPUTE, false),
            ],
        });
        let pl = pipeline_layout(device, "Raytraced", &[&layout]);
        let compute = |entry: &str| compute_pipeline(device, entry, &pl, &module, entry);
        RtPipelines {
            trace: compute("cs_trace"),
            temporal: compute("cs_temporal"),
            spatial: compute("cs_spatial"),
            layout,
        }
    })
}

/// A per-pixel buffer of `vec4<f32>`s.
fn pixel_buffer(ctx: &GpuContext, label: &str, pixels: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (pixels * 16).max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

/// The per-pixel buffers of one image size: this frame's rays, the output, and the geometry and
/// history in two sets (the frame writes one and reads the other's).
pub struct RtTargets {
    pub width: u32,
    pub height: u32,
    pub raw: wgpu::Buffer,
    pub denoised: wgpu::Buffer,
    geo: [wgpu::Buffer; 2],
    history: [wgpu::Buffer; 2],
    /// Changes when the buffers are made again (a bind-group key).
    pub generation: u64,
}

impl RtTargets {
    /// The buffers of a `width`×`height` image; an error (before anything is made) when one of
    /// them is larger than a storage binding of the device.
    pub fn new(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        generation: u64,
    ) -> Result<RtTargets, RenderError> {
        let n = u64::from(width) * u64::from(height);
        super::trace::fits(
            ctx,
            "raytraced's per-pixel buffers (16 bytes a pixel)",
            n * 16,
        )?;
        let b = |label: &str| pixel_buffer(ctx, label, n);
        Ok(RtTargets {
            width,
            height,
            raw: b("Raytraced::raw"),
            denoised: b("Raytraced::denoised"),
            geo: [b("Raytraced::geo0"), b("Raytraced::geo1")],
            history: [b("Raytraced::history0"), b("Raytraced::history1")],
            generation,
        })
    }
}

/// The passes of one method state: its uniforms and the bind groups of the two parities.
pub struct RtPasses {
    pipes: std::sync::Arc<RtPipelines>,
    uniforms: wgpu::Buffer,
    /// The bind groups for frames that write set 0 and set 1, and the key they were made for.
    groups: Option<([wgpu::BindGroup; 2], (u64, u64, u64))>,
}

impl RtPasses {
    pub fn new(ctx: &GpuContext) -> RtPasses {
        RtPasses {
            pipes: pipelines(ctx),
            uniforms: uniform_buffer::<RtUniforms>(&ctx.device, "Raytraced::uniforms"),
            groups: None,
        }
    }

    /// Record a frame's passes into `rec`: the rays, then (with `denoise`) the temporal and
    /// spatial passes, writing set `parity` and reading the other.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        uniforms: &RtUniforms,
        bvh: (&TraceScene, u64),
        positions: (&wgpu::TextureView, u64),
        targets: &RtTargets,
        parity: usize,
        denoise: bool,
    ) {
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
        let key = (targets.generation, positions.1, bvh.1);
        if self.groups.as_ref().is_none_or(|(_, k)| *k != key) {
            let group = |w: usize| {
                let r = 1 - w;
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("Raytraced::group"),
                    layout: &self.pipes.layout,
                    entries: &[
                        buffer_entry(0, &self.uniforms),
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: bvh.0.resource(),
                        },
                        view_entry(2, positions.0),
                        buffer_entry(3, &targets.raw),
                        buffer_entry(4, &targets.geo[w]),
                        buffer_entry(5, &targets.geo[r]),
                        buffer_entry(6, &targets.history[r]),
                        buffer_entry(7, &targets.history[w]),
                        buffer_entry(8, &targets.denoised),
                    ],
                })
            };
            self.groups = Some(([group(0), group(1)], key));
        }
        let Some((groups, _)) = &self.groups else {
            return;
        };
        let group = &groups[parity % 2];
        let grid = (targets.width.div_ceil(8), targets.height.div_ceil(8));
        let mut run = |name: &'static str, pipeline: &wgpu::ComputePipeline| {
            let span = rec.span(name);
            let mut pass = rec
                .encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(name),
                    timestamp_writes: span.compute_writes(rec.timer),
                });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(grid.0, grid.1, 1);
        };
        run("rt_trace", &self.pipes.trace);
        if denoise {
            run("rt_temporal", &self.pipes.temporal);
            run("rt_spatial", &self.pipes.spatial);
        }
    }
}
