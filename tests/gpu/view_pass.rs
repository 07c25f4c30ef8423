//! The view pass (what the lab's viewport shows, drawn on the GPU) against its CPU twin
//! (`render::passes::view_twin`), on every view: the final image, V, t, the classes, the error
//! against the reference, and the light-space maps one channel at a time and as a composite,
//! through each colour map. Also the probe: the values it reads under a pixel are the frame's,
//! and the auto-fit samples are the twin's.

use dbuffer::geometry::VtVariant;
use dbuffer::render::methods::reference::SAMPLES;
use dbuffer::render::passes::probe::{PixelValues, ProbeRequest, FIT_GRID};
use dbuffer::render::passes::view::{ColorMap, Mapping, View, ViewParams};
use dbuffer::render::passes::view_twin;
use dbuffer::render::readback::{Readback, TextureRead};
use dbuffer::render::session::FrameJob;
use dbuffer::render::{Frame, FrameRequest, FrameTargets, GpuContext, Knobs, Method, Session};
use dbuffer::scene;

const W: u32 = 80;
const H: u32 = 64;

struct Fixture {
    ctx: GpuContext,
    session: Session,
    targets: FrameTargets,
    request: FrameRequest,
    frame: Frame,
    reference: Vec<f32>,
}

fn fixture(method: Method) -> Fixture {
    let ctx = GpuContext::headless().unwrap_or_else(|e| panic!("{e}"));
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let mut session = Session::new(&ctx, scene);
    let request = FrameRequest {
        width: W,
        height: H,
        dbuffer_size: 128,
        method,
        vt: VtVariant::Exact,
        knobs: Knobs::default().with(&SAMPLES, 32),
        read_dbuffer: false,
        read_cost: false,
        colour_only: false,
    };
    let reference_request = FrameRequest {
        method: Method::REFERENCE,
        ..request
    };
    session
        .advance_reference(&ctx, &reference_request, 32)
        .unwrap_or_else(|e| panic!("{e}"));
    let reference = session
        .reference_visibility(&reference_request)
        .expect("the reference")
        .to_vec();
    let mut targets = FrameTargets::new();
    session
        .submit(
            &ctx,
            &mut [FrameJob {
                targets: &mut targets,
                request,
                view: None,
                render: true,
                probes: Vec::new(),
            }],
        )
        .unwrap_or_else(|e| panic!("{e}"));
    let frame = session
        .read(&ctx, &mut targets, Some(method))
        .unwrap_or_else(|e| panic!("{e}"));
    Fixture {
        ctx,
        session,
        targets,
        request,
        frame,
        reference,
    }
}

impl Fixture {
    /// The view pass's image of the frame in the targets, read back.
    fn gpu_view(&mut self, params: ViewParams) -> (u32, u32, Vec<[u8; 4]>) {
        self.session
            .submit(
                &self.ctx,
                &mut [FrameJob {
                    targets: &mut self.targets,
                    request: self.request,
                    view: Some(params),
                    render: false,
                    probes: Vec::new(),
                }],
            )
            .unwrap_or_else(|e| panic!("{e}"));
        let display = self.targets.shown().expect("a display");
        let (w, h) = (display.width, display.height);
        let bytes = Readback::default()
            .read(&self.ctx, &[TextureRead::color(display.texture, 4)])
            .unwrap_or_else(|e| panic!("{e}"))
            .remove(0);
        // As the viewport shows it: over black (the final image is the camera's colour target,
        // transparent where no surface is; the view pass's displays are opaque).
        let over_black = |c: u8, a: u8| ((u16::from(c) * u16::from(a) + 127) / 255) as u8;
        let px = bytes
            .chunks_exact(4)
            .map(|c| {
                [
                    over_black(c[0], c[3]),
                    over_black(c[1], c[3]),
                    over_black(c[2], c[3]),
                    255,
                ]
            })
            .collect();
        (w, h, px)
    }

    fn probe(&mut self, requests: Vec<ProbeRequest>) -> Vec<Vec<f32>> {
        self.session
            .submit(
                &self.ctx,
                &mut [FrameJob {
                    targets: &mut self.targets,
                    request: self.request,
                    view: None,
                    render: false,
                    probes: requests,
                }],
            )
            .unwrap_or_else(|e| panic!("{e}"));
        let probe = self.targets.probe.as_mut().expect("a probe");
        probe
            .wait(&self.ctx)
            .into_iter()
            .map(|r| r.values)
            .collect()
    }
}

/// Per channel at most 1 apart (float rounding on either side), and how many pixels differ.
fn compare(what: &str, gpu: &(u32, u32, Vec<[u8; 4]>), cpu: &(u32, u32, Vec<[u8; 4]>)) {
    assert_eq!((gpu.0, gpu.1), (cpu.0, cpu.1), "{what}: size");
    let bad: Vec<(usize, [u8; 4], [u8; 4])> = gpu
        .2
        .iter()
        .zip(&cpu.2)
        .enumerate()
        .filter(|(_, (g, c))| g.iter().zip(c.iter()).any(|(a, b)| a.abs_diff(*b) > 1))
        .map(|(i, (g, c))| (i, *g, *c))
        .collect();
    assert!(
        bad.is_empty(),
        "{what}: {} of {} pixels differ, e.g. (index, gpu, twin) {:?}",
        bad.len(),
        gpu.2.len(),
        &bad[..bad.len().min(4)]
    );
}

