//! A frame: what to render ([`FrameRequest`]), where it stays on the GPU ([`FrameTargets`]), the
//! pass order ([`record_frame`]), and what comes back when someone asks ([`read_frame`] into a
//! [`Frame`]). Recording and reading back are two steps: the lab records frames and shows them
//! from the GPU; `render`, `compare`, `bench` and the tests read back.

use glam::{Mat4, Vec3};

pub use super::frame_data::Frame;
use super::gpu_scene::GpuScene;
pub use super::light_maps::LightMapsData;
use super::light_maps::{components, LightMaps};
use super::methods::{FrameInputs, Knobs, Method, MethodState, Prepare, SharedMaps};
use super::passes::camera::{Camera, CameraTargets, CameraUniforms};
use super::passes::probe::{Probe, ProbeTargets};
use super::passes::view::{View, ViewInputs, ViewParams, ViewTarget};
use super::readback::{f32s_of, Readback, TextureRead};
use super::timer::Recorder;
use super::{GpuContext, RenderError};
use crate::geometry::VtVariant;

/// What to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameRequest {
    pub width: u32,
    pub height: u32,
    /// The D-buffer (and every shadow map) is `dbuffer_size`² texels.
    pub dbuffer_size: u32,
    pub method: Method,
    pub vt: VtVariant,
    pub knobs: Knobs,
    /// Read the D-buffer back too (`dbuffer.exr`): the method's if it is a D-buffer method, else
    /// the paper's.
    pub read_dbuffer: bool,
    /// Read the cost target back too ([`Frame::cost`]: each pixel's work, for `compare`'s
    /// cost heatmaps and the tests of each method's cost view).
    pub read_cost: bool,
    /// Only the shaded colour is wanted (a window showing the final image, reading no pixel): the
    /// camera pass writes its colour and depth and leaves the V/t and cost targets as they were.
    /// On lavapipe those two targets' 16 bytes a pixel are about a third of a hard shadow's
    /// camera pass. A view or probe that reads them renders the frame again in full
    /// ([`Session::submit`](super::Session::submit)).
    pub colour_only: bool,
}

impl Default for FrameRequest {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            dbuffer_size: 1024,
            method: Method::DBUFFER,
            vt: VtVariant::Smoothstep,
            knobs: Knobs::default(),
            read_dbuffer: false,
            read_cost: false,
            colour_only: false,
        }
    }
}

impl FrameRequest {
    /// Sizes the device can draw and knobs in range, or why not (naming what is wrong).
    pub fn validate(&self, ctx: &GpuContext) -> Result<(), RenderError> {
        let max = ctx.max_texture_side();
        for (what, size) in [
            ("image width", self.width),
            ("image height", self.height),
            ("D-buffer size", self.dbuffer_size),
        ] {
            if size == 0 || size > max {
                return Err(RenderError::Size {
                    what,
                    size,
                    max,
                    adapter: ctx.adapter.name.clone(),
                });
            }
        }
        self.knobs.validate().map_err(RenderError::Request)
    }
}

/// Where a frame stays on the GPU: the camera pass's targets, and for the lab the view pass's
/// display texture. One per view that is shown (the lab has two: either side of a split).
pub struct FrameTargets {
    pub camera: Option<CameraTargets>,
    pub view: Option<ViewTarget>,
    /// The view last asked for is the final image (record_view): where the targets hold a
    /// colour-only frame, the viewport then shows the camera's colour target itself, not
    /// `view`'s display.
    final_view: bool,
    /// What the targets hold now.
    pub rendered: Option<Rendered>,
    /// Values read back from the targets a frame later (the inspector, the display range).
    pub probe: Option<Probe>,
}

/// The texture a viewport shows: the view pass's display, opaque in every view (the final
/// image's "no surface" black), so that a window draws nothing under it; or a colour-only frame's
/// colour target, opaque as it is drawn.
pub struct ShownTexture<'a> {
    pub texture: &'a wgpu::Texture,
    pub view: &'a wgpu::TextureView,
    pub width: u32,
    pub height: u32,
    /// Changes whenever the texture is another one (a viewport registers it again).
    pub generation: u64,
}

