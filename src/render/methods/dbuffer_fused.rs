//! `dbuffer-fused` (`docs/method/dbuffer-fused.md`): the D-buffer with every silhouette chord a
//! receiver needs, so that the parts of the disk hidden by different casters, or different parts
//! of one caster, combine as they do in reality. CPU twin: `geometry::fused::FusedTwin`.
//!
//! Per light or caster move: the paper's D-buffer (this method keeps a [`DBufferLight`] of its own:
//! its `|cx_o|` is the hidden-from-centre test and its V(t) the fallback of an overflowing list;
//! its volume channels are drawn only where that fallback can be read, below), the candidate
//! edges and their proxy hulls (CPU), then the light passes `passes::fused_layers` (caster
//! crossings; receivers along each list texel's ray) and `passes::fused_lists` (merge, lists,
//! maps). Per frame: the camera pass with `shaders/methods/dbuffer_fused.wgsl`.
//!
//! **Knobs.** `--list-size` (texels per side of the list grid, default 256), `--list-cap` (edge
//! ids one list stores, default 256), `--mask-samples` (disk samples of the mask, default and
//! at most 128). The lists take `list-size² × (list-cap + 1) × 4` bytes: at most
//! [`MAX_FUSED_LIST_BYTES`] and the adapter's largest storage binding, else the frame is refused
//! naming both flags.
//!
//! **Overflow rule.** A list texel whose edges outnumber the cap is not used: its pixels walk
//! every candidate edge instead, which gives the V a list long enough would (small casters of
//! many edges under a large light overflow, and have few candidates in all), where there are at
//! most [`WHOLE_WALK_EDGES`](crate::geometry::fused::WHOLE_WALK_EDGES); with more they get the
//! paper's V(t). So do all pixels when the candidate edges exceed [`MAX_FUSED_EDGES`] (or what
//! the adapter's storage bindings hold). With fewer candidates than that no pixel reads the
//! paper's V, and its volume pass (2–15 ms of lavapipe's light pass at 1024²) is not drawn.

use super::Cost;
use super::{AdapterNeeds, Quality, SHADOW_MAP};
use crate::render::adapter::{FormatNeed, Usage};
use crate::scene::AreaLight;
use std::time::Instant;
use wgpu::DownlevelFlags as D;
use wgpu::TextureFormat as F;

use super::dbuffer_light::DBufferLight;
use super::{
    require, CameraGroup, Channel, Empty, FrameInputs, Knob, LightMaps, MethodSpec, MethodState,
    Prepare, SharedMaps,
};
use crate::budget::{bytes, MAX_FUSED_EDGES, MAX_FUSED_LIST_BYTES};
use crate::geometry::fused::{
    covered_rect, edge_proxy, max_receiver_height, scene_candidate_edges, DiskMask, MaskEval,
    DEFAULT_CAP, DEFAULT_SAMPLES, WHOLE_WALK_EDGES,
};
use crate::geometry::SceneGeometry;
use crate::render::frame_tag::FrameTag;
use crate::render::passes::dbuffer_volumes::VolumeLayout;
use crate::render::passes::fused_layers::{FusedLayers, FusedSizes, FusedUniforms};
use crate::render::passes::fused_lists::{
    list_bytes, EdgeBuffers, EdgeRecord, FusedLists, EDGE_BYTES, HULL_BYTES, HULL_CORNERS,
};
use crate::render::passes::shadow_map::{lookup_entries, ShadowUniforms, PARAMS_BINDING};
use crate::render::{
    buffer_entry, storage_buffer, texture_entry, uniform_buffer, uniform_entry, view_entry,
    GpuContext, RenderError, Texture,
};

/// Texels per side of the grid of edge lists.
pub static LIST_SIZE: Knob = Knob::int(
    "list-size",
    "dbuffer-fused: texels per side of the grid of edge lists",
    8..=2048,
    256,
);

