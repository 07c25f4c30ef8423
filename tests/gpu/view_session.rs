//! The lab's view logic without a window: a [`ViewSession`] driven through its intents as the
//! lab drives it once per window frame. The soft truth converges on its CPU worker (the engine
//! forced here; `reference_gpu_view` drives the GPU's) and is shaded;
//! a probe under the cursor is answered with the shown frame's values; the FLIP view's map is
//! computed on a thread other than the caller's and uploaded when it arrives; pass timings of a
//! method no longer shown never come back as the shown method's.

use std::time::{Duration, Instant};

use dbuffer::geometry::VtVariant;
use dbuffer::render::passes::probe::{PixelValues, ProbeRequest};
use dbuffer::render::passes::view::{Mapping, View, ViewParams};
use dbuffer::render::truth;
use dbuffer::render::view_session::{Intent, PixelProbe, Update, ViewSession};
use dbuffer::render::{FrameRequest, GpuContext, Knobs, Method};
use dbuffer::scene::{self, Scene};

/// Ample time for a worker on a loaded machine; waits end as soon as what they wait for came.
const LIMIT: Duration = Duration::from_secs(120);
const SAMPLES: u32 = 8;
const W: u32 = 64;
const H: u32 = 48;

fn view_session() -> ViewSession {
    let ctx = GpuContext::headless().unwrap_or_else(|e| panic!("{e}"));
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let mut v = ViewSession::new(ctx, scene);
    v.set_reference_engine(Some(truth::Engine::Cpu));
    v
}

