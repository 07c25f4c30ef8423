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

use crate::render::truth;
use std::time::Instant;

use crate::budget::MAX_COMPARE_PIXELS;
use crate::geometry::bvh::Bvh;
use crate::geometry::flip;
use crate::geometry::metrics::{self, HardMetrics, Metrics};
use crate::geometry::{view, VtVariant};
use crate::render::adapter::{Capabilities, Verdict};
use crate::render::offline::Offline;
use crate::render::truth::SAMPLES;
use crate::render::{Frame, FrameRequest, Knobs, Method, RenderError};
use crate::scene::{LightKind, Scene};

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
    /// Whether the image is within what a comparison may draw ([`MAX_COMPARE_PIXELS`]; the
    /// message names `--size`), checked before any frame.
    pub fn validate(&self) -> Result<(), String> {
        let (w, h) = (self.width, self.height);
        let pixels = u64::from(w) * u64::from(h);
        if pixels > MAX_COMPARE_PIXELS {
            return Err(format!(
                "--size {w}x{h} is {pixels} pixels: compare expects at most {MAX_COMPARE_PIXELS} \
                 (MAX_COMPARE_PIXELS, {} Mpixels: a method's frame, the reference's and their \
                 GPU targets stay within {} at that size)",
                MAX_COMPARE_PIXELS >> 20,
                crate::budget::bytes(crate::budget::MEMORY_BOUND_BYTES)
            ));
        }
        Ok(())
    }

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
    /// A temporal method's frames of history before the frame measured (0: its first frame);
    /// `None` for a method whose frame depends on nothing before it.
    pub history: Option<u32>,
}

impl MethodResult {
    /// The row's name: the method's, and a temporal method's first frame as `NAME-first-frame`.
    pub fn label(&self) -> String {
        label(self.method, self.history == Some(0))
    }
}

/// The name of `method`'s row (of its first frame, when `first`).
pub fn label(method: Method, first: bool) -> String {
    if first {
        format!("{}-first-frame", method.name())
    } else {
        method.name().to_string()
    }
}

/// The report's rows and the montage's tiles of `drawn`, in order: each method once, and a
/// temporal method twice — its first frame, then the frame after the history a still view has.
pub fn tiles(drawn: &[Method]) -> Vec<(Method, bool)> {
    let mut out = Vec::with_capacity(drawn.len());
    for &m in drawn {
        if m.spec().history.is_some() {
            out.push((m, true));
        }
        out.push((m, false));
    }
    out
}

/// A frame's shaded colour as FLIP takes it (sRGB, alpha dropped).
pub fn rgb_of(frame: &Frame) -> Vec<[u8; 3]> {
    frame.color.iter().map(|c| [c[0], c[1], c[2]]).collect()
}

/// Every method against the reference, every frame held ([`run`]: for a lab, a test, a small
/// image; `dbuffer compare` hands each method to its files as it finishes instead,
/// [`run_each`]).
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
    /// Which engine traced the reference's shadow rays.
    pub reference_engine: truth::Engine,
}

impl Comparison {
    pub fn reference(&self) -> &MethodResult {
        &self.results[0]
    }

    /// What the methods were measured against, as [`run_each`] hands it to each.
    pub fn against(&self) -> Against<'_> {
        Against {
            mask: &self.mask,
            reference: &self.reference().frame.visibility,
            exact: self
                .results
                .iter()
                .find(|r| r.method == truth::HARD)
                .map(|r| r.frame.visibility.as_slice()),
        }
    }

    /// The comparison without its frames.
    pub fn outline(&self) -> Outline {
        Outline {
            scene: self.scene.clone(),
            adapter: self.adapter.clone(),
            request: self.request,
            drawn: self
                .results
                .iter()
                .filter(|r| r.history != Some(0))
                .map(|r| r.method)
                .collect(),
            not_applicable: self.not_applicable.clone(),
            pixels: self.mask.iter().filter(|&&m| m).count(),
            reference_rays_per_s: self.reference_rays_per_s,
            reference_engine: self.reference_engine,
        }
    }
}

