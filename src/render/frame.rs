//! One frame, in the order of design.md §1: (geometry, cached by the caller and uploaded into a
//! [`GpuScene`]) → light pass (the D-buffer from the light centre) → camera pass (per pixel |cx|,
//! branch, t, V(t), shading) → readback.

use std::fmt;
use std::str::FromStr;

use glam::Mat4;

use super::camera_pass::{poisson_disk, CameraPass};
use super::context::GpuContext;
use super::gpu_scene::GpuScene;
use super::light_pass::LightPass;
use super::readback;
use super::sample_maps::{sample_lights, SampleMaps};
use super::{CameraUniforms, LightUniforms, MethodUniforms, RenderError};
use crate::geometry::light_view::LightView;
use crate::geometry::VtVariant;
use crate::scene::Scene;

/// How a frame's visibility is computed: the D-buffer, the techniques people use instead, or the
/// ray-cast reference (design.md §4). Each method's knobs are in [`MethodParams`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Method {
    /// The D-buffer method of seed 000.
    #[default]
    DBuffer,
    /// The D-buffer with silhouettes and volumes taken from the light centre only: the
    /// penumbra-wedge approximation seed 000 Fig. 1 criticises.
    DBufferCenter,
    /// A hard shadow map from the light centre (Williams): the `|cx_o|` test alone, with
    /// slope-scaled bias.
    Hard,
    /// Percentage-closer filtering of the hard shadow map ([`MethodParams::pcf_radius`]).
    Pcf,
    /// Percentage-closer soft shadows (Fernando 2005) sized by the disk radius: blocker search,
    /// then filtering, with a rotated Poisson kernel.
    Pcss,
    /// N shadow maps from N stratified points on the disk, averaged (seed 002 §3.1).
    Sampled,
    /// Rays to K stratified disk samples per pixel (the geometry oracle); progressive in a
    /// [`super::session::Session`].
    Reference,
}

impl Method {
    pub const ALL: [Method; 7] = [
        Method::DBuffer,
        Method::DBufferCenter,
        Method::Hard,
        Method::Pcf,
        Method::Pcss,
        Method::Sampled,
        Method::Reference,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::DBuffer => "dbuffer",
            Method::DBufferCenter => "dbuffer-center",
            Method::Hard => "hard",
            Method::Pcf => "pcf",
            Method::Pcss => "pcss",
            Method::Sampled => "sampled",
            Method::Reference => "reference",
        }
    }

    /// One line for menus and `--help`.
    pub fn description(self) -> &'static str {
        match self {
            Method::DBuffer => "D-buffer soft shadows (Jakobsen et al. 2004)",
            Method::DBufferCenter => "D-buffer with silhouettes from the light centre only",
            Method::Hard => "hard shadow map from the light centre",
            Method::Pcf => "percentage-closer filtering of the shadow map",
            Method::Pcss => "percentage-closer soft shadows (Fernando 2005)",
            Method::Sampled => "N shadow maps from points on the disk, averaged",
            Method::Reference => "ray-cast ground truth (K disk samples per pixel)",
        }
    }

    /// Whether the method's volumes are built from the light centre only.
    pub fn center_silhouettes(self) -> bool {
        self == Method::DBufferCenter
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
                format!("unknown method '{s}': expected one of {}", names.join(", "))
            })
    }
}

/// The knobs of the comparison methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MethodParams {
    /// PCF kernel radius in shadow-map texels: (2r + 1)² taps. 0 to [`MAX_PCF_RADIUS`].
    pub pcf_radius: u32,
    /// PCSS blocker-search taps, 1 to [`MAX_TAPS`].
    pub pcss_blocker_taps: u32,
    /// PCSS filter taps, 1 to [`MAX_TAPS`].
    pub pcss_filter_taps: u32,
    /// Shadow maps of the `sampled` method, 1 to [`MAX_SAMPLED_LIGHTS`].
    pub sampled_lights: u32,
    /// Disk samples per pixel of the reference (K), 1 to [`MAX_REFERENCE_SAMPLES`].
    pub reference_samples: u32,
    /// Samples per pixel a [`super::session::Session`] adds to the reference per frame.
    pub reference_step: u32,
}

