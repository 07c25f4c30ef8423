//! The lab's reference traced on the GPU: a [`ViewSession`] with the GPU engine converges batch
//! by batch (the view shows visible / samples so far after each) to the CPU's reference on every
//! built-in, starts over when the light moves mid-way, and falls back to the CPU's worker where
//! the adapter cannot trace. `trace.rs` holds `gpu_reference::compute` to the CPU's reference;
//! these drive the progressive path the lab uses (`gpu_reference::Progressive`).

use std::time::{Duration, Instant};

use dbuffer::geometry::VtVariant;
use dbuffer::render::passes::view::{Mapping, View, ViewParams};
use dbuffer::render::truth::{self, Engine};
use dbuffer::render::view_session::{Intent, ViewSession};
use dbuffer::render::{gpu_reference, reference, FrameRequest, GpuContext, Knobs};
use dbuffer::scene::{self, builtin, Scene};

/// Ample time on a loaded machine; waits end as soon as what they wait for came.
const LIMIT: Duration = Duration::from_secs(120);
const K: u32 = 64;
const W: u32 = 48;
const H: u32 = 48;
/// Rays a batch: about four samples per pixel of a 48² view, so K = 64 takes many batches.
const BATCH_RAYS: u64 = 4 * (W * H) as u64;

fn view_session(scene: Scene, engine: Engine) -> ViewSession {
    let ctx = GpuContext::headless().unwrap_or_else(|e| panic!("{e}"));
    let mut v = ViewSession::new(ctx, scene);
    v.set_reference_engine(Some(engine));
    v.gpu_worker.limit_batch(BATCH_RAYS);
    v
}

fn intent() -> Intent {
    Intent {
        request: FrameRequest {
            width: W,
            height: H,
            dbuffer_size: 256,
            method: truth::SOFT,
            vt: VtVariant::Smoothstep,
            knobs: truth::with_samples(Knobs::default(), K),
            ..FrameRequest::default()
        },
        split: None,
        params: ViewParams {
            view: View::Final,
            channels: [true, false, false, false],
            mapping: Mapping::unit(),
        },
        probe: None,
        moving: false,
        wait: false,
    }
}

fn no_motion(_: &Scene, _: u32, _: u32) -> u64 {
    0
}

/// One window frame: advance, then wait (at most a few milliseconds) for the engine to have
/// something new. Returns the (done, total) the shown frame was drawn with.
fn frame(v: &mut ViewSession, ask: &Intent) -> Option<(u32, u32)> {
    let seen = v.reference_news();
    let update = v.advance(ask, &mut no_motion);
    assert!(update.errors.is_empty(), "{:?}", update.errors);
    let shown = v.shown(0).and_then(|s| s.reference);
    v.wait_for_reference(seen, Duration::from_millis(20));
    shown
}

/// Frames until the shown frame holds every sample; the (done, total) of each frame shown.
fn until_converged(v: &mut ViewSession, ask: &Intent) -> Vec<(u32, u32)> {
    let start = Instant::now();
    let mut seen = Vec::new();
    loop {
        let shown = frame(v, ask);
        seen.extend(shown);
        if shown.is_some_and(|(d, t)| d == t) {
            return seen;
        }
        assert!(
            start.elapsed() < LIMIT,
            "not converged in {LIMIT:?}: {seen:?}"
        );
    }
}

/// V of the shown frame.
fn shown_v(v: &mut ViewSession) -> Vec<f32> {
    v.read(0, None).unwrap_or_else(|e| panic!("{e}")).visibility
}

/// (mean |ΔV|, pixels that differ) of two images of V.
fn difference(a: &[f32], b: &[f32]) -> (f64, usize) {
    assert_eq!(a.len(), b.len());
    let sum: f64 = a.iter().zip(b).map(|(x, y)| f64::from((x - y).abs())).sum();
    let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
    (sum / a.len().max(1) as f64, differ)
}

