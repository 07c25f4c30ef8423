//! The D-buffer's geometry stage on the GPU (`shaders/passes/geometry_gpu.wgsl`): per caster and
//! light move, compute passes classify the faces, find both silhouettes and their extrusion
//! points, extrude the quads, close the fans and add the silhouette faces, from the caster's
//! adjacency uploaded once ([`FlatCaster`]); they write the light pass's volume vertices and the
//! arguments of its indirect draws. Nothing is read back on the way to a frame: the counts
//! ([`GpuStageCounts`]) are read only by whoever asks ([`GpuGeometry::read_back`]: tests and
//! `dbuffer inspect`).
//!
//! Where it differs from the CPU stage (`geometry::volumes`): the triangles come in no set
//! order (the light pass's depth tests decide, as they do for the CPU's); a fan's corner is
//! numbered as it is stored, and only corners `V exact` may use are stored; each caster holds
//! its own buffers, sized from its adjacency, and one that would pass them or the volume budget
//! casts no shadow.

use crate::budget::MAX_VOLUME_TRIANGLES;
use crate::geometry::flat_caster::FlatCaster;
use crate::geometry::volume_vertices::{CORNERS_PER_ROW, TEXELS_PER_CORNER};
use crate::geometry::{GeometryStats, PreparedCasters, SceneGeometry, VolumeParams};
use crate::render::gpu_scene::IndirectVolume;
use crate::render::readback::{read_u32s, u32s, LateCopy};
use crate::render::timer::Recorder;
use crate::render::{
    buffer_entry, compute_pipeline, pipeline_layout, shader_module, storage_entry, uniform_entry,
    GpuContext, RenderError, VolumeVertex,
};
use crate::scene::AreaLight;
use std::sync::Arc;

/// What the geometry stage on the GPU needs of an adapter besides the D-buffer's own: compute
/// shaders, indirect draws, and seven storage buffers in its compute stage.
pub const GPU_GEOMETRY_DOWNLEVEL: wgpu::DownlevelFlags =
    wgpu::DownlevelFlags::COMPUTE_SHADERS.union(wgpu::DownlevelFlags::INDIRECT_EXECUTION);
pub const GPU_GEOMETRY_STORAGE_BUFFERS: u32 = 7;

/// Words of the state buffer: the counts, then the two draws' arguments.
const STATE_WORDS: usize = 24;
/// The state words that hold a caster's counts ([`GpuStageCounts::decode`]).
const COUNT_WORDS: u64 = 16;
const ARGS_UMBRA: u64 = COUNT_WORDS * 4;
const ARGS_PENUMBRA: u64 = 20 * 4;
const VERTEX_WORDS: u64 = (std::mem::size_of::<VolumeVertex>() / 4) as u64;

/// The timed span of the stage's compute passes (its GPU time in the stats).
pub const SPAN: &str = "geometry_gpu";

/// `GeomParams` of `shaders/passes/geometry_gpu.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct GeomParams {
    center: [f32; 3],
    radius: f32,
    normal: [f32; 3],
    far: f32,
    basis_u: [f32; 3],
    class_radius: f32,
    basis_w: [f32; 3],
    fan_step: f32,
    corners: [[f32; 4]; 16],
    counts: [u32; 4],
    flags: [u32; 4],
    limits: [u32; 4],
    reach: [f32; 4],
}

/// What one caster's stage counted on the GPU (`state` of the shader).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GpuStageCounts {
    /// Triangles drawn per volume (after ending them at their reach).
    pub umbra_drawn: u32,
    pub penumbra_drawn: u32,
    /// Corners stored for `V exact`.
    pub corners: u32,
    /// Over the budget or the caster's buffers, or more than [`MAX_GPU_VERTEX_ENDS`] silhouette
    /// edge ends at one vertex of a volume: it casts no shadow.
    pub refused: bool,
    /// The face classes, in `FaceClass::code` order.
    pub classes: [u32; 4],
    pub umbra_edges: u32,
    pub penumbra_edges: u32,
    pub fans: u32,
    pub umbra_fans: u32,
    pub unextruded_edges: u32,
    /// Volume triangles made, before ending them at their reach.
    pub umbra_triangles: u32,
    pub penumbra_triangles: u32,
}