pub const MAX_PCF_RADIUS: u32 = 8;
pub const MAX_TAPS: u32 = 64;
pub const MAX_SAMPLED_LIGHTS: u32 = 64;
pub const MAX_REFERENCE_SAMPLES: u32 = 65536;

impl Default for MethodParams {
    fn default() -> Self {
        Self {
            pcf_radius: 2,
            pcss_blocker_taps: 16,
            pcss_filter_taps: 32,
            sampled_lights: 16,
            reference_samples: crate::geometry::oracle::DEFAULT_SAMPLES as u32,
            reference_step: 8,
        }
    }
}

impl MethodParams {
    /// Every knob in its range, or which one is not and what was expected.
    pub fn validate(&self) -> Result<(), String> {
        let checks = [
            ("PCF radius", self.pcf_radius, 0, MAX_PCF_RADIUS),
            ("PCSS blocker taps", self.pcss_blocker_taps, 1, MAX_TAPS),
            ("PCSS filter taps", self.pcss_filter_taps, 1, MAX_TAPS),
            ("sampled lights", self.sampled_lights, 1, MAX_SAMPLED_LIGHTS),
            (
                "reference samples",
                self.reference_samples,
                1,
                MAX_REFERENCE_SAMPLES,
            ),
            (
                "reference step",
                self.reference_step,
                1,
                MAX_REFERENCE_SAMPLES,
            ),
        ];
        for (what, value, lo, hi) in checks {
            if !(lo..=hi).contains(&value) {
                return Err(format!("{what} of {value}: expected {lo} to {hi}"));
            }
        }
        Ok(())
    }
}

/// What to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameRequest {
    pub width: u32,
    pub height: u32,
    /// The D-buffer (and every shadow map) is `dbuffer_size`² texels.
    pub dbuffer_size: u32,
    pub method: Method,
    pub vt: VtVariant,
    pub params: MethodParams,
    /// Render the whole D-buffer (volumes included, whatever the method) and read it back into
    /// [`Frame`] (`distance`, `umbra`, `penumbra`). Off, each method runs only the passes it needs
    /// (as the benchmark times them) and those fields are left empty.
    pub read_dbuffer: bool,
}

impl Default for FrameRequest {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            dbuffer_size: 1024,
            method: Method::DBuffer,
            vt: VtVariant::Smoothstep,
            params: MethodParams::default(),
            read_dbuffer: true,
        }
    }
}

/// A rendered frame, read back. Images are row-major, row 0 at the top.
#[derive(Clone, Debug, Default)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// Shaded colour, sRGB 8-bit RGBA.
    pub color: Vec<[u8; 4]>,
    /// V per pixel.
    pub visibility: Vec<f32>,
    /// t per pixel.
    pub t: Vec<f32>,
    /// Branch code per pixel ([`crate::geometry::Branch::code`]).
    pub branch: Vec<u8>,
    /// World position, and 1 where a surface was hit (0 elsewhere).
    pub position: Vec<[f32; 4]>,
    pub dbuffer_size: u32,
    /// `|cx_o|` per texel ([`super::light_pass::NO_SURFACE`] where none).
    pub distance: Vec<f32>,
    /// `(|cx_uv|, |cx_s|)` per texel, 0 where no umbra exit.
    pub umbra: Vec<[f32; 2]>,
    /// `(|cx_pv|, |cx_s|)` per texel, 0 where no penumbra entry.
    pub penumbra: Vec<[f32; 2]>,
    /// GPU milliseconds per pass from timestamp queries; empty without them.
    pub gpu_ms: Vec<(String, f64)>,
}

/// Bias of the hidden-from-centre test: relative to `|cx|`, plus the slope one texel spans times
/// the tangent of the incidence angle, times this factor.
pub const BIAS_CONSTANT: f32 = 2e-4;
pub const BIAS_SLOPE: f32 = 1.5;
/// Ambient share of the shading, so shadowed surfaces keep their shape.
pub const AMBIENT: f32 = 0.1;

