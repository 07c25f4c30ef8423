//! The paper's D-buffer in light space, which `dbuffer`, `dbuffer-center` and `dbuffer-fused`
//! keep: the geometry stage per light or caster move — on the CPU
//! (`geometry::PreparedCasters::build`: classes, silhouettes, volumes, then uploaded) or on the
//! GPU (`passes::geometry_gpu`, drawn with indirect draws, nothing read back), as the
//! `--geometry` knob ([`GEOMETRY`]) says — then the light pass: the session's shadow map
//! (`|cx_o|`) and the volume channels (`passes::dbuffer_volumes`), and its maps.

use std::time::Instant;

use super::{Channel, Empty, FrameInputs, LightMaps, SharedMaps};
use crate::geometry::volume_vertices::{
    drawn_volumes, reach_below, CORNERS_PER_ROW, MAX_CORNERS, TEXELS_PER_CORNER,
};
use crate::geometry::{SceneGeometry, VolumeParams};
use crate::render::adapter::Capabilities;
use crate::render::frame_tag::FrameTag;
use crate::render::gpu_scene::{VertexChunks, VolumeDraw};
use crate::render::passes::dbuffer_volumes::{
    CasterVolumes, DBufferVolumes, VolumeLayout, VolumeTargets,
};
use crate::render::passes::geometry_gpu::{
    GpuGeometry, GPU_GEOMETRY_DOWNLEVEL, GPU_GEOMETRY_STORAGE_BUFFERS,
};
use crate::render::passes::shadow_map::LightUniforms;
use crate::render::timer::Recorder;
use crate::render::{GpuContext, RenderError};
use crate::scene::AreaLight;

/// The D-buffer's channels, in `dbuffer.exr` order (R, G, B, A): textures 0 (`|cx_o|`), 1
/// (umbra: `|cx_uv|`, `|cx_s|`), 2 (penumbra: `|cx_pv|`, `|cx_s|`). `|cx_s|` is the umbra's
/// where it has one.
pub const CHANNELS: &[Channel] = &[
    Channel::new("|cx_o|", 0, 0, Empty::Far),
    Channel::new("|cx_uv|", 1, 0, Empty::NonPositive),
    Channel::new("|cx_pv|", 2, 0, Empty::NonPositive),
    Channel::new("|cx_s|", 1, 1, Empty::NonPositive).or(2, 1),
];

/// `--geometry`: where the D-buffer's geometry stage runs. `auto`: on the GPU where the adapter
/// has compute shaders, indirect draws and the storage buffers the stage binds, is a GPU or a
/// CPU rasteriser that runs the stage well for the scene ([`gpu_geometry_by_default`]), and
/// the scene's casters fit it; else on the CPU.
pub static GEOMETRY: super::Choice = super::Choice::new(
    "geometry",
    "dbuffer, dbuffer-center: where the geometry stage (face classes, silhouettes, volumes) \
     runs: auto = on the GPU where the adapter can and runs it well (a GPU; Mesa 25's lavapipe \
     from 131,072 caster triangles), cpu, gpu (the CPU where the adapter cannot)",
    &["auto", "cpu", "gpu"],
    0,
);

/// Whether an adapter of `caps` can run the geometry stage on the GPU.
pub fn gpu_geometry_runs(caps: &Capabilities) -> bool {
    caps.downlevel.contains(GPU_GEOMETRY_DOWNLEVEL)
        && caps.limits.max_storage_buffers_per_shader_stage >= GPU_GEOMETRY_STORAGE_BUFFERS
}

/// Whether `--geometry auto` runs the stage on the GPU on an adapter of `caps` for a scene of
/// `caster_triangles`: wherever it can, but on a CPU rasteriser only where it was measured to
/// win. There the "GPU" is the same cores running the stage as compute shaders, and it depends
/// on the driver and the scene (the 2-core VM, docs/results/performance.md): under Mesa 25.0.7's
/// lavapipe the GPU path moves the light over 1M triangles in 62.8 ms against the CPU path's 124
/// (28.0 against 35.4 at 256k) but loses below (9.2 against 7.7 at 64k), and on a scene of many
/// small casters its volumes, drawn over the whole view, cost the light pass twice the fill
/// (`fusion-many` at 256²: 172 against 84 ms); Mesa 22.3's takes 2,829 ms at 1M.
pub fn gpu_geometry_by_default(caps: &Capabilities, caster_triangles: usize) -> bool {
    gpu_geometry_runs(caps)
        && runs_the_stage_well(caps.device_type, caps.mesa_major(), caster_triangles)
}