/// What a [`FrameTargets`] holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rendered {
    pub request: FrameRequest,
    /// The camera's world → clip transform the frame was drawn with.
    pub view_proj: Mat4,
    pub eye: Vec3,
}

impl FrameTargets {
    pub fn new() -> FrameTargets {
        FrameTargets {
            camera: None,
            view: None,
            final_view: false,
            rendered: None,
            probe: None,
        }
    }

    /// What a viewport shows of these targets, once something was recorded into them.
    pub fn shown(&self) -> Option<ShownTexture<'_>> {
        let colour_only = self.rendered.is_some_and(|r| r.request.colour_only);
        if let (true, true, Some(c)) = (self.final_view, colour_only, &self.camera) {
            return Some(ShownTexture {
                texture: &c.bytes_copy.as_ref().unwrap_or(&c.color).texture,
                view: &c.color_bytes,
                width: c.width,
                height: c.height,
                generation: c.generation,
            });
        }
        let d = self.view.as_ref()?.display()?;
        Some(ShownTexture {
            texture: &d.texture.texture,
            view: &d.texture.view,
            width: d.width,
            height: d.height,
            generation: d.generation,
        })
    }
}

impl ProbeTargets for FrameTargets {
    fn probe_parts(&mut self) -> (Option<(&CameraTargets, Mat4)>, &mut Option<Probe>) {
        let drawn = self.camera.as_ref().zip(self.rendered.map(|r| r.view_proj));
        (drawn, &mut self.probe)
    }
}

impl Default for FrameTargets {
    fn default() -> Self {
        Self::new()
    }
}

/// Everything one frame is recorded from.
pub struct FrameParts<'a> {
    pub inputs: FrameInputs<'a>,
    pub request: &'a FrameRequest,
    pub method: &'a mut dyn MethodState,
    pub shared: &'a mut SharedMaps,
    pub camera: &'a Camera,
    pub surfaces: &'a GpuScene,
}

/// One frame, in the order of the data flow (docs/development/architecture.md): the method's light-space passes (the D-buffer, shadow
/// maps: recorded only when the light or a caster moved since they were made), then the camera
/// pass (per pixel V and shading) into `targets`, then, for a window, the view it shows.
pub fn record_frame(
    parts: FrameParts<'_>,
    targets: &mut FrameTargets,
    view: Option<(&ViewParams, Option<(&wgpu::TextureView, u64)>)>,
    rec: &mut Recorder<'_>,
) -> Result<(), RenderError> {
    let FrameParts {
        inputs,
        request,
        method,
        shared,
        camera,
        surfaces,
    } = parts;
    let (ctx, scene) = (inputs.ctx, inputs.scene);
    let group = rec.group(&format!("{}: its passes", request.method), |rec| {
        method.prepare(Prepare(&inputs, shared, rec))
    })?;
    let polygon = scene.light.as_area().is_some_and(|a| a.corners().is_some());
    let Some(bindings) = group.bindings(&ctx.device, request.vt, polygon, request.colour_only)
    else {
        return Err(RenderError::Gpu("the method has no camera pipeline".into()));
    };
    let view_proj = inputs.view.view_proj;
    let uniforms = CameraUniforms::new(scene, view_proj);
    let FrameTargets {
        camera: camera_targets,
        rendered,
        ..
    } = targets;
    if camera_targets
        .as_ref()
        .is_some_and(|c| c.width != request.width || c.height != request.height)
    {
        *camera_targets = None;
    }
    let camera_targets = camera_targets.get_or_insert_with(|| {
        let bytes_view = ctx
            .caps
            .downlevel
            .contains(wgpu::DownlevelFlags::VIEW_FORMATS);
        CameraTargets::new(&ctx.device, request.width, request.height, bytes_view)
    });
    camera.record(ctx, rec, &uniforms, camera_targets, bindings, surfaces);
    camera_targets.copy_bytes(rec.encoder);
    *rendered = Some(Rendered {
        request: *request,
        view_proj,
        eye: scene.camera.eye,
    });
    if let Some((params, reference)) = view {
        record_view(
            ctx,
            targets,
            params,
            reference,
            method.light_maps(shared),
            rec,
        );
    }
    Ok(())
}

