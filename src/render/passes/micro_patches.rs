//! What `bitmask` reads of the centre's shadow map besides `|cx_o|`
//! (`shaders/passes/micro_patches.wgsl`), made once per light or caster move:
//! - the **patch corners**: per texel the distance at each of its four corners, gap-filled — the
//!   mean of the texels meeting there that lie on the texel's surface
//!   (`geometry::bitmask::corner_distance`), so neighbouring micro-patches share corners;
//! - a **pyramid**: level `k` holds, per `2^(k+1)` × `2^(k+1)` texels of the map, the lowest and
//!   highest height above the light's plane, the largest step between neighbouring texels'
//!   distances and the farthest distance — the camera pass skips a node nothing of which lies
//!   above the receiver, and back-projects a node wholly in front of it and of one surface as one
//!   patch.
//!
//! Both are `Rgba32Float` (one pipeline, one layout); the pyramid's first level is a power of two
//! wide (`next_power_of_two(⌈size / 2⌉)`), so each level is exactly half the one below.

use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, cleared, fullscreen_pass, texture_entry, uniform_entry, view_entry, GpuContext,
    Texture,
};

use super::next_generation;
use super::shadow_map::MapFrame;

pub const PATCH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// `PatchUniforms` of `shaders/passes/micro_patches.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PatchUniforms {
    pub inv_light_view_proj: [[f32; 4]; 4],
    pub light_center: [f32; 4],
    pub light_normal: [f32; 4],
    pub mode: u32,
    pub gap_fill: u32,
    pub size: u32,
    /// Where the level read and the level drawn start in their atlases (x, in texels).
    pub source_offset: u32,
    pub target_offset: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

const _: () = assert!(std::mem::size_of::<PatchUniforms>() == 128);

/// Where pyramid level `k` starts in its atlas (x, in texels): the levels side by side, each
/// half as wide as the one before, `base` the first's width.
pub fn level_offset(base: u32, k: u32) -> u32 {
    2 * base - 2 * (base >> k)
}

struct PatchPipeline {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

/// The corners and the pyramid, and a number that changes whenever they are made again.
pub struct PatchMaps {
    pub size: u32,
    pub corners: Texture,
    /// The pyramid in two atlases of one mip level each, `2 base × base` texels: level k at x
    /// [`level_offset`] of the first for even k, of the second for odd k. Each level is drawn
    /// from the one below, so neighbouring levels live in different textures; and no level is a
    /// mip level: wgpu's GL backend makes a texture's views by setting its base and top levels,
    /// and one texture bound at two levels at once reads the wrong one.
    pub pyramid: [Texture; 2],
    /// Levels of the pyramid.
    pub levels: u32,
    /// One uniform buffer a draw (the corners, then each level).
    uniforms: Vec<wgpu::Buffer>,
    pub generation: u64,
}

/// One draw of the pass: what it reads and writes, and for a pyramid level the square of its
/// atlas it covers (x, side, whether it clears the atlas first).
struct Draw<'a> {
    uniforms: PatchUniforms,
    source: &'a wgpu::TextureView,
    target: &'a wgpu::TextureView,
    square: Option<(u32, u32, bool)>,
}

#[derive(Default)]
pub struct MicroPatches {
    maps: Option<PatchMaps>,
}

/// The pyramid's first level's texels per side for a `size`² map, and its levels (down to 1²).
pub fn pyramid_shape(size: u32) -> (u32, u32) {
    let base = size.div_ceil(2).max(1).next_power_of_two();
    (base, base.trailing_zeros() + 1)
}

impl MicroPatches {
    pub fn maps(&self) -> Option<&PatchMaps> {
        self.maps.as_ref()
    }