/// A comparison's setup and what it drew, without any frame: what the report needs besides its
/// rows.
#[derive(Clone, Debug)]
pub struct Outline {
    pub scene: String,
    pub adapter: String,
    pub request: CompareRequest,
    /// The methods drawn, the reference first, then the registry's order (the montage's tiles).
    pub drawn: Vec<Method>,
    /// As [`Comparison::not_applicable`].
    pub not_applicable: Vec<(Method, String, String)>,
    /// Pixels that count.
    pub pixels: usize,
    pub reference_rays_per_s: f64,
    /// Which engine traced the reference's shadow rays.
    pub reference_engine: truth::Engine,
}

/// Which methods a comparison draws, in the report's order, and which it cannot (with what
/// they need and why), known before any frame.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The reference, then every other method of the registry that takes the light and the
    /// adapter.
    pub drawn: Vec<Method>,
    pub not_applicable: Vec<(Method, String, String)>,
}

impl Plan {
    /// The plan for a scene lit by `light` on a device with `caps`.
    pub fn new(light: LightKind, caps: &Capabilities) -> Plan {
        Plan::with(light, caps, &[])
    }

    /// [`Plan::new`], with the users' methods (`--method file:PATH.wgsl`) among `named` after
    /// the registry's.
    pub fn with(light: LightKind, caps: &Capabilities, named: &[Method]) -> Plan {
        let mut drawn = vec![truth::SOFT];
        let mut not_applicable = Vec::new();
        let users = named.iter().filter(|m| m.is_user());
        for &method in Method::all().iter().chain(users) {
            if truth::is_soft(method) {
                continue;
            }
            if let Some(why) = method.refuses(light) {
                let needs = method.needs().map_or(String::new(), |kinds| {
                    let names: Vec<&str> = kinds.iter().map(|k| k.name()).collect();
                    names.join(", ")
                });
                not_applicable.push((method, needs, why));
                continue;
            }
            // A method the device cannot run is listed with what it lacks, before any work.
            if let Verdict::Cannot(missing) = method.on(caps) {
                let why = method.refuses_on(caps).unwrap_or_default();
                not_applicable.push((method, missing.join(", "), why));
                continue;
            }
            drawn.push(method);
        }
        Plan {
            drawn,
            not_applicable,
        }
    }

    /// Only `methods` of the plan (`compare --methods`), the reference always, and
    /// `reference-hard` too when a hard method is among them (they are scored against it). The
    /// others are left out of the report, not listed as not applicable.
    pub fn only(mut self, methods: &[Method]) -> Plan {
        let hard = methods.iter().any(|m| m.is_hard());
        let keep =
            |m: &Method| truth::is_soft(*m) || methods.contains(m) || (hard && truth::is_hard(*m));
        self.drawn.retain(keep);
        self.not_applicable.retain(|(m, ..)| keep(m));
        self
    }

    /// Whether `reference-hard` is drawn (the montage then has a fourth row).
    pub fn has_hard_reference(&self) -> bool {
        self.drawn.contains(&truth::HARD)
    }
}

/// What every method is measured against, held through a whole comparison: the pixels that
/// count, the reference's V and image, and once drawn the exact hard shadow (12 bytes a pixel,
/// 13 with it).
#[derive(Debug, Default)]
pub struct Baseline {
    pub mask: Vec<bool>,
    pub reference: Vec<f32>,
    pub reference_rgb: Vec<[u8; 3]>,
    /// `reference-hard`'s V, which the hard methods are scored against.
    pub exact: Option<Vec<f32>>,
}

impl Baseline {
    pub fn against(&self) -> Against<'_> {
        Against {
            mask: &self.mask,
            reference: &self.reference,
            exact: self.exact.as_deref(),
        }
    }
}

/// A method's yardsticks, borrowed: the pixels that count, the reference's V and the exact hard
/// shadow's (if drawn).
#[derive(Clone, Copy, Debug)]
pub struct Against<'a> {
    pub mask: &'a [bool],
    pub reference: &'a [f32],
    pub exact: Option<&'a [f32]>,
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

