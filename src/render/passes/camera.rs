//! The camera pass every method shares (`shaders/shared/camera.wgsl`, completed by each method's
//! `shaders/methods/NAME.wgsl`): every surface from the camera, V per pixel from the method,
//! diffuse shading from the disk times V.
//!
//! Targets, `width`×`height` each: colour (Rgba8UnormSrgb), data (Rg32Float: V, and t + 2·branch
//! so both stay exact in one channel), cost (Rg32Float: the method's work at the pixel and the
//! path it took, `count_work`/`took_path` of `shared/camera.wgsl`, for the cost views) and
//! reversed depth (Depth32Float, 1 at the near plane, kept): 20 bytes of colour per pixel. The world position, when someone needs it (a render's
//! `position.exr`, the inspector), comes back from the depth; reversed float depth keeps it
//! accurate to about 1e-6 of the distance at any range.

use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::next_generation;
use crate::geometry::outline::Outline2d;
use crate::geometry::VtVariant;
use crate::render::gpu_scene::GpuScene;
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, opaque, pipeline_layout, uniform_buffer, uniform_entry, GpuContext,
    SurfaceVertex, Texture,
};
use crate::scene::{Light, Scene, MAX_POLYGON_VERTICES};

pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// The colour target seen as its bytes (the view pass copies them as they are).
pub const COLOR_BYTES_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub const DATA_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
/// The cost target: x the method's units of work at the pixel, y the path it took.
pub const COST_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The ambient share of the shading, so shadowed surfaces keep their shape.
pub const AMBIENT: f32 = 0.1;

/// `CameraUniforms` of `shaders/shared/camera.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CameraUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub eye: [f32; 3],
    pub ambient: f32,
    pub light_center: [f32; 3],
    pub light_radius: f32,
    pub light_normal: [f32; 3],
    pub light_intensity: f32,
    /// [`LIGHT_DISK`], [`LIGHT_LINE`] or [`LIGHT_POLYGON`]: a line emits all around (no
    /// one-sided test, no emitter cosine); `light_center` is then its midpoint, `light_radius`
    /// 0. A rectangle or polygon has `light_radius` the radius of the disk of its area (what
    /// `pcss` sizes its search by) and its corners below.
    pub light_kind: u32,
    /// How many of `light_corners` a rectangle or polygon has (0 for a disk or a line).
    pub light_corner_count: u32,
    /// The polygon's area (m²).
    pub light_area: f32,
    /// The radius of the disk about `light_center` that holds the whole light (a disk's own
    /// radius; 0 for a line): a plane farther than it from the centre misses the light.
    pub light_bound: f32,
    /// The light's plane basis (`AreaLight::basis`) the corners are given in.
    pub light_u: [f32; 3],
    pub _pad1: u32,
    pub light_w: [f32; 3],
    pub _pad2: u32,
    /// The corners about the centre in `(light_u, light_w)`, counter-clockwise there, two per
    /// vector (`geometry::outline::Outline2d`).
    pub light_corners: [[f32; 4]; MAX_POLYGON_VERTICES / 2],
}

const _: () = assert!(std::mem::size_of::<CameraUniforms>() == 288);

/// `CameraUniforms::light_kind` of a disk light (`LIGHT_DISK` in `shared/camera.wgsl`).
pub const LIGHT_DISK: u32 = 0;
/// `CameraUniforms::light_kind` of a line light (`LIGHT_LINE` in `shared/camera.wgsl`).
pub const LIGHT_LINE: u32 = 1;
/// `CameraUniforms::light_kind` of a rectangle or polygon light (`LIGHT_POLYGON`).
pub const LIGHT_POLYGON: u32 = 2;

/// The camera's world → clip transform for a `width`×`height` image of `scene` (whose surfaces
/// span `bounds`): reversed depth, planes that hold the whole scene.
pub fn view_projection(scene: &Scene, bounds: (Vec3, Vec3), width: u32, height: u32) -> Mat4 {
    let aspect = width as f32 / height.max(1) as f32;
    let (near, far) = camera_range(scene.camera.eye, bounds);
    // Near and far swapped: depth 1 at the near plane, 0 at the far one.
    scene.camera.projection(aspect, far, near) * scene.camera.view()
}