/// The view pass alone, over what `targets` hold.
pub fn record_view(
    ctx: &GpuContext,
    targets: &mut FrameTargets,
    params: &ViewParams,
    reference: Option<(&wgpu::TextureView, u64)>,
    maps: Option<LightMaps<'_>>,
    rec: &mut Recorder<'_>,
) {
    // The final image too goes through the pass, which makes it opaque (black where no surface):
    // shown as the camera's colour target itself it was transparent there, and a window had to
    // paint black under it — on a CPU rasteriser a blended layer the size of the viewport on
    // every repaint costs more than this pass on every render (`dbuffer gui --bench`). A
    // colour-only frame's (the lab's camera turning) is drawn opaque, and shown as it is: no
    // pass (1.4 ms a render of 695×750 on lavapipe).
    let FrameTargets {
        camera,
        view,
        rendered,
        final_view,
        ..
    } = targets;
    *final_view = params.view == View::Final;
    let (Some(camera), Some(rendered)) = (camera.as_ref(), rendered.as_ref()) else {
        return;
    };
    if *final_view && rendered.request.colour_only {
        return;
    }
    let inputs = ViewInputs {
        camera,
        camera_view_proj: rendered.view_proj,
        reference,
        maps,
    };
    view.get_or_insert_with(|| ViewTarget::new(ctx))
        .record(ctx, rec, &inputs, params);
}

/// Read the frame in `targets` back, with `maps` if given; one submit and one wait (per band of
/// rows where a target is larger than a staging buffer).
pub fn read_frame(
    ctx: &GpuContext,
    readback: &mut Readback,
    targets: &FrameTargets,
    maps: Option<&LightMaps<'_>>,
) -> Result<Frame, RenderError> {
    let (Some(camera), Some(rendered)) = (&targets.camera, &targets.rendered) else {
        return Err(RenderError::Readback(
            "nothing has been rendered yet".into(),
        ));
    };
    if rendered.request.colour_only {
        return Err(RenderError::Readback(
            "the frame was rendered colour-only: render it in full to read its V".into(),
        ));
    }
    let depth_copy = if reads_depth_whole(ctx, &camera.depth.texture) {
        None
    } else {
        Some(super::passes::depth_copy::copy(ctx, &camera.depth)?)
    };
    let mut reads = vec![
        TextureRead::color(&camera.color.texture, 4),
        TextureRead::color(&camera.data.texture, 8),
        match &depth_copy {
            Some(copy) => TextureRead::color(&copy.texture, 4),
            None => TextureRead::depth(&camera.depth.texture),
        },
    ];
    let read_cost = rendered.request.read_cost;
    if read_cost {
        reads.push(TextureRead::color(&camera.cost.texture, 8));
    }
    // The light maps' reads come after the frame's.
    let first_map = reads.len();
    let (slots, distinct) = maps.map_or(([0; 3], Vec::new()), distinct_textures);
    for t in &distinct {
        reads.push(TextureRead::color(t, 4 * components(t.format()) as u32));
    }
    let (w, h) = (camera.width, camera.height);
    let n = w as usize * h as usize;
    let mut frame = Frame {
        width: w,
        height: h,
        color: Vec::with_capacity(n),
        visibility: Vec::with_capacity(n),
        t_branch: Vec::with_capacity(n),
        depth: Vec::with_capacity(n),
        cost: Vec::with_capacity(if read_cost { n } else { 0 }),
        inverse_view_proj: rendered.view_proj.inverse(),
        dbuffer_size: rendered.request.dbuffer_size,
        maps: None,
        gpu_ms: Vec::new(),
    };
    let mut map_values: Vec<Vec<f32>> = distinct
        .iter()
        .map(|t| {
            Vec::with_capacity(t.width() as usize * t.height() as usize * components(t.format()))
        })
        .collect();
    // Every row straight into its place: no texture is ever held whole as raw bytes.
    readback.read_rows(ctx, &reads, &mut |k, _, row| match k {
        0 => frame
            .color
            .extend(row.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]])),
        1 => {
            let mut values = f32s_of(row);
            while let (Some(v), Some(tb)) = (values.next(), values.next()) {
                frame.visibility.push(v);
                frame.t_branch.push(tb);
            }
        }
        2 => frame.depth.extend(f32s_of(row)),
        3 if read_cost => {
            let mut values = f32s_of(row);
            while let (Some(work), Some(path)) = (values.next(), values.next()) {
                frame.cost.push([work, path]);
            }
        }
        k => {
            if let Some(m) = map_values.get_mut(k - first_map) {
                m.extend(f32s_of(row));
            }
        }
    })?;
    if frame.color.len() != n
        || frame.visibility.len() != n
        || frame.depth.len() != n
        || (read_cost && frame.cost.len() != n)
    {
        return Err(RenderError::Readback(
            "a target did not come back whole".into(),
        ));
    }
    frame.maps = maps.map(|m| LightMapsData::read(m, 0..m.size, slots, &distinct, map_values));
    Ok(frame)
}