/// The GPU engine's reference on every built-in against the CPU engine's, 48² at K = 64, both
/// through the view session as the lab drives it: many batches per reference (each frame shown
/// holds more samples than the last, and one mid-way shows visible / samples so far: the CPU's
/// progressive reference at that many samples, but for grazing rays), and the finished image
/// against the CPU engine's. Both trace the same samples from the same points in the same
/// order, so they differ only where a ray grazes an edge within rounding: the bound held is a
/// mean |ΔV| under 0.001 per scene and at most 1 % of all pixels differing at all (`trace.rs`
/// prints how few do).
#[test]
fn the_gpu_engine_converges_to_the_cpu_reference_on_every_builtin() {
    let (mut pixels, mut differ, mut worst_mean) = (0usize, 0usize, 0.0f64);
    let (mut partial_pixels, mut partial_differ, mut shaded) = (0usize, 0usize, 0usize);
    let ask = intent();
    for name in builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        // The CPU engine's finished frame, and the pixels where the frame shows the reference's
        // V as traced (the camera pass puts V = 0 where its own surface faces away from the
        // light, which the CPU's primary ray may not).
        let mut c = view_session(scene.clone(), Engine::Cpu);
        until_converged(&mut c, &ask);
        let cpu_frame = shown_v(&mut c);
        let cpu = reference::compute(&scene, W, H, K, &mut |_, _| {});
        let traced: Vec<bool> = cpu_frame
            .iter()
            .zip(&cpu.visibility)
            .map(|(f, v)| f == v)
            .collect();
        shaded += traced.iter().filter(|t| !**t).count();

        let mut v = view_session(scene.clone(), Engine::Gpu);
        assert_eq!(
            v.reference_engine(),
            Engine::Gpu,
            "lavapipe traces on the GPU"
        );
        // Frames until one mid-way: compare it with the CPU's reference at as many samples.
        let start = Instant::now();
        let partial = loop {
            if let Some((done, total)) = frame(&mut v, &ask) {
                if done >= K / 4 && done < total {
                    break done;
                }
                assert!(
                    done < total,
                    "{name}: done in one batch ({done} of {total})"
                );
            }
            assert!(start.elapsed() < LIMIT, "{name}: no partial reference");
        };
        let mut progressive = reference::start(&scene, W, H, K);
        progressive.step(partial as usize);
        let keep = |v: &[f32]| -> Vec<f32> {
            v.iter()
                .zip(&traced)
                .filter(|(_, t)| **t)
                .map(|(x, _)| *x)
                .collect()
        };
        let (mean, d) = difference(&keep(progressive.visibility()), &keep(&shown_v(&mut v)));
        assert!(
            mean < 1e-3,
            "{name}: at {partial} of {K} samples, mean |ΔV| {mean}"
        );
        partial_pixels += traced.len();
        partial_differ += d;

        let shown = until_converged(&mut v, &ask);
        assert!(
            shown.windows(2).all(|w| w[0].0 <= w[1].0),
            "{name}: samples only grow: {shown:?}"
        );
        let gpu = shown_v(&mut v);
        assert_eq!(v.tracing_progress().map(|(_, d, t)| (d, t)), Some((K, K)));
        assert!(!v.reference_busy(), "{name}: done");
        let (mean, d) = difference(&cpu_frame, &gpu);
        assert!(mean < 1e-3, "{name}: mean |ΔV| {mean}");
        worst_mean = worst_mean.max(mean);
        differ += d;
        pixels += gpu.len();
    }
    eprintln!(
        "the lab's GPU reference against the CPU's, {W}x{H}, K = {K}, {} built-ins: {differ} of \
         {pixels} pixels differ, worst mean |ΔV| {worst_mean:.2e}; mid-way {partial_differ} of \
         {partial_pixels} ({shaded} pixels the camera pass shades V = 0 left out)",
        builtin::names().len()
    );
    assert!(differ * 100 <= pixels, "{differ} of {pixels} pixels differ");
    assert!(partial_differ * 100 <= partial_pixels);
    assert!(
        shaded * 100 <= partial_pixels,
        "{shaded} pixels not the traced V"
    );
}

