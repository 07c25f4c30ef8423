//! `dbuffer` (Jakobsen et al. 2004, with the corrections in docs/method/dbuffer.md) and `dbuffer-center` (its silhouettes and
//! volumes taken from the light centre only: the penumbra-wedge approximation Jakobsen et al. 2004, Fig. 1
//! criticises).
//!
//! Per light or caster move: the geometry stage (`geometry::PreparedCasters::build`: classes,
//! silhouettes, volumes), the volumes uploaded, then the light pass — the session's shadow map
//! (`|cx_o|`) and the volume channels (`passes::dbuffer_volumes`). Per frame: the camera pass
//! with `shaders/methods/dbuffer.wgsl`. CPU twin: `geometry::DBufferTwin`.

use std::time::Instant;

use super::{
    require, CameraGroup, Channel, Cost, Empty, FrameInputs, LightMaps, MethodSpec, MethodState,
    Prepare, Quality, SharedMaps, Switch,
};
use crate::geometry::volume_vertices::{
    drawn_volumes, reach_below, CORNERS_PER_ROW, MAX_CORNERS, TEXELS_PER_CORNER,
};
use crate::geometry::{SceneGeometry, VolumeParams};
use crate::render::frame_tag::FrameTag;
use crate::render::gpu_scene::VertexChunks;
use crate::render::passes::dbuffer_volumes::{CasterVolumes, DBufferVolumes, VolumeLayout};
use crate::render::passes::shadow_map::{lookup_entries, LightUniforms, ShadowUniforms};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, texture_entry, uniform_buffer, view_entry, GpuContext, RenderError,
};
use crate::scene::AreaLight;

/// Both D-buffers' cost view: the texels they read, and which answer won.
const DBUFFER_COST: Cost = Cost::counted("D-buffer texels read").paths(&[
    "a chord's V(t)",
    "a closing fan's corner wedge",
    "the receiver's horizon",
    "outside the map: lit",
    "behind the light or facing away: dark",
]);

pub static DBUFFER: MethodSpec =
    MethodSpec::new("dbuffer", SHADER, |ctx| Box::new(DBuffer::new(ctx, false)))
        .adapter(NEEDS)
        .about("D-buffer soft shadows (Jakobsen et al. 2004)")
        .knobs(&[&HORIZON.0, &CORNERS.0])
        .cost(DBUFFER_COST)
        .lights(super::AREA_LIGHTS)
        .sweep(&[Quality::MapSize], &[&[512], &[1024], &[2048]]); // volumes from a planar light's outline

pub static DBUFFER_CENTER: MethodSpec = MethodSpec::new("dbuffer-center", SHADER, |ctx| {
    Box::new(DBuffer::new(ctx, true))
})
.adapter(NEEDS)
.about("D-buffer with silhouettes from the light centre only")
.knobs(&[&HORIZON.0, &CORNERS.0])
.cost(DBUFFER_COST)
.lights(super::AREA_LIGHTS)
.sweep(&[Quality::MapSize], &[&[512], &[1024], &[2048]]); // volumes from a planar light's outline

/// `--dbuffer-corners`: V exact behind a closing fan from the fan's corner (`shadow.knobs.y`).
pub static CORNERS: Switch = Switch::new(
    "dbuffer-corners",
    "dbuffer, dbuffer-center: 1 = V exact behind a closing fan is the light less the caster's \
     corner seen from the point (a wedge); 0 = one chord there too, as the paper has it",
    true,
);

/// `--dbuffer-horizon`: clip the light by the receiver's own plane (`shadow.knobs.x` of
/// `shaders/methods/dbuffer.wgsl`; the twin's [`DBufferTwin::horizon`]).
///
/// [`DBufferTwin::horizon`]: crate::geometry::DBufferTwin::horizon
pub static HORIZON: Switch = Switch::new(
    "dbuffer-horizon",
    "dbuffer, dbuffer-center: 1 = a receiver gets at most the part of the light in front of \
     its own plane (a caster's face whose plane cuts the light: its terminator); 0 = the \
     paper's lookup alone (lit there, no volume reaches a silhouette's own faces)",
    true,
);

const SHADER: &str = "methods/dbuffer.wgsl";

/// The centre's shadow map (`|cx_o|`) and the volume channels: distance, `|cx_s|` and the lit
/// side per texel (`passes::dbuffer_volumes::VolumeLayout`: `Rg32Float`, or `Rgba32Float` with
/// the side for `V exact`).
const NEEDS: super::AdapterNeeds = super::AdapterNeeds::formats(&[
    super::SHADOW_MAP[0],
    super::SHADOW_MAP[1],
    crate::render::adapter::FormatNeed::new(
        crate::render::adapter::Usage::Render,
        &[VolumeLayout::Distances.format()],
    ),
    crate::render::adapter::FormatNeed::new(
        crate::render::adapter::Usage::Render,
        &[VolumeLayout::WithSides.format()],
    ),
]);