fn intent(method: Method, view: View) -> Intent {
    Intent {
        request: FrameRequest {
            width: W,
            height: H,
            dbuffer_size: 256,
            method,
            vt: VtVariant::Smoothstep,
            knobs: truth::with_samples(Knobs::default(), SAMPLES),
            ..FrameRequest::default()
        },
        split: None,
        params: ViewParams {
            view,
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

/// Advance as a window does (again when the worker has news, or a few milliseconds later)
/// until `done`; every update is handed to `each`.
fn advance_until(
    v: &mut ViewSession,
    intent: &Intent,
    mut each: impl FnMut(&ViewSession, &Update),
    done: impl Fn(&ViewSession) -> bool,
) {
    let start = Instant::now();
    loop {
        let seen = v.reference_news();
        let update = v.advance(intent, &mut no_motion);
        assert!(update.errors.is_empty(), "{:?}", update.errors);
        each(v, &update);
        if done(v) {
            return;
        }
        assert!(start.elapsed() < LIMIT, "not done in {LIMIT:?}");
        v.wait_for_reference(seen, Duration::from_millis(5));
    }
}

fn converged(v: &ViewSession) -> bool {
    v.session
        .reference_progress()
        .is_some_and(|(done, total)| done == total)
}

#[test]
fn the_soft_truth_converges_and_a_probe_is_answered() {
    let mut v = view_session();
    let mut ask = intent(truth::SOFT, View::Final);
    let first = v.advance(&ask, &mut no_motion);
    assert!(first.errors.is_empty(), "{:?}", first.errors);
    let mut samples_seen = Vec::new();
    advance_until(
        &mut v,
        &ask,
        |v, _| {
            if let Some(r) = v.shown(0).and_then(|s| s.reference) {
                samples_seen.push(r.0);
            }
        },
        |v| {
            converged(v)
                && v.shown(0)
                    .is_some_and(|s| s.reference == Some((SAMPLES, SAMPLES)))
        },
    );
    let shown = v.shown(0).expect("the reference is shown").clone();
    assert_eq!(shown.method, truth::SOFT);
    assert_eq!(shown.note, None);
    assert!(
        samples_seen.windows(2).all(|w| w[0] <= w[1]),
        "samples only grow: {samples_seen:?}"
    );
    let frame = v.read(0, None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((frame.width, frame.height), (W, H));

    // A probe at a pixel, answered (a waiting caller gets it in the same advance) with V there.
    let (x, y) = (W / 2, H * 2 / 3);
    ask.probe = Some(PixelProbe { side: 0, x, y });
    ask.wait = true;
    let update = v.advance(&ask, &mut no_motion);
    assert!(update.errors.is_empty(), "{:?}", update.errors);
    let answer = update.probes[0]
        .iter()
        .find(
            |r| matches!(r.request, ProbeRequest::Pixel { x: px, y: py, .. } if (px, py) == (x, y)),
        )
        .expect("the probe's answer");
    let values = PixelValues::decode(&answer.values).expect("a pixel's values");
    let v_there = frame.visibility[(y * W + x) as usize];
    assert!(
        (values.visibility - v_there).abs() < 1e-6,
        "probe V {} against the frame's {v_there}",
        values.visibility
    );
    // Asked again with nothing changed: not probed again, nothing rendered.
    let again = v.advance(&ask, &mut no_motion);
    assert_eq!(again.submitted.map(|s| s.renders), Some(0));
    assert!(again.probes.iter().all(|p| p.is_empty()));
}

#[test]
fn flip_is_computed_off_the_callers_thread_and_uploaded_when_ready() {
    let mut v = view_session();
    let ask = intent(Method::DBUFFER, View::Flip);
    let mut returned_pending = false;
    advance_until(
        &mut v,
        &ask,
        |v, _| returned_pending |= v.flip_pending(),
        |v| converged(v) && v.flips_made() > 0 && !v.flip_pending(),
    );
    let thread = v.flip_thread().expect("the thread the map was computed on");
    assert_ne!(
        thread,
        std::thread::current().id(),
        "FLIP ran on the caller's thread"
    );
    println!("an advance returned while FLIP was still being computed: {returned_pending}");
    // The next advance draws the view with the map; nothing is computed again.
    let made = v.flips_made();
    let update = v.advance(&ask, &mut no_motion);
    assert!(update.errors.is_empty(), "{:?}", update.errors);
    assert!(!v.flip_pending());
    assert_eq!(v.flips_made(), made);
    let shown = v.shown(0).expect("the method is shown");
    assert_eq!(shown.method, Method::DBUFFER);
    assert_eq!(shown.note, None);
}

#[test]
fn timings_of_a_method_no_longer_shown_are_never_handed_back() {
    let mut v = view_session();
    if !v.ctx.timestamps {
        println!("skipped: the adapter has no timestamp queries");
        return;
    }
    let passes = |u: &Update| -> Vec<String> {
        u.timings.iter().flatten().map(|(p, _)| p.clone()).collect()
    };
    // Everything dbuffer times, then everything dbuffer-fused times, until both came back.
    let seen = |v: &mut ViewSession, method: Method| -> Vec<String> {
        let ask = intent(method, View::Final);
        let mut all: Vec<String> = Vec::new();
        let start = Instant::now();
        while all.is_empty() {
            assert!(start.elapsed() < LIMIT, "no timings of {method}");
            let u = v.advance(&ask, &mut no_motion);
            all.extend(passes(&u));
            let _ = v.ctx.device.poll(wgpu::PollType::wait_indefinitely());
        }
        all
    };
    let plain = seen(&mut v, Method::DBUFFER);
    let fused = seen(&mut v, Method::DBUFFER_FUSED);
    let own: Vec<String> = fused.into_iter().filter(|p| !plain.contains(p)).collect();
    assert!(!own.is_empty(), "dbuffer-fused times passes of its own");
    // A fused frame submitted, and at once the switch back: its timings arrive during the
    // dbuffer frames and must not be handed back as theirs.
    let fused_ask = intent(Method::DBUFFER_FUSED, View::Final);
    let light = v.scene().light;
    v.set_light(light.with_center(light.center() + glam::Vec3::new(0.01, 0.0, 0.0)));
    let u = v.advance(&fused_ask, &mut no_motion);
    assert_eq!(u.submitted.map(|s| s.renders), Some(1));
    let back = intent(Method::DBUFFER, View::Final);
    for k in 0..6 {
        let u = v.advance(&back, &mut no_motion);
        assert_eq!(u.methods_changed, k == 0);
        let stale: Vec<String> = passes(&u).into_iter().filter(|p| own.contains(p)).collect();
        assert!(stale.is_empty(), "dbuffer's timings list {stale:?}");
        let _ = v.ctx.device.poll(wgpu::PollType::wait_indefinitely());
    }
}

/// Debug → Capture frame: the next advance draws the whole frame again (V and t too, not only
/// the colour a still view keeps) inside a graphics-debugger capture, and says so; the one
/// after is as before. Without RenderDoc attached wgpu's capture calls do nothing, so this
/// holds what the lab does around them, not what RenderDoc records.
#[test]
fn capture_next_frame_redraws_the_frame_inside_a_capture_once() {
    let mut v = view_session();
    let still = intent(Method::DBUFFER, View::Final);
    let first = v.advance(&still, &mut no_motion);
    assert!(first.errors.is_empty(), "{:?}", first.errors);
    assert!(!first.captured);
    let idle = v.advance(&still, &mut no_motion);
    assert_eq!(
        idle.submitted.map_or(0, |s| s.renders),
        0,
        "nothing changed"
    );
    v.capture_next_frame();
    let captured = v.advance(&still, &mut no_motion);
    assert!(captured.errors.is_empty(), "{:?}", captured.errors);
    assert!(captured.captured);
    assert!(
        captured.submitted.map_or(0, |s| s.renders) >= 1,
        "the captured advance draws the frame again"
    );
    let after = v.advance(&still, &mut no_motion);
    assert!(!after.captured, "one frame only");
}

/// A changed shader file drops exactly the pipelines made from it (`GpuContext::forget_shaders`,
/// from what each cached object recorded while it was made), and the view draws again after
/// `ViewSession::shaders_changed`.
#[test]
fn a_changed_shader_drops_only_the_pipelines_made_from_it() {
    let files = |names: &[&str]| -> std::collections::BTreeSet<String> {
        names.iter().map(|n| n.to_string()).collect()
    };
    let vsm: Method = "vsm".parse().expect("vsm");
    let mut v = view_session();
    for m in [Method::DBUFFER, vsm] {
        let u = v.advance(&intent(m, View::Visibility), &mut no_motion);
        assert!(u.errors.is_empty(), "{m}: {:?}", u.errors);
    }
    // No pipeline was made from pcss's shader; vsm's camera pipelines alone from vsm's.
    assert_eq!(v.ctx.forget_shaders(&files(&["methods/pcss.wgsl"])), 0);
    assert_eq!(v.ctx.forget_shaders(&files(&["methods/vsm.wgsl"])), 1);
    assert_eq!(v.ctx.forget_shaders(&files(&["methods/vsm.wgsl"])), 0);
    // The camera's shared file: what every method's shader includes (the D-buffer's camera
    // pipelines are left of the two).
    assert_eq!(v.ctx.forget_shaders(&files(&["shared/camera.wgsl"])), 1);
    // The view pass's shader: its pipelines, nothing of the methods.
    assert_eq!(v.ctx.forget_shaders(&files(&["passes/view.wgsl"])), 1);
    // The error view against the converged truth, then a change: the view draws again with
    // the truth it had (handed in before, not traced again).
    let error = intent(vsm, View::Error);
    advance_until(
        &mut v,
        &error,
        |_, _| {},
        |v| converged(v) && v.shown(0).is_some_and(|s| s.note.is_none()),
    );
    let serial = v.shown(0).map_or(0, |s| s.serial);
    v.shaders_changed(&files(&["methods/vsm.wgsl"]));
    let u = v.advance(&error, &mut no_motion);
    assert!(u.errors.is_empty(), "{:?}", u.errors);
    let shown = v.shown(0).expect("drawn again");
    assert!(shown.serial > serial && shown.method == vsm);
    assert_eq!(shown.note, None, "the error view lost its truth");
    assert_eq!(shown.reference, Some((SAMPLES, SAMPLES)));
    // The D-buffer's state (its geometry with it) outlives a change of vsm's file, not one of
    // its own.
    assert!(v.session.geometry(Method::DBUFFER).is_some());
    v.shaders_changed(&files(&["methods/vsm.wgsl"]));
    assert!(
        v.session.geometry(Method::DBUFFER).is_some(),
        "dropped for vsm's file"
    );
    v.shaders_changed(&files(&["methods/dbuffer.wgsl"]));
    assert!(
        v.session.geometry(Method::DBUFFER).is_none(),
        "kept after its own file"
    );
}