/// Caster triangles from which `auto` takes the GPU stage on a CPU rasteriser that runs it well
/// (between the 64k where the CPU path still wins and the 256k where the GPU path does).
pub const CPU_ADAPTER_GPU_STAGE_TRIANGLES: usize = 1 << 17;

/// A GPU; or a CPU rasteriser of Mesa 25 or newer, for a scene of at least
/// [`CPU_ADAPTER_GPU_STAGE_TRIANGLES`] caster triangles ([`gpu_geometry_by_default`]).
fn runs_the_stage_well(
    device_type: wgpu::DeviceType,
    mesa_major: Option<u32>,
    caster_triangles: usize,
) -> bool {
    device_type != wgpu::DeviceType::Cpu
        || (mesa_major.is_some_and(|v| v >= 25)
            && caster_triangles >= CPU_ADAPTER_GPU_STAGE_TRIANGLES)
}

/// Where a build of the geometry stage ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeometryPath {
    Cpu,
    Gpu,
}

pub struct DBufferLight {
    center_silhouettes: bool,
    /// Whether the geometry stage may run on the GPU (not for `dbuffer-fused`, which reads the
    /// CPU stage's classes).
    gpu_allowed: bool,
    /// The GPU stage for this scene, or why it cannot run it; made on first use.
    gpu: Option<Result<GpuGeometry, String>>,
    /// Where the last build ran, and the revision the GPU stage must be recorded for (in the
    /// light pass, which has the encoder).
    path: GeometryPath,
    gpu_pending: Option<(AreaLight, VolumeParams, f32)>,
    /// The geometry, and the revision it was built for.
    geometry: Option<(SceneGeometry, u64)>,
    builds: u64,
    geometry_ms: f64,
    casters: Vec<CasterVolumes>,
    penumbra: Vec<VolumeDraw>,
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

impl DBufferLight {
    pub fn new(ctx: &GpuContext, center_silhouettes: bool) -> DBufferLight {
        DBufferLight {
            center_silhouettes,
            gpu_allowed: true,
            gpu: None,
            path: GeometryPath::Cpu,
            gpu_pending: None,
            geometry: None,
            builds: 0,
            geometry_ms: 0.0,
            casters: Vec::new(),
            penumbra: Vec::new(),
            volumes: DBufferVolumes::new(ctx),
            corners: corner_texture(ctx, &[]),
            made_for: None,
            view_proj: glam::Mat4::IDENTITY,
        }
    }

    /// The same, its geometry stage always on the CPU (what `dbuffer-fused` reads).
    pub fn on_cpu(ctx: &GpuContext, center_silhouettes: bool) -> DBufferLight {
        DBufferLight {
            gpu_allowed: false,
            ..DBufferLight::new(ctx, center_silhouettes)
        }
    }

    /// The geometry stage and the volumes' upload, when the light or a caster moved.
    fn update_geometry(&mut self, inputs: &FrameInputs<'_>, light: AreaLight) {
        let gpu = self.wants_gpu(inputs);
        let path = if gpu {
            GeometryPath::Gpu
        } else {
            GeometryPath::Cpu
        };
        if self.path == path
            && self
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
        if gpu {
            if let Some(Ok(gpu)) = &self.gpu {
                let t = Instant::now();
                let reach = reach_below(&light, inputs.surfaces.bounds);
                self.casters = gpu
                    .volumes()
                    .into_iter()
                    .map(|(umbra, _)| CasterVolumes {
                        // Its umbra's part of the view is not known without a readback.
                        rect: [0.0, 0.0, 1.0, 1.0],
                        umbra: VolumeDraw::Indirect(umbra),
                    })
                    .collect();
                self.penumbra = gpu
                    .volumes()
                    .into_iter()
                    .map(|(_, penumbra)| VolumeDraw::Indirect(penumbra))
                    .collect();
                self.gpu_pending = Some((light, params, reach));
                self.geometry_ms = t.elapsed().as_secs_f64() * 1e3;
                self.builds += 1;
                self.path = GeometryPath::Gpu;
                self.geometry = Some((SceneGeometry::default(), inputs.revision));
                self.made_for = None;
                return;
            }
        }
        self.path = GeometryPath::Cpu;
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
                umbra: VolumeDraw::Chunks(VertexChunks::new(device, "DBuffer::umbra", umbra)),
            })
            .collect();
        let penumbra = drawn.penumbra;
        self.penumbra = vec![VolumeDraw::Chunks(VertexChunks::new(
            device,
            "DBuffer::penumbra",
            &penumbra,
        ))];
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