/// The D-buffer's channels, in `dbuffer.exr` order (R, G, B, A): textures 0 (`|cx_o|`), 1
/// (umbra: `|cx_uv|`, `|cx_s|`), 2 (penumbra: `|cx_pv|`, `|cx_s|`). `|cx_s|` is the umbra's
/// where it has one.
pub const CHANNELS: &[Channel] = &[
    Channel {
        name: "|cx_o|",
        texture: 0,
        component: 0,
        empty: Empty::Far,
        or: None,
    },
    Channel {
        name: "|cx_uv|",
        texture: 1,
        component: 0,
        empty: Empty::NonPositive,
        or: None,
    },
    Channel {
        name: "|cx_pv|",
        texture: 2,
        component: 0,
        empty: Empty::NonPositive,
        or: None,
    },
    Channel {
        name: "|cx_s|",
        texture: 1,
        component: 1,
        empty: Empty::NonPositive,
        or: Some((2, 1)),
    },
];

pub struct DBuffer {
    center_silhouettes: bool,
    /// Bound for the generations of the shadow map and the volume channels ([`Bound`]).
    camera: CameraGroup,
    uniforms: wgpu::Buffer,
    /// The geometry, and the revision it was built for.
    geometry: Option<(SceneGeometry, u64)>,
    builds: u64,
    geometry_ms: f64,
    casters: Vec<CasterVolumes>,
    penumbra: VertexChunks,
    volumes: DBufferVolumes,
    /// The closing fans' corners over all casters, `TEXELS_PER_CORNER` `Rgba32Float` texels
    /// each (apex, the two edges' far ends, each edge's faces' normals, the two extrusion
    /// points), `CORNERS_PER_ROW` to a row: `corners` of
    /// `shaders/methods/dbuffer.wgsl`, named by the fans' markers
    /// (`volume_vertices::corner_marker`). A texture, not a storage buffer: the weakest devices
    /// have none in fragment shaders.
    corners: wgpu::TextureView,
    /// What the volume channels hold.
    made_for: Option<Made>,
    view_proj: glam::Mat4,
}

/// What the volume channels were drawn for.
#[derive(Clone, Copy, PartialEq)]
struct Made {
    revision: u64,
    map_size: u32,
    /// The shadow map's generation (the penumbra channel is drawn over its depth).
    map: u64,
    layout: VolumeLayout,
}

/// What the camera bind group binds: the shadow map's and the volume channels' generations, and
/// the geometry build of the corners.
#[derive(PartialEq)]
struct Bound {
    map: u64,
    volumes: u64,
    /// The geometry build the corners' texture was made for.
    corners: u64,
}

impl DBuffer {
    pub fn new(ctx: &GpuContext, center_silhouettes: bool) -> DBuffer {
        let mut entries = lookup_entries().to_vec();
        entries.extend([
            texture_entry(
                2,
                wgpu::ShaderStages::FRAGMENT,
                wgpu::TextureViewDimension::D2,
            ),
            texture_entry(
                3,
                wgpu::ShaderStages::FRAGMENT,
                wgpu::TextureViewDimension::D2,
            ),
            texture_entry(
                4,
                wgpu::ShaderStages::FRAGMENT,
                wgpu::TextureViewDimension::D2,
            ),
        ]);
        DBuffer {
            center_silhouettes,
            camera: CameraGroup::new(ctx, SHADER, &entries),
            uniforms: uniform_buffer::<ShadowUniforms>(&ctx.device, "DBuffer::uniforms"),
            geometry: None,
            builds: 0,
            geometry_ms: 0.0,
            casters: Vec::new(),
            penumbra: VertexChunks::empty(),
            volumes: DBufferVolumes::new(ctx),
            corners: corner_texture(ctx, &[]),
            made_for: None,
            view_proj: glam::Mat4::IDENTITY,
        }
    }

    /// The geometry stage and the volumes' upload, when the light or a caster moved.
    fn update_geometry(&mut self, inputs: &FrameInputs<'_>, light: AreaLight) {
        if self
            .geometry
            .as_ref()
            .is_some_and(|(_, r)| *r == inputs.revision)
        {
            return;
        }
        let params = VolumeParams {
            center_silhouettes: self.center_silhouettes,
            ..VolumeParams::for_scene(inputs.scene)
        };
        let t = Instant::now();
        let geometry = inputs.prepared().build(&light, &params);
        self.geometry_ms = t.elapsed().as_secs_f64() * 1e3;
        self.builds += 1;
        let device = &inputs.ctx.device;
        let reach = reach_below(&light, inputs.surfaces.bounds);
        let drawn = drawn_volumes(&geometry, &light, inputs.light_view, Some(reach));
        self.casters = drawn
            .umbrae
            .iter()
            .map(|(umbra, rect)| CasterVolumes {
                rect: *rect,
                umbra: VertexChunks::new(device, "DBuffer::umbra", umbra),
            })
            .collect();
        let penumbra = drawn.penumbra;
        self.penumbra = VertexChunks::new(device, "DBuffer::penumbra", &penumbra);
        let corners: Vec<[f32; 4]> = geometry
            .casters
            .iter()
            .flat_map(|g| &g.volumes.corners)
            // No fan past MAX_CORNERS carries a marker (it keeps the chord): the texture stops
            // there, within the smallest texture a device allows.
            .take(MAX_CORNERS)
            .flat_map(|c| {
                let [[n0, n1], [n2, n3]] = c.normals;
                let [s0, s1] = c.supports;
                [c.apex, c.ends[0], c.ends[1], n0, n1, n2, n3, s0, s1]
                    .map(|p| p.extend(0.0).to_array())
            })
            .collect();
        self.corners = corner_texture(inputs.ctx, &corners);
        self.geometry = Some((geometry, inputs.revision));
        self.made_for = None;
    }

