//! A method's camera pipelines ([`MethodPipeline`], shared by the device) and its group 1
//! ([`CameraGroup`]), bound again only when what it binds was made again.

use std::any::Any;
use std::sync::{Arc, OnceLock};

use crate::geometry::VtVariant;
use crate::render::passes::camera::{CameraBindings, CameraPass, Draw};
use crate::render::GpuContext;

/// A method's camera pipelines (one per V(t) variant, made on first use) and the layout of its
/// group 1, built once per device.
pub struct MethodPipeline {
    shader: &'static str,
    module: wgpu::ShaderModule,
    pub layout: wgpu::BindGroupLayout,
    /// By V(t) variant, light shape (disk or line, rectangle or polygon) and targets (all, or
    /// the colour only: [`FrameRequest::colour_only`](crate::render::FrameRequest)): the
    /// pipeline, and for a method drawn in two draws ([`CameraGroup::two_draws`]) the second's.
    pipelines: [OnceLock<(wgpu::RenderPipeline, Option<wgpu::RenderPipeline>)>; 16],
    two_draws: bool,
    camera: Arc<CameraPass>,
}

impl MethodPipeline {
    /// The pipelines of `shader` (`methods/NAME.wgsl`) whose group 1 has `entries`, drawn in
    /// two draws or one (`two_draws`, the same for every user of `shader`).
    pub fn get(
        ctx: &GpuContext,
        shader: &'static str,
        entries: &[wgpu::BindGroupLayoutEntry],
        two_draws: bool,
    ) -> Arc<MethodPipeline> {
        Self::get_from(ctx, shader, None, entries, two_draws)
    }

    /// [`MethodPipeline::get`] with the shader's expanded `source` given (a user's file)
    /// rather than read from the embedded shaders by name.
    fn get_from(
        ctx: &GpuContext,
        shader: &'static str,
        source: Option<&str>,
        entries: &[wgpu::BindGroupLayoutEntry],
        two_draws: bool,
    ) -> Arc<MethodPipeline> {
        ctx.shared_named(shader, |device| MethodPipeline {
            shader,
            module: match source {
                Some(source) => {
                    // Made again when the file changes (`render::shaders`, `user::reload`).
                    crate::render::shaders::note([shader]);
                    device.create_shader_module(wgpu::ShaderModuleDescriptor {
                        label: Some(shader),
                        source: wgpu::ShaderSource::Wgsl(source.into()),
                    })
                }
                None => crate::render::shader_module(device, shader),
            },
            layout: device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(shader),
                entries,
            }),
            pipelines: Default::default(),
            two_draws,
            camera: CameraPass::get(ctx),
        })
    }

    /// The pipeline for V(t) variant `vt` under a rectangle or polygon light (`polygon`) or
    /// not, writing the colour target only or every one, and the second draw's for a method
    /// drawn in two.
    pub fn pipeline(
        &self,
        device: &wgpu::Device,
        vt: VtVariant,
        polygon: bool,
        colour_only: bool,
    ) -> (&wgpu::RenderPipeline, Option<&wgpu::RenderPipeline>) {
        let slot = &self.pipelines
            [4 * (vt.code() as usize).min(3) + 2 * usize::from(polygon) + usize::from(colour_only)];
        let (first, second) = slot.get_or_init(|| {
            let make = |draw| {
                self.camera.method_pipeline(
                    device,
                    self.shader,
                    &self.module,
                    &self.layout,
                    (vt, polygon, colour_only),
                    draw,
                )
            };
            if self.two_draws {
                (make(Draw::First), Some(make(Draw::Refine)))
            } else {
                (make(Draw::Only), None)
            }
        });
        (first, second.as_ref())
    }
}