/// The session-long passes and their size-dependent targets.
pub struct FrameRenderer {
    light: LightPass,
    camera: CameraPass,
    sample_maps: SampleMaps,
    poisson: [[f32; 4]; 32],
    timer: Option<Timer>,
}

struct Timer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
}

/// Begin and end of the light pass, the camera pass and the `sampled` maps.
const QUERIES: u32 = 6;

impl FrameRenderer {
    pub fn new(ctx: &GpuContext) -> FrameRenderer {
        let device = &ctx.device;
        let timer = ctx.timestamps.then(|| Timer {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("FrameRenderer::queries"),
                ty: wgpu::QueryType::Timestamp,
                count: QUERIES,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("FrameRenderer::resolve"),
                size: u64::from(QUERIES) * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
        });
        let mut poisson = [[0.0; 4]; 32];
        for (i, p) in poisson_disk(64).iter().enumerate() {
            poisson[i / 2][2 * (i % 2)] = p.x;
            poisson[i / 2][2 * (i % 2) + 1] = p.y;
        }
        FrameRenderer {
            light: LightPass::new(device),
            camera: CameraPass::new(device),
            sample_maps: SampleMaps::new(device),
            poisson,
            timer,
        }
    }

    /// Render `scene` (whose volumes `gpu` holds) and read everything back. The reference needs
    /// its V: see [`FrameRenderer::render_with`].
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        gpu: &GpuScene,
        light_view: &LightView,
        request: &FrameRequest,
    ) -> Result<Frame, RenderError> {
        self.render_with(ctx, scene, gpu, light_view, request, None)
    }

    /// [`FrameRenderer::render`], with V per pixel given (row-major, `width`×`height`) for
    /// [`Method::Reference`], which is shaded like every other method.
    pub fn render_with(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        gpu: &GpuScene,
        light_view: &LightView,
        request: &FrameRequest,
        external: Option<&[f32]>,
    ) -> Result<Frame, RenderError> {
        let (device, queue) = (&ctx.device, &ctx.queue);
        let max = device.limits().max_texture_dimension_2d;
        for (what, size) in [
            ("image width", request.width),
            ("image height", request.height),
            ("D-buffer size", request.dbuffer_size),
        ] {
            if size == 0 || size > max {
                return Err(RenderError::Size { what, size, max });
            }
        }
        request.params.validate().map_err(RenderError::Request)?;
        let method = request.method;
        let mode = match method {
            Method::DBuffer | Method::DBufferCenter => 0,
            Method::Hard => 1,
            Method::Pcf => 2,
            Method::Pcss => 3,
            Method::Sampled => 4,
            Method::Reference => 5,
        };
        let pixels = request.width as usize * request.height as usize;
        if method == Method::Reference && external.is_none_or(|v| v.len() != pixels) {
            return Err(RenderError::Request(format!(
                "the reference needs V for each of the {pixels} pixels"
            )));
        }
        // Which passes this method needs: the light view (with volumes for the D-buffer), the
        // point-light maps of `sampled`. A request that reads the D-buffer back gets all of it.
        let light_pass =
            request.read_dbuffer || !matches!(method, Method::Sampled | Method::Reference);
        let volumes =
            request.read_dbuffer || matches!(method, Method::DBuffer | Method::DBufferCenter);
        let sampled = method == Method::Sampled;

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let new_dbuffer = self.light.resize(device, request.dbuffer_size);
        let new_camera = self.camera.resize(device, request.width, request.height);
        if let Some(dbuffer) = self.light.targets() {
            if new_dbuffer || !self.camera.is_bound() {
                self.camera.bind_dbuffer(device, dbuffer);
            }
        }
        // The maps of `sampled` exist at least as one 1×1 layer, so the camera pass can bind them.
        let new_maps = if sampled {
            self.sample_maps
                .resize(device, request.dbuffer_size, request.params.sampled_lights)
        } else if self.sample_maps.targets().is_none() {
            self.sample_maps.resize(device, 1, 1)
        } else {
            false
        };
        if new_camera || new_maps || !self.camera.methods_bound() {
            self.camera.bind_methods(device, &self.sample_maps);
        }
        if let Some(v) = external {
            if method == Method::Reference {
                self.camera.set_external_visibility(queue, v);
            }
        }
        let (Some(dbuffer), Some(targets)) = (self.light.targets(), self.camera.targets()) else {
            return Err(RenderError::Gpu("render targets were not created".into()));
        };

        let light = scene.light;
        let light_vp = light_view.view_projection();
        self.light.prepare(
            queue,
            &LightUniforms {
                view_proj: light_vp.to_cols_array_2d(),
                center: light.center.extend(1.0).to_array(),
                normal: light.normal.extend(0.0).to_array(),
                depth_scale: [1.0 / light_view.far, 0.0, 0.0, 0.0],
            },
        );
        let aspect = request.width as f32 / request.height as f32;
        let (near, far) = camera_range(scene.camera.eye, gpu.bounds);
        let camera_vp = scene.camera.projection(aspect, near, far) * scene.camera.view();
        let slope = texel_slope(&light_view.projection, request.dbuffer_size);
        if sampled {
            self.sample_maps.prepare(
                queue,
                &sample_lights(&light, light_view, request.params.sampled_lights),
            );
        }
        let p = &request.params;
        let methods = MethodUniforms {
            params: [
                p.pcf_radius as f32,
                p.pcss_blocker_taps as f32,
                p.pcss_filter_taps as f32,
                p.sampled_lights as f32,
            ],
            pcss: [
                if method == Method::Pcss {
                    nearest_caster(scene)
                } else {
                    0.0
                },
                0.0,
                0.0,
                0.0,
            ],
            inv_light_view_proj: light_vp.inverse().to_cols_array_2d(),
            poisson: self.poisson,
        };
        self.camera.prepare(
            queue,
            &CameraUniforms {
                view_proj: camera_vp.to_cols_array_2d(),
                light_view_proj: light_vp.to_cols_array_2d(),
                eye: scene.camera.eye.extend(1.0).to_array(),
                light_center: light.center.extend(light.radius).to_array(),
                light_normal: light.normal.extend(light.intensity).to_array(),
                bias: [
                    BIAS_CONSTANT,
                    BIAS_SLOPE,
                    request.dbuffer_size as f32,
                    slope,
                ],
                mode: [
                    mode,
                    match request.vt {
                        VtVariant::Smoothstep => 0,
                        VtVariant::Sqrt => 1,
                        VtVariant::Exact => 2,
                        VtVariant::Linear => 3,
                    },
                    (AMBIENT * 1000.0) as u32,
                    0,
                ],
            },
            &methods,
        );

        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("FrameRenderer::encoder"),
        });
        let timer = self.timer.as_ref();
        if light_pass {
            self.light.record(
                &mut encoder,
                gpu,
                timer.map(|t| (&t.queries, 0, 1)),
                volumes,
            );
        }
        if sampled {
            self.sample_maps
                .record(&mut encoder, gpu, timer.map(|t| (&t.queries, 4, 5)));
        }
        self.camera
            .record(&mut encoder, gpu, timer.map(|t| (&t.queries, 2, 3)));
        let stamps = timer.map(|t| {
            encoder.resolve_query_set(&t.queries, 0..QUERIES, &t.resolve, 0);
            let out = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("FrameRenderer::timestamps"),
                size: u64::from(QUERIES) * 8,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            encoder.copy_buffer_to_buffer(&t.resolve, 0, &out, 0, u64::from(QUERIES) * 8);
            out
        });
        let color = readback::copy(device, &mut encoder, &targets.color, 4);
        let data = readback::copy(device, &mut encoder, &targets.data, 8);
        let position = readback::copy(device, &mut encoder, &targets.position, 16);
        let maps = (request.read_dbuffer && light_pass).then(|| {
            [
                readback::copy(device, &mut encoder, &dbuffer.distance.texture, 4),
                readback::copy(device, &mut encoder, &dbuffer.umbra.texture, 8),
                readback::copy(device, &mut encoder, &dbuffer.penumbra.texture, 8),
            ]
        });
        queue.submit([encoder.finish()]);

        // Errors raised before the scope (creating pipelines) come first: they are the cause.
        let scoped = pollster::block_on(scope.pop());
        if let Some(e) = ctx.take_uncaptured_errors().into_iter().next() {
            return Err(RenderError::Gpu(e));
        }
        if let Some(e) = scoped {
            return Err(RenderError::Gpu(e.to_string()));
        }

        let rgba = |v: Vec<f32>| {
            v.chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect()
        };
        let pairs = |v: Vec<f32>| v.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        let mut gpu_ms = Vec::new();
        if let Some(buffer) = stamps {
            let bytes = readback::map_bytes(device, &buffer)?;
            let ticks: Vec<u64> = bytes
                .chunks_exact(8)
                .map(|b| u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
                .collect();
            let period_ms = f64::from(queue.get_timestamp_period()) * 1e-6;
            let ms = |a: usize, b: usize| ticks[b].saturating_sub(ticks[a]) as f64 * period_ms;
            if light_pass {
                gpu_ms.push(("light_pass".to_string(), ms(0, 1)));
            }
            if sampled {
                gpu_ms.push(("sample_maps".to_string(), ms(4, 5)));
            }
            gpu_ms.push(("camera_pass".to_string(), ms(2, 3)));
        }
        let data = data.read_f32(device)?;
        let (visibility, t_branch): (Vec<f32>, Vec<f32>) =
            data.chunks_exact(2).map(|c| (c[0], c[1])).unzip();
        // The shader stores t + 2·branch: umbra 0, hidden [2, 2.5], visible [4.5, 5], lit 7, so
        // round((x − ½)/2) is the branch and the rest is t, both exact.
        let branch: Vec<u8> = t_branch
            .iter()
            .map(|&x| ((x - 0.5) / 2.0).round().clamp(0.0, 3.0) as u8)
            .collect();
        let t = t_branch
            .iter()
            .zip(&branch)
            .map(|(&x, &b)| x - 2.0 * f32::from(b))
            .collect();
        let (distance, umbra, penumbra) = match maps {
            Some([d, u, p]) => (
                d.read_f32(device)?,
                pairs(u.read_f32(device)?),
                pairs(p.read_f32(device)?),
            ),
            None => Default::default(),
        };
        Ok(Frame {
            width: request.width,
            height: request.height,
            color: color
                .read_bytes(device)?
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
            visibility,
            t,
            branch,
            position: rgba(position.read_f32(device)?),
            dbuffer_size: request.dbuffer_size,
            distance,
            umbra,
            penumbra,
            gpu_ms,
        })
    }
}

