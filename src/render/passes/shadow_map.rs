//! The shadow map from the light centre (`shaders/passes/shadow_map.wgsl`): `|cx_o|`, the
//! Euclidean distance to the nearest surface, per texel of the light view, `size`² texels of
//! R32Float, and its depth (kept: the D-buffer's penumbra channel is drawn over it). The hard
//! shadow's map, filtered by PCF and PCSS, and the D-buffer's first channel: made once per light
//! or caster move and shared by every method that reads it.

use std::sync::Arc;

use super::next_generation;
use crate::geometry::light_view::LightView;
use crate::render::gpu_scene::GpuScene;
use crate::render::light_maps::{Channel, Empty, LightMaps};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, depth_attachment, depth_test, opaque, pipeline_layout, red,
    render_pipeline, require, shader_module, uniform_buffer, uniform_entry, GpuContext,
    PipelineSpec, RenderError, SurfaceVertex, Texture,
};
use crate::scene::{Light, Scene};

pub const DISTANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// `|cx_o|` where no surface is: far beyond any scene (inf is not a clear value everywhere).
pub const NO_SURFACE: f64 = 3.0e38;

/// What the map is made from: the scene's surfaces seen from the light, at one revision of the
/// light and casters. A method hands in its frame's inputs (`FrameInputs` converts).
#[derive(Clone, Copy)]
pub struct MapInputs<'a> {
    pub ctx: &'a GpuContext,
    pub scene: &'a Scene,
    pub surfaces: &'a GpuScene,
    pub light_view: &'a LightView,
    /// Bumped whenever the light or a caster changed: a map made for an older one is stale.
    pub revision: u64,
    /// The map is this many texels square.
    pub size: u32,
}

/// `LightUniforms` of `shaders/shared/light.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub center: [f32; 3],
    pub inv_far: f32,
    pub normal: [f32; 3],
    /// The frame tag the D-buffer's volume channels are drawn with ([`FrameTag`]); 0 for every
    /// other pass.
    ///
    /// [`FrameTag`]: crate::render::frame_tag::FrameTag
    pub tag: u32,
}

const _: () = assert!(std::mem::size_of::<LightUniforms>() == 96);

impl LightUniforms {
    /// From the light's centre (a line's midpoint); `normal` is a disk's, or for a line light
    /// (which has none) the view's axis.
    pub fn new(light: &Light, view: &LightView) -> LightUniforms {
        let normal = match light {
            Light::Area(d) => d.normal,
            Light::Line(_) => view.view.inverse().transform_vector3(glam::Vec3::NEG_Z),
        };
        LightUniforms {
            view_proj: view.view_projection().to_cols_array_2d(),
            center: light.center().to_array(),
            inv_far: 1.0 / view.far,
            normal: normal.to_array(),
            tag: 0,
        }
    }
}

/// The pipeline, built once per device.
pub struct ShadowMapPass {
    pipeline: wgpu::RenderPipeline,
    /// Group 0: the light uniforms (the D-buffer's volume passes use the same layout).
    pub layout: wgpu::BindGroupLayout,
}

impl ShadowMapPass {
    pub fn get(ctx: &GpuContext) -> Arc<ShadowMapPass> {
        ctx.shared(|device| {
            let module = shader_module(device, "passes/shadow_map.wgsl");
            let layout = light_layout(device, "ShadowMapPass::layout");
            let pipeline = render_pipeline(
                device,
                &PipelineSpec {
                    label: "ShadowMapPass::pipeline",
                    module: &module,
                    layout: &pipeline_layout(device, "ShadowMapPass::pipeline_layout", &[&layout]),
                    vs: "vs_main",
                    fs: Some("fs_main"),
                    buffers: &[Some(SurfaceVertex::layout())],
                    targets: &[opaque(DISTANCE_FORMAT)],
                    // Surfaces are two-sided (open meshes, the ground seen from below).
                    cull: None,
                    depth: depth_test(wgpu::CompareFunction::Less),
                },
            );
            ShadowMapPass { pipeline, layout }
        })
    }
}

