//! What the methods that only filter the centre's shadow map (`hard`, `pcf`, `pcss`) share: the
//! map itself is the session's ([`super::SharedMaps`]), made once per light or caster move; each
//! method has its own camera shader, the map's `ShadowUniforms` with its knobs, and maybe one
//! uniform buffer of its own (binding 2).

use super::{CameraGroup, FrameInputs, LightMaps, MethodState, Prepare, SharedMaps};
use crate::render::passes::shadow_map::{lookup_entries, ShadowUniforms};
use crate::render::{
    buffer_entry, uniform_buffer, uniform_entry, view_entry, GpuContext, RenderError,
};

/// A method's own uniform buffer: its size, and what it holds.
pub type Extra = (u64, fn() -> Vec<u8>);

/// How one of these methods differs from the others.
pub struct Flavor {
    /// Its camera shader, `methods/NAME.wgsl`.
    pub shader: &'static str,
    /// Its numbers for `ShadowUniforms::knobs`, from the frame.
    pub knobs: fn(&FrameInputs<'_>) -> [f32; 4],
    /// Its own uniform buffer (binding 2), if it has one.
    pub extra: Option<Extra>,
}

pub struct OnShadowMap {
    flavor: &'static Flavor,
    /// Bound for the shadow map's generation.
    camera: CameraGroup,
    uniforms: wgpu::Buffer,
    extra: Option<wgpu::Buffer>,
}

impl OnShadowMap {
    pub fn new(ctx: &GpuContext, flavor: &'static Flavor) -> OnShadowMap {
        let mut entries = lookup_entries().to_vec();
        if flavor.extra.is_some() {
            entries.push(uniform_entry(2, wgpu::ShaderStages::FRAGMENT));
        }
        let camera = CameraGroup::new(ctx, flavor.shader, &entries);
        let extra = flavor.extra.map(|(size, contents)| {
            let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("OnShadowMap::extra"),
                size,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            ctx.queue.write_buffer(&buffer, 0, &contents());
            buffer
        });
        OnShadowMap {
            flavor,
            camera,
            uniforms: uniform_buffer::<ShadowUniforms>(&ctx.device, "OnShadowMap::uniforms"),
            extra,
        }
    }
}

impl MethodState for OnShadowMap {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        let map = shared.shadow_map.update(inputs, rec)?;
        let uniforms =
            ShadowUniforms::new(inputs.light_view, map.size, (self.flavor.knobs)(inputs));
        inputs
            .ctx
            .queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        let mut entries = vec![
            buffer_entry(0, &self.uniforms),
            view_entry(1, &map.distance.view),
        ];
        if let Some(extra) = &self.extra {
            entries.push(buffer_entry(2, extra));
        }
        self.camera
            .bind(&inputs.ctx.device, map.generation, &entries);
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        shared.shadow_map.light_maps()
    }
}