/// The light moved mid-way: the GPU's reference starts over, and the finished image is the new
/// light's reference (the CPU's, but for grazing rays), not the old one's.
#[test]
fn moving_the_light_mid_way_restarts_the_gpu_reference() {
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let mut v = view_session(scene.clone(), Engine::Gpu);
    let ask = intent();
    let start = Instant::now();
    let before = loop {
        if let Some((done, total)) = frame(&mut v, &ask) {
            if done >= K / 4 {
                assert!(done < total, "done in one batch");
                break done;
            }
        }
        assert!(start.elapsed() < LIMIT, "no partial reference");
    };
    let light = scene.light;
    let moved = light.with_center(light.center() + glam::Vec3::new(0.6, 0.0, 0.3));
    v.set_light(moved);
    // (samples, total) of each frame drawn with the new light.
    let mut shown = Vec::new();
    loop {
        let update = v.advance(&ask, &mut no_motion);
        assert!(update.errors.is_empty(), "{:?}", update.errors);
        let s = v
            .shown(0)
            .filter(|s| s.light == moved && s.note.is_none())
            .and_then(|s| s.reference);
        shown.extend(s);
        if s.is_some_and(|(d, t)| d == t) {
            break;
        }
        assert!(start.elapsed() < LIMIT, "not converged: {shown:?}");
        let seen = v.reference_news();
        v.wait_for_reference(seen, Duration::from_millis(20));
    }
    let key = v.tracing_progress().map(|(k, _, _)| k);
    assert_eq!(
        key.map(|k| k.light),
        Some(moved),
        "the new light's reference"
    );
    // The new light's frames start from few samples again, not from where the old one was
    // (a reference that went on would show more than `before` in its first frame).
    assert!(
        shown.first().is_some_and(|s| s.0 <= before),
        "no restart: {before} samples before, then {shown:?}"
    );
    let gpu = shown_v(&mut v);
    let mut new_scene = scene.clone();
    new_scene.light = moved;
    let new = reference::compute(&new_scene, W, H, K, &mut |_, _| {});
    let old = reference::compute(&scene, W, H, K, &mut |_, _| {});
    let (to_new, differ) = difference(&new.visibility, &gpu);
    let (to_old, _) = difference(&old.visibility, &gpu);
    eprintln!("after the move: mean |ΔV| {to_new:.2e} to the new light's, {to_old:.2e} to the old");
    assert!(
        to_new < 1e-3,
        "mean |ΔV| {to_new} to the new light's reference"
    );
    assert!(differ * 100 <= gpu.len(), "{differ} pixels differ");
    assert!(to_old > 0.01, "the move changes the shadow ({to_old})");
}

/// An adapter the tracer cannot run on: the view session's reference is the CPU worker's.
#[test]
fn where_the_adapter_cannot_trace_the_cpu_worker_does() {
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let mut v = view_session(scene.clone(), Engine::Gpu);
    v.set_reference_engine(None);
    // Auto: the GPU where it can trace, but the CPU's worker on an adapter that is itself the
    // CPU (lavapipe), whose rays are several times faster there.
    let cpu_adapter = v.ctx.adapter.device_type == wgpu::DeviceType::Cpu;
    assert_eq!(
        v.reference_engine(),
        if cpu_adapter {
            Engine::Cpu
        } else {
            Engine::Gpu
        },
        "auto: the GPU where it can, the CPU on a CPU adapter"
    );
    let limits = wgpu::Limits {
        max_storage_buffers_per_shader_stage: 0,
        ..wgpu::Limits::downlevel_webgl2_defaults()
    };
    v.ctx.caps = dbuffer::render::adapter::Capabilities::webgpu(
        &v.ctx.adapter,
        wgpu::Features::empty(),
        limits,
    );
    assert!(gpu_reference::refuses_on(&v.ctx.caps).is_some());
    assert_eq!(v.reference_engine(), Engine::Cpu);
    let ask = intent();
    until_converged(&mut v, &ask);
    assert!(v.worker.steps() > 0, "the CPU's worker cast the rays");
    assert_eq!(v.gpu_worker.news(), 0, "nothing traced on the GPU");
    let cpu = reference::compute(&scene, W, H, K, &mut |_, _| {});
    assert_eq!(shown_v(&mut v), cpu.visibility);
}

/// Dispatches bounded below one sample per pixel of the image (as a slow device's are): each
/// batch is traced in slices of pixels, one dispatch a frame, and read back after its last; the
/// finished image is the CPU's reference all the same.
#[test]
fn a_batch_traced_in_slices_of_pixels_is_the_whole_batch() {
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let mut v = view_session(scene.clone(), Engine::Gpu);
    v.gpu_worker.limit_batch(u64::from(W * H) / 4);
    let ask = intent();
    let start = Instant::now();
    let mut frames = 0u32;
    let mut shown = Vec::new();
    loop {
        let s = frame(&mut v, &ask);
        frames += 1;
        shown.extend(s);
        if s.is_some_and(|(d, t)| d == t) {
            break;
        }
        assert!(start.elapsed() < LIMIT, "not converged: {shown:?}");
    }
    // One sample per pixel a batch, each in several dispatches (frames).
    assert!(
        shown.contains(&(1, K)) && shown.contains(&(2, K)),
        "one sample per batch: {shown:?}"
    );
    assert!(frames > 2 * K, "{frames} frames for {K} batches in slices");
    let cpu = reference::compute(&scene, W, H, K, &mut |_, _| {});
    let (mean, differ) = difference(&cpu.visibility, &shown_v(&mut v));
    assert!(mean < 1e-3, "mean |ΔV| {mean}");
    assert!(
        differ * 100 <= cpu.visibility.len(),
        "{differ} pixels differ"
    );
}