/// The camera pass's view of a method: its pipeline (and a second draw's, for a method drawn in
/// two: `CameraGroup::two_draws` of the methods) and its bind group (group 1).
pub struct CameraBindings<'a> {
    pub pipeline: &'a wgpu::RenderPipeline,
    pub refine: Option<&'a wgpu::RenderPipeline>,
    pub bind_group: &'a wgpu::BindGroup,
    /// The pipelines write the colour target only.
    pub colour_only: bool,
}

/// The camera a frame is drawn from, as the methods see it while they record: screen-space
/// methods (stencil volumes, planar shadows) draw their own passes over the camera's pixels
/// before the camera pass, so they need its transform and its image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenView {
    /// The camera pass's world → clip transform (reversed depth, finite far plane).
    pub view_proj: Mat4,
    /// The same camera with its far plane at infinity, reversed depth `ε + (1 − ε)·near/D` at view
    /// distance D (so `1` at the near plane and [`INFINITE_EPSILON`] at infinity): its x, y and w
    /// rows equal `view_proj`'s, so both cover the same pixels. Shadow volumes extruded to
    /// infinity (w = 0) are drawn with it and never clipped (Everitt and Kilgard's infinite
    /// projection, with the depth reversed for float precision).
    pub infinite_view_proj: Mat4,
    pub eye: Vec3,
    pub width: u32,
    pub height: u32,
}

/// Depth of a point at infinity under [`ScreenView::infinite_view_proj`]: strictly inside the
/// clip volume and behind every finite surface (16 steps of 24-bit depth).
pub const INFINITE_EPSILON: f32 = 1.0 / (1 << 20) as f32;

impl ScreenView {
    /// The view of a `width`×`height` image of `scene` (whose surfaces span `bounds`).
    pub fn new(scene: &Scene, bounds: (Vec3, Vec3), width: u32, height: u32) -> ScreenView {
        let aspect = width as f32 / height.max(1) as f32;
        let (near, _) = camera_range(scene.camera.eye, bounds);
        // clip.z = ε·clip.w + (1 − ε)·near·w: depth ε + (1 − ε)·near/D for a point, ε for a
        // direction (w = 0).
        let mut infinite =
            Mat4::perspective_infinite_rh(scene.camera.fov_y_deg.to_radians(), aspect, near);
        infinite.z_axis.z = -INFINITE_EPSILON;
        infinite.w_axis.z = (1.0 - INFINITE_EPSILON) * near;
        ScreenView {
            view_proj: view_projection(scene, bounds, width, height),
            infinite_view_proj: infinite * scene.camera.view(),
            eye: scene.camera.eye,
            width,
            height,
        }
    }
}

impl CameraUniforms {
    pub fn new(scene: &Scene, view_proj: Mat4) -> CameraUniforms {
        let light = scene.light;
        let (radius, normal, kind) = match light {
            Light::Area(d) if d.is_disk() => (d.radius, d.normal, LIGHT_DISK),
            Light::Area(d) => (
                (d.area() / std::f32::consts::PI).sqrt(),
                d.normal,
                LIGHT_POLYGON,
            ),
            Light::Line(_) => (0.0, Vec3::ZERO, LIGHT_LINE),
        };
        let mut corners = [[0.0; 4]; MAX_POLYGON_VERTICES / 2];
        let (mut count, mut area, mut u, mut w) = (0, 0.0, Vec3::ZERO, Vec3::ZERO);
        if let Some(a) = light.as_area() {
            (u, w) = a.basis();
            if let Outline2d::Polygon {
                corners: c,
                area: ar,
            } = Outline2d::of(a)
            {
                for (i, p) in c.iter().enumerate().take(MAX_POLYGON_VERTICES) {
                    corners[i / 2][2 * (i % 2)] = p.x;
                    corners[i / 2][2 * (i % 2) + 1] = p.y;
                }
                count = c.len().min(MAX_POLYGON_VERTICES) as u32;
                area = ar;
            }
        }
        CameraUniforms {
            light_corner_count: count,
            light_area: area,
            light_u: u.to_array(),
            light_w: w.to_array(),
            light_corners: corners,
            view_proj: view_proj.to_cols_array_2d(),
            eye: scene.camera.eye.to_array(),
            ambient: AMBIENT,
            light_center: light.center().to_array(),
            light_radius: radius,
            light_normal: normal.to_array(),
            light_intensity: light.intensity(),
            light_kind: kind,
            light_bound: light.as_area().map_or(0.0, |a| a.radius),
            _pad1: 0,
            _pad2: 0,
        }
    }
}