    /// The geometry stage (face classes, silhouettes, volumes) for the current light, when the
    /// light or a caster moved.
    pub fn geometry_stage(&mut self, inputs: &FrameInputs<'_>) -> Result<(), RenderError> {
        let light = *inputs.area(if self.center_silhouettes {
            DBUFFER_CENTER.name
        } else {
            DBUFFER.name
        })?;
        self.update_geometry(inputs, light);
        Ok(())
    }

    /// The light pass after [`DBuffer::geometry_stage`]: the shadow map and the volume
    /// channels, when something moved since they were made.
    pub fn light_pass(
        &mut self,
        inputs: &FrameInputs<'_>,
        shared: &mut SharedMaps,
        rec: &mut Recorder<'_>,
    ) -> Result<(), RenderError> {
        let map = shared.shadow_map.update(inputs, rec)?;
        let key = Made {
            revision: inputs.revision,
            map_size: map.size,
            map: map.generation,
            layout: VolumeLayout::for_vt(inputs.vt),
        };
        if self.made_for != Some(key) {
            let depth = shared.shadow_map.depth_for_drawing(inputs, rec)?;
            self.volumes.record(
                inputs.ctx,
                rec,
                &LightUniforms::new(&inputs.scene.light, inputs.light_view),
                depth,
                &self.casters,
                &self.penumbra,
                key.layout,
            );
            self.made_for = Some(key);
            self.view_proj = inputs.light_view.view_projection();
        }
        Ok(())
    }
}

/// The corners' texture: `TEXELS_PER_CORNER × CORNERS_PER_ROW` texels wide (less for fewer corners), a row per
/// `CORNERS_PER_ROW` corners; one zero corner where there are none (a binding is never empty).
fn corner_texture(ctx: &GpuContext, corners: &[[f32; 4]]) -> wgpu::TextureView {
    use wgpu::util::DeviceExt;
    let texels_per_row = TEXELS_PER_CORNER * CORNERS_PER_ROW;
    let mut data = corners.to_vec();
    if data.is_empty() {
        data.resize(TEXELS_PER_CORNER, [0.0; 4]);
    }
    let width = data.len().min(texels_per_row);
    data.resize(data.len().div_ceil(width) * width, [0.0; 4]);
    let rows = data.len() / width;
    ctx.device
        .create_texture_with_data(
            &ctx.queue,
            &wgpu::TextureDescriptor {
                label: Some("DBuffer::corners"),
                size: wgpu::Extent3d {
                    width: width as u32,
                    height: rows as u32,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&data),
        )
        .create_view(&wgpu::TextureViewDescriptor::default())
}

impl MethodState for DBuffer {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        self.geometry_stage(inputs)?;
        self.light_pass(inputs, shared, rec)?;
        let map = shared.shadow_map.made()?;
        let horizon = f32::from(inputs.knobs.get(&HORIZON));
        let corners = f32::from(inputs.knobs.get(&CORNERS));
        let v = require(
            self.volumes.targets(),
            "the D-buffer's targets were not made",
        )?;
        let tag = v.tag.bits() as f32;
        let uniforms =
            ShadowUniforms::new(inputs.light_view, map.size, [horizon, corners, tag, 0.0]);
        inputs
            .ctx
            .queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        let bound = Bound {
            map: map.generation,
            volumes: v.generation,
            corners: self.builds,
        };
        self.camera.bind(
            &inputs.ctx.device,
            bound,
            &[
                buffer_entry(0, &self.uniforms),
                view_entry(1, &map.distance.view),
                view_entry(2, &v.umbra.view),
                view_entry(3, &v.penumbra.view),
                view_entry(4, &self.corners),
            ],
        );
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        self.made_for?;
        let map = shared.shadow_map.targets()?;
        let v = self.volumes.targets()?;
        let generation = map.generation ^ v.generation.rotate_left(32);
        let textures = [&map.distance, &v.umbra, &v.penumbra];
        Some(
            LightMaps::new(v.size, self.view_proj, textures, CHANNELS, generation).tagged([
                FrameTag::NONE,
                v.tag,
                v.tag,
            ]),
        )
    }

    fn geometry(&self) -> Option<&SceneGeometry> {
        self.geometry.as_ref().map(|(g, _)| g)
    }

    fn geometry_builds(&self) -> (u64, f64) {
        (self.builds, self.geometry_ms)
    }

    fn invalidate(&mut self) {
        self.made_for = None;
    }
}