    /// Make the corners (gap-filled or not) and the pyramid of `distance`, the centre's `size`²
    /// distance map seen as `frame` says.
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        distance: &wgpu::TextureView,
        size: u32,
        gap_fill: bool,
        frame: &MapFrame,
    ) {
        let pipe = ctx.shared(|device| {
            let (pipeline, layout) = fullscreen_pass(
                device,
                "MicroPatches",
                "passes/micro_patches.wgsl",
                &[
                    uniform_entry(0, wgpu::ShaderStages::FRAGMENT),
                    texture_entry(
                        1,
                        wgpu::ShaderStages::FRAGMENT,
                        wgpu::TextureViewDimension::D2,
                    ),
                ],
                PATCH_FORMAT,
            );
            PatchPipeline { pipeline, layout }
        });
        if self.maps.as_ref().is_none_or(|m| m.size != size) {
            self.maps = Some(PatchMaps::new(ctx, size));
        }
        let Some(m) = &mut self.maps else { return };
        m.generation = next_generation();
        let (base, levels) = pyramid_shape(size);
        let uniforms = |mode: u32, gap_fill: bool, size: u32, offsets: (u32, u32)| PatchUniforms {
            inv_light_view_proj: frame.inv_light_view_proj.to_cols_array_2d(),
            light_center: frame.center.extend(0.0).to_array(),
            light_normal: frame.normal.extend(0.0).to_array(),
            mode,
            gap_fill: gap_fill as u32,
            size,
            source_offset: offsets.0,
            target_offset: offsets.1,
            _pad0: 0,
            _pad1: 0,
            _pad2: 0,
        };
        // Draw i: its uniforms, its source, its target, and where in the target (the corners: all
        // of it, cleared; a level: its square of its atlas, the atlas cleared by its first level).
        let atlas = |k: u32| &m.pyramid[(k % 2) as usize].view;
        let mut draws: Vec<Draw> = vec![
            Draw {
                uniforms: uniforms(0, gap_fill, size, (0, 0)),
                source: distance,
                target: &m.corners.view,
                square: None,
            },
            Draw {
                uniforms: uniforms(1, false, size, (0, 0)),
                source: distance,
                target: atlas(0),
                square: Some((0, base, true)),
            },
        ];
        for k in 1..levels {
            let at = level_offset(base, k);
            draws.push(Draw {
                uniforms: uniforms(2, false, base >> (k - 1), (level_offset(base, k - 1), at)),
                source: atlas(k - 1),
                target: atlas(k),
                square: Some((at, base >> k, k == 1)),
            });
        }
        let span = rec.span("bitmask_patches");
        let last = draws.len() - 1;
        for (i, d) in draws.iter().enumerate() {
            ctx.queue
                .write_buffer(&m.uniforms[i], 0, bytemuck::bytes_of(&d.uniforms));
            let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("MicroPatches::group"),
                layout: &pipe.layout,
                entries: &[buffer_entry(0, &m.uniforms[i]), view_entry(1, d.source)],
            });
            let clear = d.square.is_none_or(|(_, _, first)| first);
            let attachment = if clear {
                cleared(d.target, wgpu::Color::TRANSPARENT)
            } else {
                Some(wgpu::RenderPassColorAttachment {
                    view: d.target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let mut pass = rec.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("MicroPatches::pass"),
                color_attachments: &[attachment],
                depth_stencil_attachment: None,
                timestamp_writes: span.writes(rec.timer, i == 0, i == last),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipe.pipeline);
            pass.set_bind_group(0, &group, &[]);
            if let Some((x, side, _)) = d.square {
                pass.set_viewport(x as f32, 0.0, side as f32, side as f32, 0.0, 1.0);
                pass.set_scissor_rect(x, 0, side, side);
            }
            pass.draw(0..3, 0..1);
        }
    }
}

impl PatchMaps {
    fn new(ctx: &GpuContext, size: u32) -> PatchMaps {
        use wgpu::TextureUsages as U;
        let (base, levels) = pyramid_shape(size);
        let corners = Texture::new(
            &ctx.device,
            "MicroPatches::corners",
            (size, size),
            PATCH_FORMAT,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
        );
        let pyramid = [0, 1].map(|_| {
            Texture::new(
                &ctx.device,
                "MicroPatches::pyramid",
                (2 * base, base),
                PATCH_FORMAT,
                U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
            )
        });
        let uniforms = (0..=levels)
            .map(|_| {
                crate::render::uniform_buffer::<PatchUniforms>(
                    &ctx.device,
                    "MicroPatches::uniforms",
                )
            })
            .collect();
        PatchMaps {
            size,
            corners,
            pyramid,
            levels,
            uniforms,
            generation: 0,
        }
    }
}