/// Render the reference and every method in one session, every frame held; `progress` hears
/// what is being done.
pub fn run(
    offline: &mut Offline,
    name: &str,
    scene: &Scene,
    request: &CompareRequest,
    progress: impl FnMut(&str),
) -> Result<Comparison, RenderError> {
    let mut results = Vec::new();
    let plan = Plan::new(scene.light.kind(), &offline.ctx.caps);
    let (outline, baseline) = run_each(
        offline,
        name,
        scene,
        request,
        plan,
        progress,
        |tile, _, r| -> Result<(), RenderError> {
            results.push((tile, r));
            Ok(())
        },
    )?;
    results.sort_by_key(|(tile, _)| *tile);
    Ok(Comparison {
        scene: outline.scene,
        adapter: outline.adapter,
        request: outline.request,
        mask: baseline.mask,
        results: results.into_iter().map(|(_, r)| r).collect(),
        not_applicable: outline.not_applicable,
        reference_rays_per_s: outline.reference_rays_per_s,
        reference_engine: outline.reference_engine,
    })
}

/// Render the reference and every method of `plan` ([`Plan::new`] for the scene's light and
/// the device, or [`Plan::only`] some of them) in one session, handing each measured
/// method to `each` as it finishes, with its tile (its place in the report's order) and what it
/// was measured against; a method's frame is let go of (on the CPU, and its textures on the
/// GPU) before the next one is drawn, so what a run holds is one method's frame and the
/// [`Baseline`], whatever the number of methods. The reference comes first, then
/// `reference-hard` (the hard methods' yardstick), then the others in registry order.
/// Returns the comparison's outline and its baseline.
pub fn run_each<E: From<RenderError>>(
    offline: &mut Offline,
    name: &str,
    scene: &Scene,
    request: &CompareRequest,
    plan: Plan,
    mut progress: impl FnMut(&str),
    mut each: impl FnMut(usize, &Against<'_>, MethodResult) -> Result<(), E>,
) -> Result<(Outline, Baseline), E> {
    request.knobs.validate().map_err(RenderError::Request)?;
    request.validate().map_err(RenderError::Request)?;
    // Every method is scored against the reference: without it there is nothing to compare.
    if let Some(why) = truth::SOFT.refuses_on(&offline.ctx.caps) {
        return Err(RenderError::Request(why).into());
    }
    for (method, _, why) in &plan.not_applicable {
        progress(&format!("{method}: not applicable ({why})"));
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
    let (reference, ref_report) = render(offline, &mut session, &frame_request(truth::SOFT))?;
    session.release(&offline.ctx, truth::SOFT)?;
    let rays_ms = cpu(&ref_report.cpu_ms, "reference_rays");
    let hit_pixels = ref_report.reference_rays.map_or(0, |(_, n)| n);
    let reference_rays_per_s = hit_pixels as f64 * f64::from(k) / (rays_ms.max(1e-9) * 1e-3);

    let facing = view::facing_light(
        scene,
        &Bvh::build(scene.all_triangles()),
        request.width,
        request.height,
    );
    let mask: Vec<bool> = facing
        .iter()
        .enumerate()
        .map(|(i, &f)| f && reference.hit(i))
        .collect();
    drop(facing);
    let mut base = Baseline {
        reference_rgb: rgb_of(&reference),
        reference: reference.visibility.clone(),
        mask,
        exact: None,
    };
    let tiles = tiles(&plan.drawn);
    let tile_of = |m: Method, first: bool| tiles.iter().position(|&t| t == (m, first)).unwrap_or(0);
    let tile = |m: Method| tile_of(m, false);
    let measured = measure(
        &base,
        request,
        truth::SOFT,
        reference,
        (rays_ms, cpu(&ref_report.cpu_ms, "frame_and_readback")),
    )?;
    each(tile(truth::SOFT), &base.against(), measured)?;
    // The exact hard shadow first: every hard method after it is scored against it.
    let mut order: Vec<Method> = plan
        .drawn
        .iter()
        .copied()
        .filter(|m| truth::is_hard(*m))
        .collect();
    order.extend(plan.drawn.iter().copied().filter(|m| !truth::is_truth(*m)));
    for method in order {
        progress(&format!("{method}: {}", method.description()));
        let req = frame_request(method);
        // The first frame of a pipeline includes shader compilation on some drivers: time the
        // second, with its light-space passes made again (the geometry is the first's).
        session.draw(&offline.ctx, &req)?;
        let (builds, geometry_ms) = session.geometry_builds(method);
        session.invalidate_light_maps();
        let cpu_ms = if builds > 0 { geometry_ms } else { 0.0 };
        // A temporal method: its first frame (no history), then the frame after the history a
        // user standing still has (its knob's frames), each scored and labelled.
        let history = method.spec().history.map(|k| req.knobs.get(k));
        if let Some(frames) = history {
            session.reset_history(method);
            let t = Instant::now();
            let frame = session.frame(&offline.ctx, &req)?;
            let wall_ms = t.elapsed().as_secs_f64() * 1e3;
            let mut first = measure(&base, request, method, frame, (cpu_ms, wall_ms))?;
            first.history = Some(0);
            each(tile_of(method, true), &base.against(), first)?;
            for _ in 1..frames {
                session.draw(&offline.ctx, &req)?;
            }
        }
        let t = Instant::now();
        // Read back with the method's own textures already let go of.
        let frame = session.frame_releasing(&offline.ctx, &req)?;
        let wall_ms = t.elapsed().as_secs_f64() * 1e3;
        if truth::is_hard(method) {
            base.exact = Some(frame.visibility.clone());
        }
        let mut measured = measure(&base, request, method, frame, (cpu_ms, wall_ms))?;
        measured.history = history;
        each(tile(method), &base.against(), measured)?;
    }
    let outline = Outline {
        scene: name.to_string(),
        adapter: offline.ctx.adapter_description(),
        request: *request,
        drawn: plan.drawn,
        not_applicable: plan.not_applicable,
        pixels: base.mask.iter().filter(|&&m| m).count(),
        reference_rays_per_s,
        reference_engine: offline.reference,
    };
    Ok((outline, base))
}

/// One frame of `request` read back, without the D-buffer's maps (nothing here writes them).
fn render(
    offline: &mut Offline,
    session: &mut crate::render::Session,
    request: &FrameRequest,
) -> Result<(Frame, crate::render::offline::FrameReport), RenderError> {
    let mut noop = |_: usize, _: usize| {};
    let progress: &mut dyn FnMut(usize, usize) = match offline.progress.as_mut() {
        Some(p) => p.as_mut(),
        None => &mut noop,
    };
    crate::render::offline::render_in(&offline.ctx, session, request, progress)
}

/// `frame` of `method` measured against `base`: its metrics, FLIP against the reference's
/// image, and for a hard method its score against the exact hard shadow.
fn measure(
    base: &Baseline,
    request: &CompareRequest,
    method: Method,
    frame: Frame,
    (cpu_ms, wall_ms): (f64, f64),
) -> Result<MethodResult, RenderError> {
    let flip = flip::ldr_flip(
        &base.reference_rgb,
        &rgb_of(&frame),
        request.width,
        request.height,
        flip::DEFAULT_PPD,
    )
    .map_err(|e| RenderError::Request(e.to_string()))?;
    let hard = base
        .exact
        .as_ref()
        .filter(|_| method.is_hard())
        .map(|exact| {
            metrics::compare_hard(
                exact,
                &frame.visibility,
                &base.mask,
                request.width,
                request.height,
            )
        });
    Ok(MethodResult {
        method,
        metrics: metrics::compare(&base.reference, &frame.visibility, &base.mask),
        gpu_ms: gpu_total(&frame),
        cpu_ms,
        wall_ms,
        hard,
        flip_mean: flip::mean(&flip),
        flip,
        frame,
        history: None,
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