/// The bind group layout of the light uniforms.
pub fn light_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
    })
}

/// The map's textures.
pub struct ShadowMapTargets {
    pub size: u32,
    pub distance: Texture,
    pub depth: Texture,
    /// Changes whenever the textures are made again.
    pub generation: u64,
}

/// A session's shadow map: what it holds and for which revision of the scene.
pub struct ShadowMap {
    pass: Arc<ShadowMapPass>,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    targets: Option<ShadowMapTargets>,
    made_for: Option<u64>,
    /// The depth no longer holds the surfaces' alone (the D-buffer's penumbra pass drew into it).
    depth_used: bool,
    /// The light view it was last made with.
    view_proj: glam::Mat4,
}

/// The map's one channel, for the views and the inspector.
pub const CHANNELS: &[Channel] = &[Channel::new("|cx_o|", 0, 0, Empty::Far)];

impl ShadowMap {
    pub fn new(ctx: &GpuContext) -> ShadowMap {
        let pass = ShadowMapPass::get(ctx);
        let uniforms = uniform_buffer::<LightUniforms>(&ctx.device, "ShadowMap::uniforms");
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ShadowMap::bind_group"),
            layout: &pass.layout,
            entries: &[buffer_entry(0, &uniforms)],
        });
        ShadowMap {
            pass,
            uniforms,
            bind_group,
            targets: None,
            made_for: None,
            depth_used: false,
            view_proj: glam::Mat4::IDENTITY,
        }
    }

    pub fn targets(&self) -> Option<&ShadowMapTargets> {
        self.targets.as_ref()
    }

    /// The map as light-space maps, once it has been made.
    pub fn light_maps(&self) -> Option<LightMaps<'_>> {
        let t = self.targets.as_ref().filter(|_| self.made_for.is_some())?;
        Some(LightMaps::single(
            t.size,
            self.view_proj,
            &t.distance,
            CHANNELS,
            t.generation,
        ))
    }

    /// The next request remakes the map.
    pub fn invalidate(&mut self) {
        self.made_for = None;
    }

    /// Make the map hold `inputs.revision` at `inputs.size`, recording its pass only when it
    /// does not yet; its targets.
    pub fn update<'a>(
        &mut self,
        inputs: impl Into<MapInputs<'a>>,
        rec: &mut Recorder<'_>,
    ) -> Result<&ShadowMapTargets, RenderError> {
        self.record(&inputs.into(), rec);
        self.made()
    }

    /// Its targets, or the error that says they were not made.
    pub fn made(&self) -> Result<&ShadowMapTargets, RenderError> {
        require(self.targets(), "the shadow map was not made")
    }

    fn record(&mut self, inputs: &MapInputs<'_>, rec: &mut Recorder<'_>) {
        let size = inputs.size;
        if self.targets.as_ref().is_none_or(|t| t.size != size) {
            use wgpu::TextureUsages as U;
            let device = &inputs.ctx.device;
            self.targets = Some(ShadowMapTargets {
                size,
                distance: Texture::new(
                    device,
                    "ShadowMapTargets::distance",
                    (size, size),
                    DISTANCE_FORMAT,
                    U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
                ),
                depth: Texture::new(
                    device,
                    "ShadowMapTargets::depth",
                    (size, size),
                    DEPTH_FORMAT,
                    U::RENDER_ATTACHMENT,
                ),
                generation: next_generation(),
            });
            self.made_for = None;
        }
        if self.made_for == Some(inputs.revision) {
            return;
        }
        let Some(t) = &self.targets else { return };
        self.view_proj = inputs.light_view.view_projection();
        inputs.ctx.queue.write_buffer(
            &self.uniforms,
            0,
            bytemuck::bytes_of(&LightUniforms::new(&inputs.scene.light, inputs.light_view)),
        );
        let span = rec.span("shadow_map");
        let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("ShadowMap::pass"),
            color_attachments: &[cleared(&t.distance.view, red(NO_SURFACE))],
            depth_stencil_attachment: depth_attachment(
                &t.depth.view,
                wgpu::LoadOp::Clear(1.0),
                true,
            ),
            timestamp_writes: span.writes(rec.timer, true, true),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pass.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        inputs.surfaces.draw(&mut pass);
        drop(pass);
        self.made_for = Some(inputs.revision);
        self.depth_used = false;
    }

    /// The map's depth as the surfaces left it, for a pass that draws into it next (the map is
    /// made again first if an earlier such pass used it up).
    pub fn depth_for_drawing<'a>(
        &mut self,
        inputs: impl Into<MapInputs<'a>>,
        rec: &mut Recorder<'_>,
    ) -> Result<&Texture, RenderError> {
        if self.depth_used {
            self.made_for = None;
        }
        self.record(&inputs.into(), rec);
        self.depth_used = true;
        Ok(&self.made()?.depth)
    }
}

