//! `dbuffer compare`: every method and the ray-cast reference from the same view, measured
//! against it (docs/method/metrics.md) — the numbers and pictures that show where the D-buffer is right and
//! where the alternatives are not.
//!
//! Which pixels count: those where the GPU hit a surface that faces the light (the CPU's view of
//! the same pixels decides "faces the light", as in the accuracy tests).
//!
//! Under a line light the reference casts rays to stratified points on the segment, and the
//! methods that need a disk (the D-buffer family, `wedges`, `pcss`) are listed as not
//! applicable with their reason instead of being drawn (and `linear-ssm` under a disk).

pub mod heatmap;
pub mod montage;
pub mod report;
pub mod temporal;

use std::time::Instant;

use crate::geometry::bvh::Bvh;
use crate::geometry::flip;
use crate::geometry::metrics::{self, HardMetrics, Metrics};
use crate::geometry::{view, VtVariant};
use crate::render::adapter::Verdict;
use crate::render::methods::reference::SAMPLES;
use crate::render::offline::Offline;
use crate::render::{Frame, FrameRequest, Knobs, Method, RenderError};
use crate::scene::Scene;

/// What to compare.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompareRequest {
    pub width: u32,
    pub height: u32,
    pub dbuffer_size: u32,
    /// The V(t) variant of the D-buffer methods.
    pub vt: VtVariant,
    /// The knobs of every method; the reference's `samples` is its K.
    pub knobs: Knobs,
}

impl CompareRequest {
    /// The reference's disk samples per pixel.
    pub fn samples(&self) -> u32 {
        self.knobs.get(&SAMPLES)
    }
}

/// One method measured against the reference.
#[derive(Debug)]
pub struct MethodResult {
    pub method: Method,
    pub frame: Frame,
    pub metrics: Metrics,
    /// GPU milliseconds of the method's own passes (timestamp queries), if the adapter has them.
    pub gpu_ms: Option<f64>,
    /// CPU milliseconds of the method's own per-frame work: the geometry stage for the D-buffer
    /// methods, the ray casting for the reference, nothing for the shadow-map methods.
    pub cpu_ms: f64,
    /// Wall milliseconds of the measured frame (readback included).
    pub wall_ms: f64,
    /// For a hard method (one that uses the light's centre as a point light), measured against
    /// `reference-hard` too.
    pub hard: Option<HardMetrics>,
    /// FLIP of its shaded image against the reference's, per pixel ([`flip::ldr_flip`] at
    /// [`flip::DEFAULT_PPD`]).
    pub flip: Vec<f32>,
    /// The mean of `flip` over every pixel (FLIP's own headline number).
    pub flip_mean: f64,
}

/// A frame's shaded colour as FLIP takes it (sRGB, alpha dropped).
pub fn rgb_of(frame: &Frame) -> Vec<[u8; 3]> {
    frame.color.iter().map(|c| [c[0], c[1], c[2]]).collect()
}

/// Every method against the reference.
#[derive(Debug)]
pub struct Comparison {
    pub scene: String,
    pub adapter: String,
    pub request: CompareRequest,
    /// The pixels that count.
    pub mask: Vec<bool>,
    /// The reference first, then every other method in registry order that takes the scene's
    /// light.
    pub results: Vec<MethodResult>,
    /// The methods that refuse the scene's light (a disk-only method under a line light, or
    /// the reverse) or the adapter: each with what it needs (`"disk"`, `"line"`, or what the
    /// adapter lacks) and its one-line reason.
    pub not_applicable: Vec<(Method, String, String)>,
    /// Reference shadow rays per second (all cores).
    pub reference_rays_per_s: f64,
}

impl Comparison {
    pub fn reference(&self) -> &MethodResult {
        &self.results[0]
    }
}

/// The pixels every metric counts: the ones where `frame` shows a surface (any frame of the
/// view) and the CPU's receiver under the pixel faces the light (`receivers` from
/// [`view::receivers`] at the frame's size).
pub fn counted_pixels(receivers: &[Option<view::Receiver>], frame: &Frame) -> Vec<bool> {
    receivers
        .iter()
        .enumerate()
        .map(|(i, r)| frame.hit(i) && r.is_some_and(|r| r.faces_light))
        .collect()
}