/// Edge ids one list holds.
pub static LIST_CAP: Knob = Knob::int(
    "list-cap",
    "dbuffer-fused: edges one list holds (a longer one is not used: its pixels walk every candidate edge)",
    1..=1024,
    DEFAULT_CAP as u32,
);

/// Disk samples of the mask.
pub static MASK_SAMPLES: Knob = Knob::int(
    "mask-samples",
    "dbuffer-fused: disk samples of the mask where the disk is more than one layer deep",
    1..=128,
    DEFAULT_SAMPLES as u32,
);

pub static DBUFFER_FUSED: MethodSpec = MethodSpec::new("dbuffer-fused", SHADER, |ctx| {
    Box::new(DBufferFused::new(ctx))
})
.adapter(NEEDS)
.about("D-buffer with every silhouette chord (occluder fusion)")
.knobs(&[&LIST_SIZE, &LIST_CAP, &MASK_SAMPLES])
.cost(Cost::counted("listed edges visited").paths(&[
    "outside the map, or dark: no list",
    "no chord cuts the light",
    "one convex caster: exact V",
    "mask: the samples' count",
    "list overflowed: every candidate edge",
    "one or two chords: exact V",
    "mask, one layer deep: exact V",
    "too many candidate edges: the paper's V",
]))
.lights(super::AREA_LIGHTS)
.sweep(
    &[Quality::MapSize, Quality::Knob(&MASK_SAMPLES)],
    &[&[512, 32], &[1024, 64], &[1024, 128], &[2048, 128]],
); // its chords cut a disk or a convex polygon

const SHADER: &str = "methods/dbuffer_fused.wgsl";

/// `DBufferFusedParams` of `shaders/methods/dbuffer_fused.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DBufferFusedParams {
    /// The frame tag of the paper's volume channels (`dbuffer`'s, read where its V is).
    pub tag: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// What it needs of the adapter: the layers (half-float counts, float receivers, the first
/// layer's depth) and the maps drawn as float colour targets, the edge lists counted and stored by
/// fragment shaders (atomics into storage buffers) over proxies the vertex stage reads from
/// storage, and read back by the camera pass's (4 storage buffers a stage). No compute pass.
const NEEDS: AdapterNeeds = AdapterNeeds {
    formats: &[
        SHADOW_MAP[0],
        SHADOW_MAP[1],
        FormatNeed::new(Usage::Render, &[F::R16Float]),
        FormatNeed::new(Usage::Render, &[F::Rgba32Float]),
        FormatNeed::new(Usage::Render, &[F::R8Unorm]),
    ],
    downlevel: D::FRAGMENT_WRITABLE_STORAGE.union(D::VERTEX_STORAGE),
    storage_buffers_per_stage: 4,
    ..AdapterNeeds::NONE
};

/// The method's light-space channels: textures 0 (`|cx_o|`) and 1 (the maps of
/// `passes::fused_lists`: crossings, farthest crossing height, list count, overflow).
pub const CHANNELS: &[Channel] = &[
    Channel::new("layers to c", 1, 0, Empty::NonPositive),
    Channel::new("list length", 1, 2, Empty::NonPositive),
    Channel::new("overflow", 1, 3, Empty::NonPositive),
    Channel::new("|cx_o|", 0, 0, Empty::Far),
];

/// One edge's proxy hull, light-view NDC corners.
type HullCorners = [[f32; 2]; HULL_CORNERS];

/// The candidate edges for one revision and list grid.
struct Edges {
    revision: u64,
    list_size: u32,
    map_size: u32,
    count: usize,
    h_max: f32,
    /// More candidates than the budget or the adapter holds: every list overflows.
    over_budget: bool,
    /// The part of the light view (`[0, 1]²`, y down) that the casters and the proxies cover:
    /// outside it no texel has a crossing or a list.
    rect: [f32; 4],
    buffers: EdgeBuffers,
}