impl GpuStageCounts {
    /// The counts in a caster's state words (`s`: at least [`COUNT_WORDS`]), its stored corners
    /// at most `corner_capacity`.
    fn decode(s: &[u32], corner_capacity: u32) -> GpuStageCounts {
        let w = |i: usize| s.get(i).copied().unwrap_or(0);
        GpuStageCounts {
            umbra_drawn: w(0),
            penumbra_drawn: w(1),
            corners: w(2).min(corner_capacity),
            refused: w(3) != 0,
            classes: [w(5), w(6), w(7), w(8)],
            umbra_edges: w(9),
            penumbra_edges: w(10),
            fans: w(11),
            umbra_fans: w(12),
            unextruded_edges: w(13),
            umbra_triangles: w(14),
            penumbra_triangles: w(15),
        }
    }

    /// The counts as the CPU stage states them, for a caster of `triangles` faces
    /// ([`GeometryStats`]: the stats panel, `meta.json`, `dbuffer inspect`). A refused caster
    /// has no volume triangles, as the CPU's has none.
    pub fn stats(&self, triangles: usize) -> GeometryStats {
        let made = |n: u32| if self.refused { 0 } else { n as usize };
        GeometryStats {
            triangles,
            all_front: self.classes[0] as usize,
            none_front: self.classes[1] as usize,
            silhouette_a: self.classes[2] as usize,
            silhouette_b: self.classes[3] as usize,
            umbra_edges: self.umbra_edges as usize,
            penumbra_edges: self.penumbra_edges as usize,
            fans: made(self.fans),
            umbra_fans: made(self.umbra_fans),
            umbra_triangles: made(self.umbra_triangles),
            penumbra_triangles: made(self.penumbra_triangles),
            unextruded_edges: self.unextruded_edges as usize,
        }
    }
}

/// What a caster whose volumes the GPU stage refused is warned with.
fn refused_warning(name: &str) -> String {
    format!(
        "caster '{name}': its shadow volumes pass the GPU stage's buffers or budget \
         ({MAX_VOLUME_TRIANGLES} volume triangles, MAX_VOLUME_TRIANGLES), or more than \
         {MAX_GPU_VERTEX_ENDS} silhouette edges meet at one vertex: it casts no shadow \
         (--geometry cpu draws it)"
    )
}

/// One caster's stage read back ([`GpuGeometry::read_back`]).
#[derive(Clone, Debug, Default)]
pub struct GpuCasterReadback {
    pub counts: GpuStageCounts,
    /// One class code per face.
    pub classes: Vec<u32>,
    /// Per edge: bit 0 on the umbra silhouette, bit 1 on the penumbra one, bit 2 without a
    /// volume (its line meets the light).
    pub silhouettes: Vec<u8>,
    pub umbra: Vec<VolumeVertex>,
    pub penumbra: Vec<VolumeVertex>,
    /// The stored corners, `TEXELS_PER_CORNER` texels each, numbered from `corner_base`.
    pub corners: Vec<[f32; 4]>,
    pub corner_base: u32,
}

/// The pipelines, built once per device.
struct GeometryGpuPass {
    layout: wgpu::BindGroupLayout,
    classify: wgpu::ComputePipeline,
    edges: wgpu::ComputePipeline,
    fans: wgpu::ComputePipeline,
    faces: wgpu::ComputePipeline,
    finish: wgpu::ComputePipeline,
}