/// Render the reference and every method in one session; `progress` hears what is being done.
pub fn run(
    offline: &mut Offline,
    name: &str,
    scene: &Scene,
    request: &CompareRequest,
    mut progress: impl FnMut(&str),
) -> Result<Comparison, RenderError> {
    request.knobs.validate().map_err(RenderError::Request)?;
    // Every method is scored against the reference: without it there is nothing to compare.
    if let Some(why) = Method::REFERENCE.refuses_on(&offline.ctx.caps) {
        return Err(RenderError::Request(why));
    }
    let frame_request = |method| FrameRequest {
        width: request.width,
        height: request.height,
        dbuffer_size: request.dbuffer_size,
        method,
        vt: request.vt,
        knobs: request.knobs,
        read_dbuffer: false,
        // Each method's work per pixel: its cost heatmap.
        read_cost: true,
        colour_only: false,
    };
    let k = request.samples();
    progress(&format!(
        "reference: {} rays per pixel over {}x{}",
        k, request.width, request.height
    ));
    let mut session = offline.session(scene.clone());
    let (reference, ref_report) =
        offline.render_in(&mut session, &frame_request(Method::REFERENCE))?;
    let rays_ms = cpu(&ref_report.cpu_ms, "reference_rays");
    let hit_pixels = ref_report.reference_rays.map_or(0, |(_, n)| n);
    let reference_rays_per_s = hit_pixels as f64 * f64::from(k) / (rays_ms.max(1e-9) * 1e-3);

    let receivers = view::receivers(
        scene,
        &Bvh::build(scene.all_triangles()),
        request.width,
        request.height,
    );
    let mask = counted_pixels(&receivers, &reference);

    let mut results = vec![MethodResult {
        method: Method::REFERENCE,
        metrics: metrics::compare(&reference.visibility, &reference.visibility, &mask),
        gpu_ms: gpu_total(&reference),
        cpu_ms: rays_ms,
        wall_ms: cpu(&ref_report.cpu_ms, "frame_and_readback"),
        frame: reference,
        hard: None,
        flip: Vec::new(),
        flip_mean: 0.0,
    }];
    let mut not_applicable = Vec::new();
    for &method in Method::all() {
        if method.is_reference() {
            continue;
        }
        if let Some(why) = method.refuses(scene.light.kind()) {
            progress(&format!("{method}: not applicable ({why})"));
            let needs = method.needs().map_or(String::new(), |kinds| {
                let names: Vec<&str> = kinds.iter().map(|k| k.name()).collect();
                names.join(", ")
            });
            not_applicable.push((method, needs, why));
            continue;
        }
        // A method the device cannot run is listed with what it lacks, before any work.
        if let Verdict::Cannot(missing) = method.on(&offline.ctx.caps) {
            let why = method.refuses_on(&offline.ctx.caps).unwrap_or_default();
            progress(&format!("{method}: not applicable ({why})"));
            not_applicable.push((method, missing.join(", "), why));
            continue;
        }
        progress(&format!("{method}: {}", method.description()));
        let req = frame_request(method);
        // The first frame of a pipeline includes shader compilation on some drivers: time the
        // second, with its light-space passes made again.
        offline.render_in(&mut session, &req)?;
        session.invalidate_light_maps();
        let t = Instant::now();
        let (frame, _) = offline.render_in(&mut session, &req)?;
        let wall_ms = t.elapsed().as_secs_f64() * 1e3;
        let (builds, geometry_ms) = session.geometry_builds(method);
        results.push(MethodResult {
            method,
            metrics: metrics::compare(&results[0].frame.visibility, &frame.visibility, &mask),
            gpu_ms: gpu_total(&frame),
            cpu_ms: if builds > 0 { geometry_ms } else { 0.0 },
            wall_ms,
            frame,
            hard: None,
            flip: Vec::new(),
            flip_mean: 0.0,
        });
    }
    // FLIP of every shaded image against the reference's (the reference's own: 0).
    let reference_rgb = rgb_of(&results[0].frame);
    for r in &mut results {
        r.flip = flip::ldr_flip(
            &reference_rgb,
            &rgb_of(&r.frame),
            request.width,
            request.height,
            flip::DEFAULT_PPD,
        )
        .map_err(|e| RenderError::Request(e.to_string()))?;
        r.flip_mean = flip::mean(&r.flip);
    }
    // Every hard method against the exact hard shadow as well.
    let hard_reference = results
        .iter()
        .find(|r| r.method == Method::REFERENCE_HARD)
        .map(|r| r.frame.visibility.clone());
    if let Some(exact) = hard_reference {
        for r in results.iter_mut().filter(|r| r.method.is_hard()) {
            r.hard = Some(metrics::compare_hard(
                &exact,
                &r.frame.visibility,
                &mask,
                request.width,
                request.height,
            ));
        }
    }
    Ok(Comparison {
        scene: name.to_string(),
        adapter: offline.ctx.adapter_description(),
        request: *request,
        mask,
        results,
        not_applicable,
        reference_rays_per_s,
    })
}

fn cpu(list: &[(String, f64)], stage: &str) -> f64 {
    list.iter()
        .find(|(s, _)| s == stage)
        .map_or(0.0, |(_, ms)| *ms)
}

fn gpu_total(frame: &Frame) -> Option<f64> {
    (!frame.gpu_ms.is_empty()).then(|| frame.gpu_ms.iter().map(|(_, ms)| ms).sum())
}