pub struct DBufferFused {
    paper: DBufferLight,
    /// Bound for the paper's volume channels where its V is never read (no crossing).
    no_paper: Texture,
    /// Bound for the generations of what it reads ([`Bound`]).
    camera: CameraGroup,
    shadow_uniforms: wgpu::Buffer,
    params: wgpu::Buffer,
    uniforms: wgpu::Buffer,
    layers: FusedLayers,
    lists: FusedLists,
    edges: Option<Edges>,
    /// The mask's look-up tables.
    lut: Option<Lut>,
    geometry_ms: f64,
    /// What the light passes hold.
    made_for: Option<Made>,
    view_proj: glam::Mat4,
}

/// The mask's look-up tables, for this many samples of this light (a polygon's samples follow
/// its shape).
struct Lut {
    buffer: wgpu::Buffer,
    samples: u32,
    light: AreaLight,
}

/// What the light passes were recorded for.
#[derive(Clone, Copy, PartialEq)]
struct Made {
    revision: u64,
    map_size: u32,
    list_size: u32,
    cap: u32,
    /// The candidate edges' generation.
    edges: u64,
}

/// What the camera bind group binds: the generations of the shadow map, the paper's volume
/// channels, the lists and the edges, and the sample count of the look-up tables.
#[derive(PartialEq)]
struct Bound {
    map: u64,
    paper: u64,
    lists: u64,
    edges: u64,
    samples: u32,
}

impl DBufferFused {
    pub fn new(ctx: &GpuContext) -> DBufferFused {
        use wgpu::ShaderStages as S;
        let mut entries = lookup_entries().to_vec();
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: S::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let d2 = wgpu::TextureViewDimension::D2;
        entries.extend([
            uniform_entry(PARAMS_BINDING, S::FRAGMENT),
            texture_entry(3, S::FRAGMENT, d2),
            texture_entry(4, S::FRAGMENT, d2),
            texture_entry(5, S::FRAGMENT, d2),
            uniform_entry(6, S::FRAGMENT),
            storage(7),
            storage(8),
            storage(9),
            storage(10),
        ]);
        let uniforms = uniform_buffer::<FusedUniforms>(&ctx.device, "DBufferFused::uniforms");
        DBufferFused {
            paper: DBufferLight::on_cpu(ctx, false),
            no_paper: Texture::new(
                &ctx.device,
                "DBufferFused::no_paper",
                (1, 1),
                VolumeLayout::Distances.format(),
                wgpu::TextureUsages::TEXTURE_BINDING,
            ),
            camera: CameraGroup::two_draws(ctx, SHADER, &entries),
            shadow_uniforms: uniform_buffer::<ShadowUniforms>(
                &ctx.device,
                "DBufferFused::shadow_uniforms",
            ),
            params: uniform_buffer::<DBufferFusedParams>(&ctx.device, "DBufferFused::params"),
            layers: FusedLayers::new(ctx, &uniforms),
            lists: FusedLists::new(ctx, &uniforms),
            uniforms,
            edges: None,
            lut: None,
            geometry_ms: 0.0,
            made_for: None,
            view_proj: glam::Mat4::IDENTITY,
        }
    }

    /// How many candidate edges the current light has (0 before the first frame).
    pub fn candidate_edges(&self) -> usize {
        self.edges.as_ref().map_or(0, |e| e.count)
    }
}