impl GeometryGpuPass {
    fn get(ctx: &GpuContext) -> Arc<GeometryGpuPass> {
        ctx.shared(|device| {
            let module = shader_module(device, "passes/geometry_gpu.wgsl");
            let c = wgpu::ShaderStages::COMPUTE;
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("GeometryGpuPass::layout"),
                entries: &[
                    uniform_entry(0, c),
                    storage_entry(1, c, true),
                    storage_entry(2, c, true),
                    storage_entry(3, c, false),
                    storage_entry(4, c, false),
                    storage_entry(5, c, false),
                    storage_entry(6, c, false),
                    storage_entry(7, c, false),
                ],
            });
            let pl = pipeline_layout(device, "GeometryGpuPass::pipelines", &[&layout]);
            let make = |entry| compute_pipeline(device, entry, &pl, &module, entry);
            GeometryGpuPass {
                classify: make("classify"),
                edges: make("edges_pass"),
                fans: make("fans"),
                faces: make("faces_pass"),
                finish: make("finish"),
                layout,
            }
        })
    }
}

/// One caster's buffers.
struct GpuCaster {
    flat_counts: (u32, u32, u32),
    convex: bool,
    params: wgpu::Buffer,
    work: wgpu::Buffer,
    umbra: wgpu::Buffer,
    penumbra: wgpu::Buffer,
    state: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    capacity: (u32, u32),
    corner_base: u32,
    corner_capacity: u32,
}

/// The most silhouette edge ends of one volume at one vertex the GPU's closing fans pair (every
/// pair compared, as the CPU does up to as many); past it the caster casts no shadow.
pub const MAX_GPU_VERTEX_ENDS: u32 = 64;

/// The most corners the GPU stage stores for `V exact` over a scene's casters (the corners'
/// texture is copied whole per build: 9.4 MB); a fan past it keeps its lit side (the chord's
/// V), as the CPU's do past `MAX_CORNERS`.
pub const MAX_GPU_CORNERS: u32 = 65_536;

/// The geometry stage on the GPU for every caster of a scene.
pub struct GpuGeometry {
    pass: Arc<GeometryGpuPass>,
    casters: Vec<GpuCaster>,
    /// Every caster's stored corners, copied into [`GpuGeometry::corner_texture`] per build.
    corner_buffer: wgpu::Buffer,
    corner_texture: wgpu::Texture,
    pub corner_view: wgpu::TextureView,
    corner_rows: u32,
    /// The casters' names, for the warnings.
    names: Vec<String>,
    /// The last build's counts on their way back, a frame or more late (the lab's stats and
    /// warnings; nothing waits for them).
    copy: LateCopy,
    /// The counts of the last build that came back.
    counts: Option<Vec<GpuStageCounts>>,
}

/// Triangles one volume of a caster may need at most, within the device's binding and the
/// scene's volume budget: each extruded edge two quad triangles, each silhouette face one, each
/// fan at most a half turn, every triangle cut in two at most where it is ended.
fn capacity(flat: &FlatCaster, umbra: bool, max_binding: u64) -> u32 {
    let (f, e) = (u64::from(flat.faces), u64::from(flat.edges));
    let fans = 2 * e * crate::geometry::outline::MAX_ARC_POINTS as u64;
    let made = 2 * e + fans + if umbra { f } else { 0 };
    let bytes_per = 3 * VERTEX_WORDS * 4;
    (2 * made)
        .min(2 * MAX_VOLUME_TRIANGLES)
        .min(max_binding / bytes_per)
        .max(1) as u32
}