/// Near and far planes that hold the whole scene, given by its bounds, as seen from `eye`.
pub fn camera_range(eye: Vec3, (lo, hi): (Vec3, Vec3)) -> (f32, f32) {
    let mut far = 1.0f32;
    for corner in 0..8 {
        let pick = |bit: u32, a: f32, b: f32| if corner & bit == 0 { a } else { b };
        let p = Vec3::new(
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

/// Which draw of the surfaces a camera pipeline makes: a method's one, or one of the two of a
/// method drawn twice (`methods::CameraGroup::two_draws`): `fs_first` (every pixel, marking
/// some by a depth one float step farther) and `fs_refine` (depth test greater: the marked
/// pixels, their depth written back).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Draw {
    Only,
    First,
    Refine,
}

/// Group 0 of every method's camera pipeline, built once per device.
pub struct CameraPass {
    pub layout: wgpu::BindGroupLayout,
}

impl CameraPass {
    pub fn get(ctx: &GpuContext) -> Arc<CameraPass> {
        ctx.shared(|device| CameraPass {
            layout: device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("CameraPass::layout"),
                entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
            }),
        })
    }

    /// A method's camera pipeline for V(t) variant `vt` and a rectangle or polygon light
    /// (`polygon`: `POLYGON_LIGHT` of `shared/camera.wgsl`) or not: `module` (from
    /// `methods/NAME.wgsl`, which includes `shared/camera.wgsl`), with the method's own bindings
    /// as group 1, for the one draw of the surfaces or one of two ([`Draw`]).
    pub fn method_pipeline(
        &self,
        device: &wgpu::Device,
        label: &str,
        module: &wgpu::ShaderModule,
        method_layout: &wgpu::BindGroupLayout,
        (vt, polygon, colour_only): (VtVariant, bool, bool),
        draw: Draw,
    ) -> wgpu::RenderPipeline {
        let layout = pipeline_layout(
            device,
            "CameraPass::pipeline_layout",
            &[&self.layout, method_layout],
        );
        let constants = [
            ("VT_VARIANT", f64::from(vt.code())),
            ("POLYGON_LIGHT", f64::from(u8::from(polygon))),
        ];
        let options = wgpu::PipelineCompilationOptions {
            constants: &constants,
            ..Default::default()
        };
        // The shader writes all three; a pipeline without the last two drops them.
        let all = [
            opaque(COLOR_FORMAT),
            opaque(DATA_FORMAT),
            opaque(COST_FORMAT),
        ];
        let targets = if colour_only { &all[..1] } else { &all[..] };
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_main"),
                compilation_options: options.clone(),
                buffers: &[Some(SurfaceVertex::layout())],
            },
            // Surfaces are two-sided (open meshes, the ground seen from below).
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Greater),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(match draw {
                    Draw::Only => "fs_main",
                    Draw::First => "fs_first",
                    Draw::Refine => "fs_refine",
                }),
                compilation_options: options,
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

/// The camera pass's targets.
pub struct CameraTargets {
    pub width: u32,
    pub height: u32,
    pub color: Texture,
    /// `color` as its bytes (Rgba8Unorm): what the view pass copies and the lab shows.
    pub color_bytes: wgpu::TextureView,
    /// On a device without view formats (GL): the texture `color_bytes` views, an Rgba8Unorm
    /// copy of `color` made after each camera pass ([`CameraTargets::copy_bytes`]; a copy
    /// between formats that differ only in sRGB-ness moves the bytes as they are).
    pub bytes_copy: Option<Texture>,
    pub data: Texture,
    /// The method's work per pixel and the path it took ([`COST_FORMAT`]).
    pub cost: Texture,
    pub depth: Texture,
    /// Changes whenever the textures are made again (whoever binds them binds again).
    pub generation: u64,
}