/// The candidate edges and their proxies, when the light, a caster or the list grid
/// changed.
fn update_edges(
    slot: &mut Option<Edges>,
    inputs: &FrameInputs<'_>,
    geometry: &SceneGeometry,
    list_size: u32,
    max_binding: u64,
) -> Option<f64> {
    let key = (inputs.revision, list_size, inputs.map_size);
    if slot
        .as_ref()
        .is_some_and(|e| (e.revision, e.list_size, e.map_size) == key)
    {
        return None;
    }
    let t = Instant::now();
    // A disk (the session refuses a line light for this method before a frame gets here).
    let light = inputs.scene.light.area_or_centre();
    let edges = scene_candidate_edges(inputs.prepared(), geometry);
    let h_max = max_receiver_height(inputs.scene, &light);
    let limit = MAX_FUSED_EDGES
        .min(max_binding / EDGE_BYTES)
        .min(max_binding / HULL_BYTES);
    let over_budget = edges.len() as u64 > limit;
    let uniforms = FusedUniforms::new(
        &light,
        inputs.light_view,
        FusedSizes {
            map_size: inputs.map_size,
            list_size,
            cap: 0,
            samples: 0,
            edge_count: 0,
            h_max,
            all_overflow: false,
        },
    );
    let vp = inputs.light_view.view_projection();
    let (records, hulls): (Vec<EdgeRecord>, Vec<HullCorners>) = if over_budget {
        (Vec::new(), Vec::new())
    } else {
        edges
            .iter()
            .map(|e| {
                let hull = edge_proxy(e, &light, h_max, uniforms.half_slope, &vp);
                let last = hull.last().copied().unwrap_or(glam::Vec2::ZERO);
                let corners =
                    std::array::from_fn(|i| hull.get(i).copied().unwrap_or(last).to_array());
                (e.gpu_record(light.center), corners)
            })
            .unzip()
    };
    let rect = if over_budget {
        // Every texel's overflow flag is set.
        [0.0, 0.0, 1.0, 1.0]
    } else {
        covered_rect(
            inputs.scene,
            inputs.light_view,
            hulls.iter().flatten().copied(),
        )
    };
    *slot = Some(Edges {
        revision: inputs.revision,
        list_size,
        map_size: inputs.map_size,
        count: edges.len(),
        h_max,
        over_budget,
        rect,
        buffers: EdgeBuffers::new(&inputs.ctx.device, &records, &hulls),
    });
    Some(t.elapsed().as_secs_f64() * 1e3)
}