/// Whether the camera's `depth` is copied into a buffer as it is: the device can copy a depth
/// texture (GL cannot) and the whole of it fits one staging buffer (WebGPU copies no part of a
/// depth texture, and [`Readback`] reads larger textures in bands of rows). Otherwise the frame
/// reads the depth's exact `R32Float` copy ([`depth_copy`](super::passes::depth_copy)), in bands
/// like any colour target: above 2,896² on a 32 MiB staging cap.
pub fn reads_depth_whole(ctx: &GpuContext, depth: &wgpu::Texture) -> bool {
    ctx.caps
        .downlevel
        .contains(wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES)
        && super::readback::fits_whole(ctx, depth, 4)
}

/// Each distinct texture of `maps` once, and which of them each slot is.
fn distinct_textures<'a>(maps: &LightMaps<'a>) -> ([usize; 3], Vec<&'a wgpu::Texture>) {
    let mut slots = [0usize; 3];
    let mut distinct: Vec<&wgpu::Texture> = Vec::new();
    for (slot, raw) in slots.iter_mut().zip(maps.raw) {
        *slot = match distinct.iter().position(|t| *t == raw) {
            Some(k) => k,
            None => {
                distinct.push(raw);
                distinct.len() - 1
            }
        };
    }
    (slots, distinct)
}

/// Rows `rows` of the light-space maps `maps` (a band of them: a render's 8192² D-buffer is
/// written to its files a band at a time, never held whole).
pub fn read_light_map_rows(
    ctx: &GpuContext,
    readback: &mut Readback,
    maps: &LightMaps<'_>,
    rows: std::ops::Range<u32>,
) -> Result<LightMapsData, RenderError> {
    let (slots, distinct) = distinct_textures(maps);
    let reads: Vec<TextureRead<'_>> = distinct
        .iter()
        .map(|t| TextureRead::color(t, 4 * components(t.format()) as u32).rows(rows.clone()))
        .collect();
    let mut values: Vec<Vec<f32>> = reads
        .iter()
        .map(|r| {
            Vec::with_capacity(
                r.texture.width() as usize * r.rows.len() * components(r.texture.format()),
            )
        })
        .collect();
    readback.read_rows(ctx, &reads, &mut |k, _, row| {
        if let Some(v) = values.get_mut(k) {
            v.extend(f32s_of(row));
        }
    })?;
    let rows = reads.first().map_or(0..0, |r| r.rows.clone());
    Ok(LightMapsData::read(maps, rows, slots, &distinct, values))
}