/// What every method's camera pass is made of: its pipelines ([`MethodPipeline`], shared by
/// the device) and its bind group (group 1), made again only when what it binds was made again.
///
/// [`CameraGroup::bind`] takes the entries and a key that says what they are made of — the
/// generation of each texture or buffer bound that can be replaced, as a named struct where
/// there are several (a bind group made from a comparable description, as rerun's
/// `BindGroupDesc`). A key equal to the last one keeps the group: no bind group per frame, and
/// none that binds a texture since replaced.
pub struct CameraGroup {
    pipeline: Arc<MethodPipeline>,
    /// The group and the key it was made for.
    bound: Option<(wgpu::BindGroup, Box<dyn Any + Send>)>,
}

impl CameraGroup {
    /// The camera pipelines of `shader` (`methods/NAME.wgsl`) whose group 1 has `layout`.
    pub fn new(
        ctx: &GpuContext,
        shader: &'static str,
        layout: &[wgpu::BindGroupLayoutEntry],
    ) -> CameraGroup {
        CameraGroup {
            pipeline: MethodPipeline::get(ctx, shader, layout, false),
            bound: None,
        }
    }

    /// The camera pipelines of a user's shader: `name` its key (`file:PATH`), `source` its
    /// expanded text.
    pub fn from_source(
        ctx: &GpuContext,
        name: &'static str,
        source: &str,
        layout: &[wgpu::BindGroupLayoutEntry],
    ) -> CameraGroup {
        CameraGroup {
            pipeline: MethodPipeline::get_from(ctx, name, Some(source), layout, false),
            bound: None,
        }
    }

    /// The same for a method whose V costs much at few pixels: the camera pass draws the
    /// surfaces twice. The first draw (`fs_first` of its shader) shades every pixel it can
    /// cheaply and marks the others by writing their depth one float step farther (reversed
    /// depth: smaller); the second (`fs_refine`), depth test greater, passes only there and
    /// writes the surface's depth back. A CPU rasteriser runs every branch of a shader for a
    /// whole group of pixels, but none of it for a group the depth test rejects: the expensive
    /// code runs only for groups with a marked pixel.
    pub fn two_draws(
        ctx: &GpuContext,
        shader: &'static str,
        layout: &[wgpu::BindGroupLayoutEntry],
    ) -> CameraGroup {
        CameraGroup {
            pipeline: MethodPipeline::get(ctx, shader, layout, true),
            bound: None,
        }
    }

    /// Make the bind group of `entries` unless the one held was made for `key`.
    pub fn bind<K: PartialEq + Send + 'static>(
        &mut self,
        device: &wgpu::Device,
        key: K,
        entries: &[wgpu::BindGroupEntry<'_>],
    ) {
        let current = self.bound.as_ref().and_then(|(_, k)| k.downcast_ref::<K>());
        if current == Some(&key) {
            return;
        }
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.pipeline.shader),
            layout: &self.pipeline.layout,
            entries,
        });
        self.bound = Some((group, Box::new(key)));
    }

    /// The pipeline for V(t) variant `vt` and the light's shape, and the group; `None` before
    /// the first [`CameraGroup::bind`] (a method returns its group from
    /// [`MethodState::prepare`](super::MethodState::prepare) once it has bound it).
    pub fn bindings(
        &self,
        device: &wgpu::Device,
        vt: VtVariant,
        polygon: bool,
        colour_only: bool,
    ) -> Option<CameraBindings<'_>> {
        self.bound.as_ref().map(|(group, _)| {
            let (pipeline, refine) = self.pipeline.pipeline(device, vt, polygon, colour_only);
            CameraBindings {
                pipeline,
                refine,
                bind_group: group,
                colour_only,
            }
        })
    }
}

/// Group 1 of a method whose V per pixel is a texture: the screen passes' visibility
/// (`shaders/shared/screen_v.wgsl`) or the reference's V handed in (`methods/reference.wgsl`).
pub fn v_texture_entries() -> [wgpu::BindGroupLayoutEntry; 1] {
    [crate::render::texture_entry(
        0,
        wgpu::ShaderStages::FRAGMENT,
        wgpu::TextureViewDimension::D2,
    )]
}
