//! `dbuffer` (Jakobsen et al. 2004, with the corrections in docs/method/dbuffer.md) and `dbuffer-center` (its silhouettes and
//! volumes taken from the light centre only: the penumbra-wedge approximation Jakobsen et al. 2004, Fig. 1
//! criticises).
//!
//! Per light or caster move: the geometry stage (`geometry::PreparedCasters::build`: classes,
//! silhouettes, volumes), the volumes uploaded, then the light pass — the session's shadow map
//! (`|cx_o|`) and the volume channels (`passes::dbuffer_volumes`). Per frame: the camera pass
//! with `shaders/methods/dbuffer.wgsl`. CPU twin: `geometry::DBufferTwin`.

use std::sync::atomic::{AtomicU32, Ordering};

use super::dbuffer_light::DBufferLight;
pub use super::dbuffer_light::{
    gpu_geometry_by_default, gpu_geometry_runs, light_move_ms, GeometryPath, GEOMETRY,
};
use super::{
    require, CameraGroup, Cost, LightMaps, MethodSpec, MethodState, Prepare, Quality, SharedMaps,
    Switch,
};
use crate::geometry::bvh::Bvh;
use crate::geometry::SceneGeometry;
use crate::render::passes::dbuffer_volumes::VolumeLayout;
use crate::render::passes::shadow_map::{lookup_entries, ShadowUniforms, PARAMS_BINDING};
use crate::render::passes::trace::{Path, TraceScene};
use crate::render::{
    buffer_entry, storage_entry, texture_entry, uniform_buffer, uniform_entry, view_entry,
    GpuContext, RenderError,
};

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
        .knobs(&[&HORIZON.0, &CORNERS.0, &GEOMETRY.0])
        .cost(DBUFFER_COST)
        .lights(super::AREA_LIGHTS)
        .sweep(&[Quality::MapSize], &[&[512], &[1024], &[2048]]); // volumes from a planar light's outline

pub static DBUFFER_CENTER: MethodSpec = MethodSpec::new("dbuffer-center", SHADER, |ctx| {
    Box::new(DBuffer::new(ctx, true))
})
.adapter(NEEDS)
.about("D-buffer with silhouettes from the light centre only")
.knobs(&[&HORIZON.0, &CORNERS.0, &GEOMETRY.0])
.cost(DBUFFER_COST)
.lights(super::AREA_LIGHTS)
.sweep(&[Quality::MapSize], &[&[512], &[1024], &[2048]]); // volumes from a planar light's outline

/// `--dbuffer-corners`: V exact behind a closing fan from the fan's corner
/// ([`DBufferParams::corners`]).
pub static CORNERS: Switch = Switch::new(
    "dbuffer-corners",
    "dbuffer, dbuffer-center: 1 = V exact behind a closing fan is the light less the caster's \
     corner seen from the point (a wedge); 0 = one chord there too, as the paper has it",
    true,
);

/// `--dbuffer-horizon`: clip the light by the receiver's own plane ([`DBufferParams::horizon`]
/// of `shaders/methods/dbuffer.wgsl`; the twin's [`DBufferTwin::horizon`]).
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

/// A user's method's knobs of the D-buffer's own (its `params`).
pub static USER_KNOBS: [&super::Knob; 2] = [&HORIZON.0, &CORNERS.0];

/// Where a user's method's knobs are bound in group 1 (`user_params`, a `vec4<f32>`): after the
/// D-buffer's six.
pub const USER_BINDING: u32 = 6;

/// Where a user's method that calls `scene_occluded` gets the scene's BVH (one storage buffer,
/// `passes::trace::TraceScene`) and its counts (a uniform `vec4<u32>`) in group 1.
pub const BVH_BINDING: u32 = 7;
pub const BVH_COUNTS_BINDING: u32 = 8;

/// [`NEEDS`] and a storage buffer the fragment stage reads: a user's method that traces the
/// scene's BVH.
pub const NEEDS_WITH_BVH: super::AdapterNeeds = super::AdapterNeeds {
    storage_buffers_per_stage: 1,
    ..NEEDS
};