fn params(view: View, channels: [bool; 4], mapping: Mapping) -> ViewParams {
    ViewParams {
        view,
        channels,
        mapping,
    }
}

#[test]
fn every_view_agrees_with_its_twin() {
    let mut f = fixture(Method::DBUFFER);
    let distinct = |img: &(u32, u32, Vec<[u8; 4]>)| {
        let mut c = img.2.clone();
        c.sort_unstable();
        c.dedup();
        c.len()
    };
    let one = [true, false, false, false];
    let mut cases = vec![
        ("final", params(View::Final, one, Mapping::unit())),
        ("classes", params(View::Classes, one, Mapping::unit())),
        ("V", params(View::Visibility, one, Mapping::unit())),
        ("error", params(View::Error, one, Mapping::error())),
        ("NaN / range", params(View::Range, one, Mapping::unit())),
    ];
    for map in ColorMap::ALL {
        let m = Mapping {
            black: 0.2,
            white: 0.9,
            map,
            auto: false,
        };
        cases.push(("t", params(View::T, one, m)));
    }
    for (c, range) in [
        (0, (2.0, 6.0)),
        (1, (2.5, 5.0)),
        (2, (2.5, 4.5)),
        (3, (1.5, 3.0)),
    ] {
        let mut on = [false; 4];
        on[c] = true;
        let m = Mapping {
            black: range.0,
            white: range.1,
            map: ColorMap::Turbo,
            auto: false,
        };
        cases.push(("light map channel", params(View::DBuffer, on, m)));
    }
    let composite = Mapping {
        black: 2.0,
        white: 6.0,
        map: ColorMap::Gray,
        auto: false,
    };
    cases.push((
        "light map composite",
        params(View::DBuffer, [true, true, true, false], composite),
    ));
    let reference = f.reference.clone();
    for (what, p) in cases {
        let gpu = f.gpu_view(p);
        let cpu = view_twin::render(&f.frame, Some(&reference), &p);
        compare(&format!("{what} {:?}", p.view), &gpu, &cpu);
        let least = if p.view == View::Classes { 3 } else { 8 };
        assert!(distinct(&gpu) > least, "{what}: the view shows something");
    }
    // The FLIP view: the map handed in (here a made-up one), through the range, where the
    // error view has the reference V; before a map is handed in, the image.
    let unit_heat = Mapping {
        black: 0.0,
        white: 1.0,
        map: ColorMap::Heat,
        auto: false,
    };
    let flip_params = params(View::Flip, one, unit_heat);
    let before = f.gpu_view(flip_params);
    let image = view_twin::render(&f.frame, None, &flip_params);
    compare("FLIP before a map", &before, &image);
    let map: Vec<f32> = (0..f.frame.len()).map(|i| (i % 17) as f32 / 16.0).collect();
    let key = f.session.reference_key(&FrameRequest {
        method: Method::REFERENCE,
        ..f.request
    });
    f.session
        .set_flip(&f.ctx, key, &map)
        .unwrap_or_else(|e| panic!("{e}"));
    let gpu = f.gpu_view(flip_params);
    let cpu = view_twin::render(&f.frame, Some(&map), &flip_params);
    compare("FLIP", &gpu, &cpu);
    assert!(distinct(&gpu) > 8, "the FLIP view shows the map");
}

#[test]
fn the_probe_reads_the_frame_and_the_fit_samples_the_twins_grid() {
    let mut f = fixture(Method::DBUFFER);
    let p = params(
        View::Visibility,
        [true, false, false, false],
        Mapping::auto(),
    );
    // A pixel in the shadow, on a surface.
    let i = (0..f.frame.visibility.len())
        .find(|&i| f.frame.hit(i) && (0.1..0.9).contains(&f.frame.visibility[i]))
        .expect("a penumbra pixel");
    let (x, y) = (i as u32 % W, i as u32 / W);
    let answers = f.probe(vec![
        ProbeRequest::Pixel { x, y, params: p },
        ProbeRequest::Fit { params: p },
    ]);
    assert_eq!(answers.len(), 2, "both answers came back");
    let (pixel, fit) = if answers[0].len() < answers[1].len() {
        (&answers[0], &answers[1])
    } else {
        (&answers[1], &answers[0])
    };
    let v = PixelValues::decode(pixel).expect("a pixel's values");
    assert_eq!(v.visibility, f.frame.visibility[i]);
    assert_eq!(v.t, f.frame.t(i));
    assert_eq!(v.branch, f.frame.branch(i));
    assert_eq!(v.reference, Some(f.reference[i]));
    let pos = v.position.expect("a surface");
    let q = f.frame.position(i).expect("a surface");
    assert!((pos - q).length() < 1e-4, "{pos} vs {q}");
    // The texel under the point: the D-buffer's channels there, as read back.
    let ((tx, ty), texel) = v.texel.expect("the point is in the light view");
    let maps = f.frame.maps.as_ref().expect("the maps were read");
    assert_eq!(maps.texel(tx, ty), Some(texel));
    // The fit's samples are the twin's grid of the same frame.
    let twin = view_twin::fit_samples(&f.frame, Some(&f.reference), &p, FIT_GRID);
    assert_eq!(fit.len(), twin.len());
    for (k, (g, c)) in fit.iter().zip(&twin).enumerate() {
        assert!(
            (g.is_nan() && c.is_nan()) || g == c,
            "fit sample {k}: GPU {g}, twin {c}"
        );
    }
    let mut m = Mapping::auto();
    m.fit(fit.iter().copied());
    assert!(m.black < m.white, "{m:?}");
}