impl MethodState for DBufferFused {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        let list_size = inputs.knobs.get(&LIST_SIZE);
        let cap = inputs.knobs.get(&LIST_CAP);
        let samples = inputs.knobs.get(&MASK_SAMPLES).clamp(1, 128);
        let device = &inputs.ctx.device;
        let max_binding = device.limits().max_storage_buffer_binding_size;
        let lists = list_bytes(list_size, cap);
        let ids = lists / (u64::from(cap) + 1) * u64::from(cap);
        if lists > MAX_FUSED_LIST_BYTES || ids > max_binding {
            return Err(RenderError::Request(format!(
                "--list-size {list_size} with --list-cap {cap}: dbuffer-fused's lists would take {} \
                 (MAX_FUSED_LIST_BYTES is {}, this adapter binds at most {} at once); lower either",
                bytes(lists),
                bytes(MAX_FUSED_LIST_BYTES),
                bytes(max_binding)
            )));
        }
        // The paper's geometry (face classes), then its light pass: |cx_o| always, the volume
        // channels only where the paper's V can be read (below).
        self.paper.geometry_stage(inputs, DBUFFER_FUSED.name)?;
        let geometry = require(
            self.paper.geometry(),
            "the D-buffer's geometry was not made",
        )?;
        if let Some(ms) = update_edges(&mut self.edges, inputs, geometry, list_size, max_binding) {
            self.geometry_ms = ms;
        }
        let edges = require(self.edges.as_ref(), "dbuffer-fused's edges were not made")?;
        // The paper's V is read only where every list overflows or an overflowing list has more
        // candidate edges than a pixel walks; else its volume channels are not drawn at all.
        let paper_read = edges.over_budget || edges.count > WHOLE_WALK_EDGES;
        if paper_read {
            self.paper.light_pass(inputs, shared, rec)?;
        } else {
            shared.shadow_map.update(inputs, rec)?;
        }
        let light = inputs.scene.light.area_or_centre();
        // A disk's samples are the same for every disk; a polygon's follow its shape.
        let same_shape = |l: &AreaLight| (l.is_disk() && light.is_disk()) || *l == light;
        if self
            .lut
            .as_ref()
            .is_none_or(|lut| lut.samples != samples || !same_shape(&lut.light))
        {
            let words = DiskMask::for_light(&light, samples as usize, MaskEval::Lut).lut_words();
            self.lut = Some(Lut {
                buffer: storage_buffer(device, "DBufferFused::lut", &words),
                samples,
                light,
            });
        }
        let uniforms = FusedUniforms::new(
            &inputs.scene.light.area_or_centre(),
            inputs.light_view,
            FusedSizes {
                map_size: inputs.map_size,
                list_size,
                cap,
                samples,
                edge_count: edges.buffers.count,
                h_max: edges.h_max,
                all_overflow: edges.over_budget,
            },
        );
        inputs
            .ctx
            .queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        let key = Made {
            revision: inputs.revision,
            map_size: inputs.map_size,
            list_size,
            cap,
            edges: edges.buffers.generation,
        };
        if self.made_for != Some(key) {
            self.layers
                .record(inputs.ctx, rec, inputs.surfaces, inputs.map_size, list_size);
            let layers = require(
                self.layers.targets(),
                "dbuffer-fused's layers were not made",
            )?;
            self.lists
                .record(inputs.ctx, rec, layers, &edges.buffers, cap, edges.rect);
            self.made_for = Some(key);
            self.view_proj = inputs.light_view.view_projection();
        }
        let map = shared.shadow_map.made()?;
        let (Some(lists), Some(Lut { buffer: lut, .. })) =
            (self.lists.targets(), self.lut.as_ref())
        else {
            return Err(RenderError::Gpu(
                "dbuffer-fused's maps were not made".into(),
            ));
        };
        // The paper's volume channels and their frame tag, or where its V is never read, a
        // texel of no crossing in their place. Generation 0 is no made texture's.
        let (paper, umbra, penumbra, tag) = if paper_read {
            let maps = require(
                self.paper.light_maps(shared),
                "the D-buffer's targets were not made",
            )?;
            let [_, umbra, penumbra] = maps.textures;
            (maps.generation, umbra, penumbra, maps.tags[1])
        } else {
            let none = &self.no_paper.view;
            (0, none, none, FrameTag::NONE)
        };
        let shadow = ShadowUniforms::new(inputs.light_view, map.size);
        let params = DBufferFusedParams {
            tag: tag.bits(),
            ..DBufferFusedParams::default()
        };
        let queue = &inputs.ctx.queue;
        queue.write_buffer(&self.shadow_uniforms, 0, bytemuck::bytes_of(&shadow));
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let bound = Bound {
            map: map.generation,
            paper,
            lists: lists.generation,
            edges: edges.buffers.generation,
            samples,
        };
        self.camera.bind(
            device,
            bound,
            &[
                buffer_entry(0, &self.shadow_uniforms),
                view_entry(1, &map.distance.view),
                buffer_entry(PARAMS_BINDING, &self.params),
                view_entry(3, umbra),
                view_entry(4, penumbra),
                view_entry(5, &lists.maps.view),
                buffer_entry(6, &self.uniforms),
                buffer_entry(7, &edges.buffers.edges),
                buffer_entry(8, &lists.counts),
                buffer_entry(9, &lists.lists),
                buffer_entry(10, lut),
            ],
        );
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        self.made_for?;
        let map = shared.shadow_map.targets()?;
        let lists = self.lists.targets()?;
        let generation = map.generation ^ lists.generation.rotate_left(32);
        let textures = [&map.distance, &lists.maps, &lists.maps];
        Some(LightMaps::new(
            lists.map_size,
            self.view_proj,
            textures,
            CHANNELS,
            generation,
        ))
    }

    fn geometry(&self) -> Option<&SceneGeometry> {
        self.paper.geometry()
    }

    fn geometry_builds(&self) -> (u64, f64) {
        let (builds, ms) = self.paper.geometry_builds();
        (builds, ms + self.geometry_ms)
    }

    fn invalidate(&mut self) {
        self.paper.invalidate();
        self.made_for = None;
    }
}