impl GpuGeometry {
    /// The casters' adjacency uploaded and their buffers made, or why this scene keeps the CPU
    /// stage (a caster past the device's storage binding).
    pub fn new(ctx: &GpuContext, prepared: &PreparedCasters) -> Result<GpuGeometry, String> {
        let device = &ctx.device;
        let limits = device.limits();
        let max_binding = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let pass = GeometryGpuPass::get(ctx);
        let mut flats = Vec::new();
        let mut corner_base = 0u32;
        for mesh in &prepared.meshes {
            let flat = FlatCaster::new(mesh);
            let bytes = (flat.topo.len() as u64 * 4)
                .max(flat.geo.len() as u64 * 16)
                .max(flat.work_words() * 4);
            if bytes > max_binding {
                return Err(format!(
                    "caster '{}' needs {bytes} bytes in one storage binding (the device binds \
                     {max_binding})",
                    mesh.name
                ));
            }
            // Only a corner V exact may use is stored: none of a caster past the wedge check.
            let past_check = !flat.convex
                && flat.vertices as usize > crate::geometry::volumes::CORNER_CHECK_VERTICES;
            let room = MAX_GPU_CORNERS.saturating_sub(corner_base);
            let corner_capacity = if past_check {
                0
            } else {
                (2 * flat.edges).min(room)
            };
            flats.push((flat, (corner_base, corner_capacity)));
            corner_base += corner_capacity;
        }
        let corner_rows = u64::from(corner_base.max(1)).div_ceil(CORNERS_PER_ROW as u64) as u32;
        let row_bytes = (TEXELS_PER_CORNER * CORNERS_PER_ROW * 16) as u64;
        let corner_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("GpuGeometry::corners"),
            size: u64::from(corner_rows) * row_bytes,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let corner_texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("GpuGeometry::corner_texture"),
            size: wgpu::Extent3d {
                width: (TEXELS_PER_CORNER * CORNERS_PER_ROW) as u32,
                height: corner_rows,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let corner_view = corner_texture.create_view(&wgpu::TextureViewDescriptor::default());
        let casters = flats
            .iter()
            .map(|(flat, corners)| {
                let capacity = (
                    capacity(flat, true, max_binding),
                    capacity(flat, false, max_binding),
                );
                GpuCaster::new(ctx, &pass, flat, capacity, *corners, &corner_buffer)
            })
            .collect();
        let copy = LateCopy::new(
            device,
            "GpuGeometry::counts_copy",
            flats.len() as u64 * COUNT_WORDS * 4,
        );
        Ok(GpuGeometry {
            pass,
            casters,
            corner_buffer,
            corner_texture,
            corner_view,
            corner_rows,
            names: prepared.meshes.iter().map(|m| m.name.clone()).collect(),
            copy,
            counts: None,
        })
    }

    /// Record the stage for `light` (classes against the centre alone for `dbuffer-center`'s
    /// `params.center_silhouettes`), each volume ended at `reach` where given (the umbra only
    /// where `end_umbra`: a scene of one caster).
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        rec: &mut Recorder<'_>,
        light: &AreaLight,
        params: &VolumeParams,
        reach: Option<f32>,
    ) {
        let end_umbra = self.casters.len() == 1;
        let (u, w) = light.basis();
        let mut corners = [[0.0f32; 4]; 16];
        let count = match light.corners() {
            Some(p) => {
                for (k, v) in p.vertices().iter().take(16).enumerate() {
                    corners[k] = v.extend(0.0).to_array();
                }
                p.vertices().len().min(16) as u32
            }
            None => 0,
        };
        // Each caster is held to the whole budget: what the casters before it made is not
        // known without reading it back.
        let budget = MAX_VOLUME_TRIANGLES as u32;
        for c in &self.casters {
            let (f, e, v) = c.flat_counts;
            let g = GeomParams {
                center: light.center.to_array(),
                radius: light.radius,
                normal: light.normal.to_array(),
                far: params.far,
                basis_u: u.to_array(),
                class_radius: if params.center_silhouettes {
                    0.0
                } else {
                    light.radius
                },
                basis_w: w.to_array(),
                fan_step: params.fan_step_deg.to_radians().max(1e-3),
                corners,
                counts: [f, e, v, count],
                flags: [
                    u32::from(count > 0 && !params.center_silhouettes),
                    u32::from(c.convex),
                    c.capacity.0,
                    c.capacity.1,
                ],
                limits: [
                    budget,
                    c.corner_base,
                    c.corner_capacity,
                    u32::from(end_umbra && reach.is_some()),
                ],
                reach: [reach.unwrap_or(-1.0), reach.unwrap_or(-1.0), 0.0, 0.0],
            };
            ctx.queue.write_buffer(&c.params, 0, bytemuck::bytes_of(&g));
            // Only the ends' counts start at zero: the classes, slots and points are written
            // before they are read.
            rec.encoder
                .clear_buffer(&c.work, u64::from(f) * 4, Some(u64::from(v) * 8));
            rec.encoder.clear_buffer(&c.state, 0, None);
        }
        let span = rec.span(SPAN);
        let max_groups = ctx
            .device
            .limits()
            .max_compute_workgroups_per_dimension
            .max(1);
        let groups = |items: u32| {
            let groups = items.div_ceil(64).max(1);
            let x = groups.min(max_groups);
            (x, groups.div_ceil(x))
        };
        // One compute pass per step: each step reads what the one before wrote, and a pass
        // boundary orders that on every backend (GL included).
        let steps = [
            &self.pass.classify,
            &self.pass.edges,
            &self.pass.fans,
            &self.pass.faces,
            &self.pass.finish,
        ];
        for (k, pipeline) in steps.into_iter().enumerate() {
            let writes = span.compute_writes_over(rec.timer, k == 0, k + 1 == steps.len());
            let mut p = rec
                .encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("GpuGeometry::stage"),
                    timestamp_writes: writes,
                });
            p.set_pipeline(pipeline);
            for c in &self.casters {
                let (f, e, v) = c.flat_counts;
                let items = [f, e, v, f, 1][k];
                let (x, y) = if k == 4 { (1, 1) } else { groups(items) };
                p.set_bind_group(0, &c.bind_group, &[]);
                p.dispatch_workgroups(x, y, 1);
            }
        }
        rec.encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &self.corner_buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some((TEXELS_PER_CORNER * CORNERS_PER_ROW * 16) as u32),
                    rows_per_image: Some(self.corner_rows),
                },
            },
            self.corner_texture.as_image_copy(),
            self.corner_texture.size(),
        );
        // The counts, back a frame or more later (unless the last ones are still mapping).
        if self.copy.free() && !self.casters.is_empty() {
            for (i, c) in self.casters.iter().enumerate() {
                rec.encoder.copy_buffer_to_buffer(
                    &c.state,
                    0,
                    &self.copy.buffer,
                    i as u64 * COUNT_WORDS * 4,
                    COUNT_WORDS * 4,
                );
            }
            self.copy.copied();
        }
    }

    /// Pick up the counts of a recorded build without waiting: the first call after the build
    /// was submitted asks for the copy, a later one takes it ([`GpuGeometry::last_counts`]).
    /// `true` while they are on their way or have just arrived.
    pub fn poll_counts(&mut self) -> bool {
        let Some(bytes) = self.copy.poll() else {
            return self.copy.pending();
        };
        if (bytes.len() as u64) < self.casters.len() as u64 * COUNT_WORDS * 4 {
            return true; // the map failed: the counts before stay
        }
        let words = u32s(&bytes);
        self.counts = Some(
            self.casters
                .iter()
                .zip(words.chunks(COUNT_WORDS as usize))
                .map(|(c, s)| GpuStageCounts::decode(s, c.corner_capacity))
                .collect(),
        );
        true
    }

    /// Per caster, the counts of the last build that came back ([`GpuGeometry::poll_counts`]).
    pub fn last_counts(&self) -> Option<&[GpuStageCounts]> {
        self.counts.as_deref()
    }

    /// The counts of the last build that came back, over every caster, as the CPU stage states
    /// them ([`GpuStageCounts::stats`]).
    pub fn last_stats(&self) -> Option<GeometryStats> {
        let counts = self.counts.as_ref()?;
        let mut out = GeometryStats::default();
        for (c, caster) in counts.iter().zip(&self.casters) {
            out += c.stats(caster.flat_counts.0 as usize);
        }
        Some(out)
    }

    /// A warning per caster of the last build that came back whose volumes the stage refused
    /// (it casts no shadow).
    pub fn refused_warnings(&self) -> Vec<String> {
        self.counts
            .iter()
            .flatten()
            .zip(&self.names)
            .filter(|(c, _)| c.refused)
            .map(|(_, name)| refused_warning(name))
            .collect()
    }

    /// Per caster its umbra and its penumbra, as the light pass draws them.
    pub fn volumes(&self) -> Vec<(IndirectVolume, IndirectVolume)> {
        self.casters
            .iter()
            .map(|c| {
                (
                    IndirectVolume {
                        vertices: c.umbra.clone(),
                        args: c.state.clone(),
                        offset: ARGS_UMBRA,
                    },
                    IndirectVolume {
                        vertices: c.penumbra.clone(),
                        args: c.state.clone(),
                        offset: ARGS_PENUMBRA,
                    },
                )
            })
            .collect()
    }

    /// The counts of the last build as the CPU stage's [`SceneGeometry`] states them (no classes,
    /// silhouettes or volumes in it: those stay on the GPU), with a warning per caster that
    /// casts nothing; reads back (waits for the GPU): for `render`'s `meta.json` and `dbuffer
    /// inspect`, never on the way to a frame.
    pub fn stats(
        &self,
        ctx: &GpuContext,
        prepared: &PreparedCasters,
    ) -> Result<SceneGeometry, RenderError> {
        let read = self.read_back(ctx)?;
        let mut out = SceneGeometry {
            warnings: prepared.scene_warnings.clone(),
            ..SceneGeometry::default()
        };
        for (r, mesh) in read.iter().zip(&prepared.meshes) {
            let stats = r.counts.stats(mesh.faces.len());
            out.warnings.extend(mesh.report.warning(&mesh.name));
            if r.counts.refused {
                out.warnings.push(refused_warning(&mesh.name));
            }
            if stats.unextruded_edges > 0 {
                out.warnings.push(format!(
                    "caster '{}': {} silhouette edges point into the light disk and get no volume",
                    mesh.name, stats.unextruded_edges
                ));
            }
            out.stats += stats;
            out.casters.push(crate::geometry::CasterGeometry {
                name: mesh.name.clone(),
                stats,
                ..Default::default()
            });
        }
        Ok(out)
    }

    /// Run the stage once for `light` and read its counts back ([`GpuGeometry::stats`]):
    /// `dbuffer inspect --geometry gpu`.
    pub fn run_once(
        ctx: &GpuContext,
        prepared: &PreparedCasters,
        light: &AreaLight,
        params: &VolumeParams,
        reach: Option<f32>,
    ) -> Result<SceneGeometry, RenderError> {
        let mut gpu = GpuGeometry::new(ctx, prepared).map_err(RenderError::Request)?;
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("GpuGeometry::run_once"),
            });
        {
            let mut rec = Recorder::new(&mut encoder, None);
            gpu.record(ctx, &mut rec, light, params, reach);
        }
        ctx.queue.submit([encoder.finish()]);
        gpu.stats(ctx, prepared)
    }

    /// Every caster's last stage read back (waits for the GPU): for tests and `dbuffer inspect`,
    /// never on the way to a frame.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<Vec<GpuCasterReadback>, RenderError> {
        let corner_words = read_u32s(ctx, &self.corner_buffer)?;
        let mut out = Vec::new();
        for c in &self.casters {
            let s = read_u32s(ctx, &c.state)?;
            let (f, e, _) = c.flat_counts;
            let counts = GpuStageCounts::decode(&s, c.corner_capacity);
            let work = read_u32s(ctx, &c.work)?;
            let v = c.flat_counts.2 as usize;
            let points = f as usize + 2 * v + 4 * e as usize;
            let silhouettes = (0..e as usize)
                .map(|i| {
                    let umbra = work[points + 8 * i + 3];
                    let penumbra = work[points + 8 * i + 7];
                    ((umbra & 1) | ((penumbra & 1) << 1) | (umbra & 4)) as u8
                })
                .collect();
            let vertices =
                |buffer: &wgpu::Buffer, n: u32| -> Result<Vec<VolumeVertex>, RenderError> {
                    if n == 0 {
                        return Ok(Vec::new());
                    }
                    let words = read_u32s(ctx, buffer)?;
                    let take = (3 * n as usize * VERTEX_WORDS as usize).min(words.len());
                    Ok(bytemuck::cast_slice(&words[..take]).to_vec())
                };
            let corners_from = (c.corner_base * TEXELS_PER_CORNER as u32 * 4) as usize;
            let corners_to =
                corners_from + (counts.corners * TEXELS_PER_CORNER as u32 * 4) as usize;
            out.push(GpuCasterReadback {
                classes: work[..f as usize].to_vec(),
                silhouettes,
                umbra: vertices(&c.umbra, counts.umbra_drawn.min(c.capacity.0))?,
                penumbra: vertices(&c.penumbra, counts.penumbra_drawn.min(c.capacity.1))?,
                corners: bytemuck::cast_slice(&corner_words[corners_from..corners_to]).to_vec(),
                corner_base: c.corner_base,
                counts,
            });
        }
        Ok(out)
    }
}