#[test]
fn methods_without_maps_show_the_frame_and_the_reference_view_needs_the_reference() {
    let mut f = fixture(Method::HARD);
    // The hard shadow keeps the centre's map alone: one channel.
    let maps = f.frame.maps.as_ref().expect("the shadow map");
    assert_eq!(maps.channels.len(), 1);
    let p = params(
        View::DBuffer,
        [true, false, false, false],
        Mapping {
            black: 2.0,
            white: 6.0,
            map: ColorMap::Heat,
            auto: false,
        },
    );
    let gpu = f.gpu_view(p);
    compare("hard's map", &gpu, &view_twin::render(&f.frame, None, &p));
    assert_eq!(
        (gpu.0, gpu.1),
        (128, 128),
        "the light-space view is the map's size"
    );
}

/// A colour-only frame (the lab turning its camera: `FrameRequest::colour_only`) shows the same
/// final image as a full one, and a probe asked of it renders the frame again in full: the
/// values read are this frame's, not what an earlier frame left in the V/t target.
#[test]
fn a_colour_only_frame_shows_the_same_image_and_a_probe_renders_it_in_full() {
    let mut f = fixture(Method::DBUFFER);
    let final_view = params(View::Final, [true, false, false, false], Mapping::auto());
    let (_, _, full) = f.gpu_view(final_view);
    // Another method's frame leaves its V in the targets; then the D-buffer, colour only.
    let hard = FrameRequest {
        method: Method::HARD,
        ..f.request
    };
    let colour_only = FrameRequest {
        colour_only: true,
        ..f.request
    };
    for (request, view) in [(hard, None), (colour_only, Some(final_view))] {
        f.session
            .submit(
                &f.ctx,
                &mut [FrameJob {
                    targets: &mut f.targets,
                    request,
                    view,
                    render: true,
                    probes: Vec::new(),
                }],
            )
            .unwrap_or_else(|e| panic!("{e}"));
    }
    f.request = colour_only;
    let (_, _, shown) = f.gpu_view(final_view);
    assert!(shown == full, "the colour-only frame's image differs");
    // It is shown as the camera pass drew it (no view pass), and opaque as the view pass's
    // displays are: a window paints nothing under it.
    let display = f.targets.shown().expect("a display");
    let camera = f.targets.camera.as_ref().expect("camera targets");
    assert_eq!(
        display.generation, camera.generation,
        "a colour-only frame's final image is its colour target"
    );
    let camera_generation = camera.generation;
    let bytes = Readback::default()
        .read(&f.ctx, &[TextureRead::color(display.texture, 4)])
        .unwrap_or_else(|e| panic!("{e}"))
        .remove(0);
    assert!(
        bytes.chunks_exact(4).all(|c| c[3] == 255),
        "a colour-only frame is drawn opaque"
    );
    let misses = (0..f.frame.color.len())
        .filter(|&i| !f.frame.hit(i))
        .count();
    assert!(misses > 0, "the view shows pixels with no surface");
    // A readback of it (an export) renders the frame in full into targets of its own: it reads
    // the frame's V, and what the viewport shows stays as it was.
    let read = f
        .session
        .read(&f.ctx, &mut f.targets, None)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(read.visibility == f.frame.visibility, "the readback's V");
    let display = f.targets.shown().expect("a display");
    assert_eq!(display.generation, camera_generation);
    let after = Readback::default()
        .read(&f.ctx, &[TextureRead::color(display.texture, 4)])
        .unwrap_or_else(|e| panic!("{e}"))
        .remove(0);
    assert!(after == bytes, "a readback changed what the viewport shows");
    // A penumbra pixel, where the hard shadow's V (0 or 1) is not the D-buffer's.
    let i = (0..f.frame.visibility.len())
        .find(|&i| f.frame.hit(i) && (0.1..0.9).contains(&f.frame.visibility[i]))
        .expect("a penumbra pixel");
    let (x, y) = (i as u32 % W, i as u32 / W);
    let p = params(
        View::Visibility,
        [true, false, false, false],
        Mapping::auto(),
    );
    let answers = f.probe(vec![ProbeRequest::Pixel { x, y, params: p }]);
    let v = PixelValues::decode(&answers[0]).expect("a pixel's values");
    assert_eq!(v.visibility, f.frame.visibility[i]);
    assert_eq!(v.t, f.frame.t(i));
}