    /// Whether this frame's geometry stage runs on the GPU: as [`GEOMETRY`] says, where the
    /// adapter can and the scene's casters fit the GPU stage (made here on first use).
    fn wants_gpu(&mut self, inputs: &FrameInputs<'_>) -> bool {
        let choice = inputs.knobs.get(&GEOMETRY);
        let wanted = match choice {
            1 => false,
            2 => true,
            _ => gpu_geometry_by_default(&inputs.ctx.caps, inputs.scene.caster_triangle_count()),
        };
        if !self.gpu_allowed || !wanted || !gpu_geometry_runs(&inputs.ctx.caps) {
            return false;
        }
        if self.gpu.is_none() {
            self.gpu = Some(GpuGeometry::new(inputs.ctx, inputs.prepared()));
        }
        matches!(self.gpu, Some(Ok(_)))
    }

    /// Where the last build of the geometry stage ran.
    pub fn geometry_path(&self) -> GeometryPath {
        self.path
    }

    /// Pick up the GPU stage's counts a frame or more after its build (never waits); `true`
    /// while they are on their way or have just arrived.
    pub fn poll_gpu_counts(&mut self) -> bool {
        match &mut self.gpu {
            Some(Ok(gpu)) if self.path == GeometryPath::Gpu => gpu.poll_counts(),
            _ => false,
        }
    }

    /// The GPU stage, once made (its last build read back by tests and `dbuffer inspect`).
    pub fn gpu_geometry(&self) -> Option<&GpuGeometry> {
        self.gpu.as_ref().and_then(|g| g.as_ref().ok())
    }

    /// The geometry stage (face classes, silhouettes, volumes) for the current light, when the
    /// light or a caster moved; an error naming `method` for a line light.
    pub fn geometry_stage(
        &mut self,
        inputs: &FrameInputs<'_>,
        method: &str,
    ) -> Result<(), RenderError> {
        let light = *inputs.area(method)?;
        self.update_geometry(inputs, light);
        Ok(())
    }