/// Bias of the hidden-from-centre test of every method that reads the map: relative to `|cx|`,
/// plus the slope one texel spans times the tangent of the incidence angle, times this factor.
pub const BIAS_CONSTANT: f32 = 2e-4;
pub const BIAS_SLOPE: f32 = 1.5;

/// `ShadowUniforms` of `shaders/shared/shadow_lookup.wgsl`: how the camera pass of a method
/// built on the map finds a point's texel and tests it. Only the map's own numbers: a method's
/// parameters are its own uniform struct (`params` of its shader, declared in its module).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowUniforms {
    pub light_view_proj: [[f32; 4]; 4],
    pub inv_light_view_proj: [[f32; 4]; 4],
    pub size: f32,
    pub texel_slope: f32,
    pub bias_constant: f32,
    pub bias_slope: f32,
}

const _: () = assert!(std::mem::size_of::<ShadowUniforms>() == 144);

impl ShadowUniforms {
    pub fn new(view: &LightView, size: u32) -> ShadowUniforms {
        let vp = view.view_projection();
        ShadowUniforms {
            light_view_proj: vp.to_cols_array_2d(),
            inv_light_view_proj: vp.inverse().to_cols_array_2d(),
            size: size as f32,
            texel_slope: view.texel_slope(size),
            bias_constant: BIAS_CONSTANT,
            bias_slope: BIAS_SLOPE,
        }
    }
}

/// Where a method built on the map binds its own parameters in group 1 (`params` of its shader,
/// a uniform): after the lookup's two. Its other bindings follow from 3 on.
pub const PARAMS_BINDING: u32 = 2;

/// The first two entries of the group 1 of a method built on the map (its `ShadowUniforms` and
/// the map): `shared/shadow_lookup.wgsl` declares them; the method adds its own after them (its
/// `params` at [`PARAMS_BINDING`]).
pub fn lookup_entries() -> [wgpu::BindGroupLayoutEntry; 2] {
    [
        uniform_entry(0, wgpu::ShaderStages::FRAGMENT),
        crate::render::texture_entry(
            1,
            wgpu::ShaderStages::FRAGMENT,
            wgpu::TextureViewDimension::D2,
        ),
    ]
}

/// Where the map looks from, for a pass that turns its distances into depths of its own: the
/// light view's clip space back to the world, and the light's centre and normal (the normal is
/// zero for a line light, which has none: such a pass keeps distances).
#[derive(Clone, Copy, Debug)]
pub struct MapFrame {
    pub inv_light_view_proj: glam::Mat4,
    pub center: glam::Vec3,
    pub normal: glam::Vec3,
}

impl MapFrame {
    pub fn new(view: &LightView, light: &crate::scene::Light) -> MapFrame {
        MapFrame {
            inv_light_view_proj: view.view_projection().inverse(),
            center: light.center(),
            normal: light.as_area().map_or(glam::Vec3::ZERO, |a| a.normal),
        }
    }
}