/// The centre's shadow map (`|cx_o|`) and the volume channels: distance, `|cx_s|` and the lit
/// side per texel (`passes::dbuffer_volumes::VolumeLayout`: `Rg32Float`, or `Rgba32Float` with
/// the side for `V exact`).
pub const NEEDS: super::AdapterNeeds = super::AdapterNeeds::formats(&[
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

pub use super::dbuffer_light::CHANNELS;

/// `DBufferParams` of `shaders/methods/dbuffer.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DBufferParams {
    /// 1: V at most the part of the light in front of the receiver's plane ([`HORIZON`]).
    pub horizon: u32,
    /// 1: V exact toward a closing fan's corner ([`CORNERS`]).
    pub corners: u32,
    /// The frame tag of the volume channels ([`FrameTag::bits`]).
    ///
    /// [`FrameTag::bits`]: crate::render::frame_tag::FrameTag::bits
    pub tag: u32,
    pub _pad0: u32,
}

/// The paper's method: the D-buffer in light space ([`DBufferLight`]) read by its camera pass.
pub struct DBuffer {
    paper: DBufferLight,
    /// Bound for the generations of the shadow map and the volume channels ([`Bound`]).
    camera: CameraGroup,
    uniforms: wgpu::Buffer,
    params: wgpu::Buffer,
    /// The method's name, for an error about its light.
    name: &'static str,
    /// A user's method: its knobs' values and their uniform (at [`USER_BINDING`]).
    user: Option<(&'static UserValues, wgpu::Buffer)>,
    /// A user's method that traces the scene: its BVH's counts uniform, and the BVH once built
    /// (with the mesh revision it was built for).
    bvh: Option<(wgpu::Buffer, Option<(TraceScene, u64)>)>,
}

/// What the camera bind group binds: the shadow map's and the volume channels' generations, and
/// the geometry build of the corners.
#[derive(PartialEq)]
struct Bound {
    map: u64,
    volumes: u64,
    /// The geometry build the corners' texture was made for.
    corners: u64,
    /// The mesh revision the scene's BVH was built for (a user's method that traces it).
    bvh: Option<u64>,
}

/// A user's method's four knob values (`user_params.values`), read each frame: the lab's
/// sliders set them while it draws.
#[derive(Debug, Default)]
pub struct UserValues([AtomicU32; 4]);

impl UserValues {
    pub fn new(values: [f32; 4]) -> UserValues {
        UserValues(values.map(|v| AtomicU32::new(v.to_bits())))
    }

    pub fn get(&self) -> [f32; 4] {
        std::array::from_fn(|i| f32::from_bits(self.0[i].load(Ordering::Relaxed)))
    }

    /// Set value `i` (nothing past the fourth).
    pub fn set(&self, i: usize, value: f32) {
        if let Some(v) = self.0.get(i) {
            v.store(value.to_bits(), Ordering::Relaxed);
        }
    }
}

impl DBuffer {
    /// Group 1 of `methods/dbuffer.wgsl`.
    fn entries() -> Vec<wgpu::BindGroupLayoutEntry> {
        let mut entries = lookup_entries().to_vec();
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let d2 = wgpu::TextureViewDimension::D2;
        entries.extend([
            uniform_entry(PARAMS_BINDING, fragment),
            texture_entry(3, fragment, d2),
            texture_entry(4, fragment, d2),
            texture_entry(5, fragment, d2),
        ]);
        entries
    }

    pub fn new(ctx: &GpuContext, center_silhouettes: bool) -> DBuffer {
        DBuffer {
            paper: DBufferLight::new(ctx, center_silhouettes),
            camera: CameraGroup::new(ctx, SHADER, &Self::entries()),
            uniforms: uniform_buffer::<ShadowUniforms>(&ctx.device, "DBuffer::uniforms"),
            params: uniform_buffer::<DBufferParams>(&ctx.device, "DBuffer::params"),
            name: if center_silhouettes {
                DBUFFER_CENTER.name
            } else {
                DBUFFER.name
            },
            user: None,
            bvh: None,
        }
    }

    /// The paper's D-buffer drawn by a user's shader (`spec.shader`, its expanded `source`),
    /// its group 1 the D-buffer's and the uniform of the knobs' `values`.
    pub fn user(
        ctx: &GpuContext,
        spec: &'static MethodSpec,
        source: &str,
        values: &'static UserValues,
        bvh: bool,
    ) -> DBuffer {
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let mut entries = Self::entries();
        entries.push(uniform_entry(USER_BINDING, fragment));
        if bvh {
            entries.push(storage_entry(BVH_BINDING, fragment, true));
            entries.push(uniform_entry(BVH_COUNTS_BINDING, fragment));
        }
        DBuffer {
            paper: DBufferLight::new(ctx, false),
            camera: CameraGroup::from_source(ctx, spec.shader, source, &entries),
            uniforms: uniform_buffer::<ShadowUniforms>(&ctx.device, "DBuffer::uniforms"),
            params: uniform_buffer::<DBufferParams>(&ctx.device, "DBuffer::params"),
            name: spec.name,
            user: Some((
                values,
                uniform_buffer::<[f32; 4]>(&ctx.device, "DBuffer::user_params"),
            )),
            bvh: bvh.then(|| {
                (
                    uniform_buffer::<[u32; 4]>(&ctx.device, "DBuffer::bvh_counts"),
                    None,
                )
            }),
        }
    }

    /// The method's name, for an error about its light.
    fn name(&self) -> &'static str {
        self.name
    }
}

impl MethodState for DBuffer {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        self.paper.geometry_stage(inputs, self.name())?;
        self.paper.light_pass(inputs, shared, rec)?;
        let map = shared.shadow_map.made()?;
        let v = require(self.paper.targets(), "the D-buffer's targets were not made")?;
        let uniforms = ShadowUniforms::new(inputs.light_view, map.size);
        let params = DBufferParams {
            horizon: u32::from(inputs.knobs.get(&HORIZON)),
            corners: u32::from(inputs.knobs.get(&CORNERS)),
            tag: v.tag.bits(),
            _pad0: 0,
        };
        let queue = &inputs.ctx.queue;
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        if let Some((values, buffer)) = &self.user {
            queue.write_buffer(buffer, 0, bytemuck::bytes_of(&values.get()));
        }
        if let Some((counts, built)) = &mut self.bvh {
            if built
                .as_ref()
                .is_none_or(|(_, meshes)| *meshes != inputs.meshes)
            {
                let bvh = Bvh::build(inputs.scene.all_triangles());
                let gpu = TraceScene::new(inputs.ctx, &bvh, Path::WgslBvh)?;
                let words = [gpu.node_count(), gpu.triangle_count(), 0, 0];
                queue.write_buffer(counts, 0, bytemuck::bytes_of(&words));
                *built = Some((gpu, inputs.meshes));
            }
        }
        let bound = Bound {
            map: map.generation,
            volumes: v.generation,
            corners: self.paper.geometry_builds().0,
            bvh: self
                .bvh
                .as_ref()
                .and_then(|(_, b)| b.as_ref().map(|(_, m)| *m)),
        };
        let mut entries = vec![
            buffer_entry(0, &self.uniforms),
            view_entry(1, &map.distance.view),
            buffer_entry(PARAMS_BINDING, &self.params),
            view_entry(3, &v.umbra.view),
            view_entry(4, &v.penumbra.view),
            view_entry(5, self.paper.corners()),
        ];
        if let Some((_, buffer)) = &self.user {
            entries.push(buffer_entry(USER_BINDING, buffer));
        }
        if let Some((counts, built)) = &self.bvh {
            let (gpu, _) = require(built.as_ref(), "the scene's BVH")?;
            entries.push(wgpu::BindGroupEntry {
                binding: BVH_BINDING,
                resource: gpu.resource(),
            });
            entries.push(buffer_entry(BVH_COUNTS_BINDING, counts));
        }
        self.camera.bind(&inputs.ctx.device, bound, &entries);
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        self.paper.light_maps(shared)
    }

    fn geometry(&self) -> Option<&SceneGeometry> {
        self.paper.geometry()
    }

    fn geometry_builds(&self) -> (u64, f64) {
        self.paper.geometry_builds()
    }

    fn gpu_geometry(&self) -> Option<&crate::render::passes::geometry_gpu::GpuGeometry> {
        self.paper
            .gpu_geometry()
            .filter(|_| self.paper.geometry_path() == GeometryPath::Gpu)
    }

    fn invalidate(&mut self) {
        self.paper.invalidate();
    }

    fn poll_geometry(&mut self) -> bool {
        self.paper.poll_gpu_counts()
    }
}