    /// The light pass after [`DBufferLight::geometry_stage`]: the shadow map and the volume
    /// channels, when something moved since they were made.
    pub fn light_pass(
        &mut self,
        inputs: &FrameInputs<'_>,
        shared: &mut SharedMaps,
        rec: &mut Recorder<'_>,
    ) -> Result<(), RenderError> {
        if let (Some((light, params, reach)), Some(Ok(gpu))) =
            (self.gpu_pending.take(), &mut self.gpu)
        {
            gpu.record(inputs.ctx, rec, &light, &params, Some(reach));
        }
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

    /// The volume channels, once drawn.
    pub fn targets(&self) -> Option<&VolumeTargets> {
        self.volumes.targets()
    }

    /// The closing fans' corners (`corners` of `shaders/methods/dbuffer.wgsl`).
    pub fn corners(&self) -> &wgpu::TextureView {
        match (&self.gpu, self.path) {
            (Some(Ok(gpu)), GeometryPath::Gpu) => &gpu.corner_view,
            _ => &self.corners,
        }
    }

    /// Its light-space maps: `|cx_o|` and the volume channels, once drawn.
    pub fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
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

    /// The CPU geometry stage's output (none where the GPU made the last build).
    pub fn geometry(&self) -> Option<&SceneGeometry> {
        self.geometry
            .as_ref()
            .filter(|_| self.path == GeometryPath::Cpu)
            .map(|(g, _)| g)
    }

    /// CPU milliseconds of its last geometry build, and how many builds it has made.
    pub fn geometry_builds(&self) -> (u64, f64) {
        (self.builds, self.geometry_ms)
    }

    /// Forget the volume channels: the next light pass draws them again.
    pub fn invalidate(&mut self) {
        self.made_for = None;
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

/// Milliseconds from a light move to volumes the light pass can draw, per run, on `path`: on
/// the CPU the geometry stage, the volumes laid out as drawn (`drawn_volumes`) and uploaded; on
/// the GPU the stage's compute passes recorded and run. Each run waits until the device is idle,
/// so both count what must be done before the light pass could draw (`bench`'s scaling curve).
/// The scene's casters are prepared (welded, adjacency, on the GPU its buffers) once, untimed.
pub fn light_move_ms(
    ctx: &GpuContext,
    scene: &crate::scene::Scene,
    path: GeometryPath,
    runs: usize,
) -> Result<Vec<f64>, RenderError> {
    let Some(light) = scene.light.as_area().copied() else {
        return Ok(Vec::new());
    };
    let prepared = crate::geometry::PreparedCasters::new(scene);
    let params = VolumeParams::for_scene(scene);
    let view = crate::geometry::light_view::LightView::fit(scene);
    let reach = reach_below(&light, scene.bounds());
    let mut gpu = match path {
        GeometryPath::Gpu => Some(GpuGeometry::new(ctx, &prepared).map_err(RenderError::Request)?),
        GeometryPath::Cpu => None,
    };
    let mut out = Vec::new();
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("light_move_ms"),
            });
        let kept = match &mut gpu {
            Some(gpu) => {
                let mut rec = Recorder::new(&mut encoder, None);
                gpu.record(ctx, &mut rec, &light, &params, Some(reach));
                Vec::new()
            }
            None => {
                let geometry = prepared.build(&light, &params);
                let drawn = drawn_volumes(&geometry, &light, &view, Some(reach));
                let mut kept: Vec<VertexChunks> = drawn
                    .umbrae
                    .iter()
                    .map(|(u, _)| VertexChunks::new(&ctx.device, "light_move_ms::umbra", u))
                    .collect();
                kept.push(VertexChunks::new(
                    &ctx.device,
                    "light_move_ms::penumbra",
                    &drawn.penumbra,
                ));
                kept
            }
        };
        ctx.queue.submit([encoder.finish()]);
        crate::render::readback::map_now(&ctx.device)?;
        out.push(t.elapsed().as_secs_f64() * 1e3);
        drop(kept);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::{runs_the_stage_well, CPU_ADAPTER_GPU_STAGE_TRIANGLES};
    use wgpu::DeviceType;

    #[test]
    fn auto_takes_the_gpu_on_a_gpu_and_on_mesa_25s_lavapipe_for_large_casters() {
        let large = CPU_ADAPTER_GPU_STAGE_TRIANGLES;
        for gpu in [
            DeviceType::DiscreteGpu,
            DeviceType::IntegratedGpu,
            DeviceType::VirtualGpu,
        ] {
            for tris in [0, 224, large] {
                assert!(runs_the_stage_well(gpu, None, tris));
                assert!(runs_the_stage_well(gpu, Some(22), tris));
            }
        }
        assert!(runs_the_stage_well(DeviceType::Cpu, Some(25), large));
        assert!(runs_the_stage_well(DeviceType::Cpu, Some(26), 4 * large));
        assert!(
            !runs_the_stage_well(DeviceType::Cpu, Some(25), large - 1),
            "many small casters: the CPU path"
        );
        assert!(!runs_the_stage_well(DeviceType::Cpu, Some(22), 4 * large));
        assert!(
            !runs_the_stage_well(DeviceType::Cpu, Some(24), large),
            "not measured"
        );
        assert!(
            !runs_the_stage_well(DeviceType::Cpu, None, large),
            "WARP, SwiftShader: not measured"
        );
    }
}
