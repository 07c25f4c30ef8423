//! The NaN / range view and the counts of what it marks: the reference method shades a V handed
//! in from outside (`Session::set_reference`), here one with NaN, ±∞, 1.5, a negative V and one a
//! float step above 1 at chosen surface pixels. The NaN has to survive the camera pass's float
//! target, the view pass has to mark exactly those pixels in magenta, and the probe's GPU count,
//! the read-back frame's count (what `compare` reports as `invalid_px`) and the CPU twin have to
//! agree.

use dbuffer::geometry::VtVariant;
use dbuffer::render::methods::reference::SAMPLES;
use dbuffer::render::passes::probe::{range_count, ProbeRequest};
use dbuffer::render::passes::view::{Mapping, View, ViewParams};
use dbuffer::render::passes::view_twin::{self, RANGE_MARK};
use dbuffer::render::readback::{Readback, TextureRead};
use dbuffer::render::session::FrameJob;
use dbuffer::render::{Frame, FrameRequest, FrameTargets, GpuContext, Knobs, Method, Session};
use dbuffer::scene;

const W: u32 = 48;
const H: u32 = 40;

/// Render the reference over `v` (handed in as its V) and read the frame back.
fn render(
    ctx: &GpuContext,
    session: &mut Session,
    targets: &mut FrameTargets,
    request: FrameRequest,
    v: &[f32],
) -> Frame {
    let key = session.reference_key(&request);
    session
        .set_reference(ctx, key, v, (8, 8))
        .unwrap_or_else(|e| panic!("{e}"));
    session
        .submit(
            ctx,
            &mut [FrameJob {
                targets: &mut *targets,
                request,
                view: None,
                render: true,
                probes: Vec::new(),
            }],
        )
        .unwrap_or_else(|e| panic!("{e}"));
    session
        .read(ctx, targets, Some(request.method))
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn invalid_v_is_marked_and_counted_where_it_was_handed_in() {
    let ctx = GpuContext::headless().unwrap_or_else(|e| panic!("{e}"));
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let mut session = Session::new(&ctx, scene);
    let request = FrameRequest {
        width: W,
        height: H,
        dbuffer_size: 64,
        method: Method::REFERENCE,
        vt: VtVariant::Exact,
        knobs: Knobs::default().with(&SAMPLES, 8),
        ..FrameRequest::default()
    };
    let mut targets = FrameTargets::new();
    let n = (W * H) as usize;
    // A sound V first: nothing marked, and the surface pixels to spoil.
    let sound: Vec<f32> = (0..n).map(|i| (i % 11) as f32 / 10.0).collect();
    let frame = render(&ctx, &mut session, &mut targets, request, &sound);
    assert_eq!(frame.out_of_range_pixels(), 0, "a V in [0, 1] is sound");
    let hits: Vec<usize> = (0..n).filter(|&i| frame.hit(i)).collect();
    assert!(hits.len() > n / 4, "the scene fills the frame");
    let bad = [
        f32::NAN,
        1.5,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -0.25,
        // One float step above 1: lit, so t + 2 × branch is 7 + 1.2e-7, which rounds to 7.
        1.0 + f32::EPSILON,
    ];
    let spoiled: Vec<usize> = (0..bad.len())
        .map(|k| hits[(k * 37 + 5) % hits.len()])
        .collect();
    let mut v = sound.clone();
    for (&i, &b) in spoiled.iter().zip(&bad) {
        v[i] = b;
    }
    // A spoiled V where no surface is: nothing shows it, nothing counts it.
    let miss = (0..n)
        .find(|&i| !frame.hit(i))
        .expect("a pixel without a surface");
    v[miss] = f32::NAN;
    let frame = render(&ctx, &mut session, &mut targets, request, &v);

    // What the camera pass wrote: the NaN survives the float target, the rest as handed in;
    // t one step above 1 (lost to rounding in the sum) reads back as the stand-in 1.25.
    assert!(frame.visibility[spoiled[0]].is_nan(), "the NaN survives");
    assert!(frame.t(spoiled[0]).is_nan());
    for (k, &i) in spoiled.iter().enumerate().skip(1) {
        assert_eq!(frame.visibility[i], bad[k], "pixel {i}");
    }
    assert_eq!(frame.t(spoiled[1]), 1.5);
    assert_eq!(
        frame.t(spoiled[5]),
        1.25,
        "a t out of range reads back out of range"
    );
    let marked: Vec<usize> = (0..n).filter(|&i| frame.out_of_range(i)).collect();
    let mut expected = spoiled.clone();
    expected.sort_unstable();
    assert_eq!(marked, expected);
    assert_eq!(frame.out_of_range_pixels(), bad.len());

    // The view pass marks exactly those, as its twin does; the probe counts them on the GPU.
    let params = ViewParams {
        view: View::Range,
        channels: [true, false, false, false],
        mapping: Mapping::unit(),
    };
    session
        .submit(
            &ctx,
            &mut [FrameJob {
                targets: &mut targets,
                request,
                view: Some(params),
                render: false,
                probes: vec![ProbeRequest::Range { params, serial: 7 }],
            }],
        )
        .unwrap_or_else(|e| panic!("{e}"));
    let display = targets.shown().expect("a display");
    assert_eq!((display.width, display.height), (W, H));
    let bytes = Readback::default()
        .read(&ctx, &[TextureRead::color(display.texture, 4)])
        .unwrap_or_else(|e| panic!("{e}"))
        .remove(0);
    let gpu: Vec<[u8; 4]> = bytes
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    let magenta: Vec<usize> = (0..n).filter(|&i| gpu[i] == RANGE_MARK).collect();
    assert_eq!(
        magenta, expected,
        "the view marks exactly the spoiled pixels"
    );
    let (_, _, twin) = view_twin::render(&frame, None, &params);
    for i in 0..n {
        let close = gpu[i]
            .iter()
            .zip(&twin[i])
            .all(|(a, b)| a.abs_diff(*b) <= 1);
        assert!(close, "pixel {i}: gpu {:?}, twin {:?}", gpu[i], twin[i]);
    }
    // The rest is a dimmed grey: no channel above 0.4 of white, and not all black.
    let rest: Vec<&[u8; 4]> = (0..n)
        .filter(|i| !expected.contains(i))
        .map(|i| &gpu[i])
        .collect();
    assert!(rest
        .iter()
        .all(|c| c[0] == c[1] && c[1] == c[2] && c[0] <= 103));
    assert!(
        rest.iter().any(|c| c[0] > 20),
        "the image shows under the marks"
    );
    let probe = targets.probe.as_mut().expect("a probe");
    let answers = probe.wait(&ctx);
    let counted: Vec<(u64, u64)> = answers
        .iter()
        .filter_map(|r| match r.request {
            ProbeRequest::Range { serial, .. } => Some((serial, range_count(&r.values))),
            _ => None,
        })
        .collect();
    assert_eq!(
        counted,
        [(7, bad.len() as u64)],
        "the GPU's count, with its serial"
    );
}