/// Near and far planes that hold the whole scene, given by its bounds, as seen from `eye`.
fn camera_range(eye: glam::Vec3, (lo, hi): (glam::Vec3, glam::Vec3)) -> (f32, f32) {
    let mut far = 1.0f32;
    for corner in 0..8 {
        let pick = |bit: u32, a: f32, b: f32| if corner & bit == 0 { a } else { b };
        let p = glam::Vec3::new(
            pick(1, lo.x, hi.x),
            pick(2, lo.y, hi.y),
            pick(4, lo.z, hi.z),
        );
        let d = (p - eye).length();
        if d.is_finite() {
            far = far.max(d);
        }
    }
    let far = far * 1.5;
    (far * 1e-4, far)
}

/// The distance from the light centre to the nearest caster vertex in front of the light: where
/// PCSS's blocker search stops.
fn nearest_caster(scene: &Scene) -> f32 {
    let light = scene.light;
    scene
        .casters()
        .flat_map(|o| o.mesh.positions.iter())
        .filter(|v| light.height_of(**v) > 0.0)
        .map(|v| (*v - light.center).length())
        .filter(|d| d.is_finite() && *d > 0.0)
        .fold(f32::MAX, f32::min)
        .min(1e30)
}

/// The slope one D-buffer texel spans (the larger of its two axes).
fn texel_slope(projection: &Mat4, size: u32) -> f32 {
    let w = 2.0 / projection.x_axis.x;
    let h = 2.0 / projection.y_axis.y;
    w.abs().max(h.abs()) / size.max(1) as f32
}