impl CameraTargets {
    /// `bytes_view`: the device takes a second view format (`DownlevelFlags::VIEW_FORMATS`).
    pub fn new(device: &wgpu::Device, width: u32, height: u32, bytes_view: bool) -> CameraTargets {
        use wgpu::TextureUsages as U;
        let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
        let color = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("CameraTargets::color"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: COLOR_FORMAT,
            usage,
            view_formats: if bytes_view {
                &[COLOR_BYTES_FORMAT]
            } else {
                &[]
            },
        });
        let color_view = color.create_view(&wgpu::TextureViewDescriptor::default());
        let bytes_copy = (!bytes_view).then(|| {
            Texture::new(
                device,
                "CameraTargets::bytes_copy",
                (width, height),
                COLOR_BYTES_FORMAT,
                U::COPY_DST | U::TEXTURE_BINDING,
            )
        });
        let color_bytes = match &bytes_copy {
            Some(copy) => copy
                .texture
                .create_view(&wgpu::TextureViewDescriptor::default()),
            None => color.create_view(&wgpu::TextureViewDescriptor {
                label: Some("CameraTargets::color_bytes"),
                format: Some(COLOR_BYTES_FORMAT),
                ..Default::default()
            }),
        };
        CameraTargets {
            width,
            height,
            color: Texture {
                texture: color,
                view: color_view,
            },
            color_bytes,
            bytes_copy,
            data: Texture::new(
                device,
                "CameraTargets::data",
                (width, height),
                DATA_FORMAT,
                usage,
            ),
            cost: Texture::new(
                device,
                "CameraTargets::cost",
                (width, height),
                COST_FORMAT,
                usage,
            ),
            depth: Texture::new(
                device,
                "CameraTargets::depth",
                (width, height),
                DEPTH_FORMAT,
                usage,
            ),
            generation: next_generation(),
        }
    }
}

impl CameraTargets {
    /// Bring `bytes_copy` (if there is one) up to date with `color`.
    pub fn copy_bytes(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(copy) = &self.bytes_copy {
            encoder.copy_texture_to_texture(
                self.color.texture.as_image_copy(),
                copy.texture.as_image_copy(),
                self.color.texture.size(),
            );
        }
    }
}

/// A session's camera pass: its uniforms.
pub struct Camera {
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

impl Camera {
    pub fn new(ctx: &GpuContext) -> Camera {
        let pass = CameraPass::get(ctx);
        let uniforms = uniform_buffer::<CameraUniforms>(&ctx.device, "Camera::uniforms");
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Camera::bind_group"),
            layout: &pass.layout,
            entries: &[buffer_entry(0, &uniforms)],
        });
        Camera {
            uniforms,
            bind_group,
        }
    }

    /// Record the pass into `targets` with the method's pipeline and bindings.
    pub fn record(
        &self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        uniforms: &CameraUniforms,
        targets: &CameraTargets,
        method: CameraBindings<'_>,
        surfaces: &GpuScene,
    ) {
        ctx.queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
        let span = rec.span("camera_pass");
        // A colour-only frame is shown as its colour target is (frame::record_view), so it is
        // opaque: black where no surface is, as the view pass makes a full frame's final image.
        let background = if method.colour_only {
            wgpu::Color::BLACK
        } else {
            wgpu::Color::TRANSPARENT
        };
        let all = [
            cleared(&targets.color.view, background),
            cleared(&targets.data.view, wgpu::Color::TRANSPARENT),
            cleared(&targets.cost.view, wgpu::Color::TRANSPARENT),
        ];
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("Camera::pass"),
            color_attachments: if method.colour_only {
                &all[..1]
            } else {
                &all[..]
            },
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth.view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(method.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_bind_group(1, method.bind_group, &[]);
        surfaces.draw(&mut pass);
        if let Some(refine) = method.refine {
            pass.set_pipeline(refine);
            surfaces.draw(&mut pass);
        }
    }
}