impl GpuCaster {
    fn new(
        ctx: &GpuContext,
        pass: &GeometryGpuPass,
        flat: &FlatCaster,
        capacity: (u32, u32),
        (corner_base, corner_capacity): (u32, u32),
        corners: &wgpu::Buffer,
    ) -> GpuCaster {
        use wgpu::util::DeviceExt;
        use wgpu::BufferUsages as U;
        let device = &ctx.device;
        let init = |label, bytes: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: U::STORAGE,
            })
        };
        let topo = init("GpuCaster::topo", bytemuck::cast_slice(&flat.topo));
        let geo = init("GpuCaster::geo", bytemuck::cast_slice(&flat.geo));
        let plain = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            })
        };
        let work = plain(
            "GpuCaster::work",
            flat.work_words() * 4,
            U::STORAGE | U::COPY_DST | U::COPY_SRC,
        );
        let tri_bytes = 3 * VERTEX_WORDS * 4;
        let umbra = plain(
            "GpuCaster::umbra",
            u64::from(capacity.0) * tri_bytes,
            U::STORAGE | U::VERTEX | U::COPY_SRC,
        );
        let penumbra = plain(
            "GpuCaster::penumbra",
            u64::from(capacity.1) * tri_bytes,
            U::STORAGE | U::VERTEX | U::COPY_SRC,
        );
        let state = plain(
            "GpuCaster::state",
            STATE_WORDS as u64 * 4,
            U::STORAGE | U::INDIRECT | U::COPY_DST | U::COPY_SRC,
        );
        let params = crate::render::uniform_buffer::<GeomParams>(device, "GpuCaster::params");
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("GpuCaster::bind_group"),
            layout: &pass.layout,
            entries: &[
                buffer_entry(0, &params),
                buffer_entry(1, &topo),
                buffer_entry(2, &geo),
                buffer_entry(3, &work),
                buffer_entry(4, &umbra),
                buffer_entry(5, &penumbra),
                buffer_entry(6, &state),
                buffer_entry(7, corners),
            ],
        });
        GpuCaster {
            flat_counts: (flat.faces, flat.edges, flat.vertices),
            convex: flat.convex,
            params,
            work,
            umbra,
            penumbra,
            state,
            bind_group,
            capacity,
            corner_base,
            corner_capacity,
        }
    }
}
