//! `raytraced` — shadow rays traced on the GPU and denoised — against the ray-cast reference:
//! after the history a still view has (15 frames) its penumbra error is below PCSS's on every
//! built-in with an area light; its raw rays are whole counts of the rays traced; the same
//! frames give the same images; a light that moves leaves little of its old shadow behind.
//! Numbers are printed (`cargo test --release --test gpu raytraced -- --nocapture`).

use dbuffer::geometry::metrics;
use dbuffer::geometry::VtVariant;
use dbuffer::render::methods::raytraced::{self, DENOISE, FRAMES, RAYS};
use dbuffer::render::methods::reference::SAMPLES;
use dbuffer::render::offline::Offline;
use dbuffer::render::{FrameRequest, Knobs, Method};
use dbuffer::scene::{self, Light};

use crate::support::scored::Scored;

const SIZE: u32 = 128;

fn rt() -> Method {
    Method::of(&raytraced::RAYTRACED).expect("raytraced is on the registry")
}

fn request(method: Method, knobs: Knobs) -> FrameRequest {
    FrameRequest {
        width: SIZE,
        height: SIZE,
        dbuffer_size: 512,
        method,
        vt: VtVariant::Exact,
        knobs,
        ..FrameRequest::default()
    }
}

/// At its defaults, after its stated history, below PCSS 16/32's penumbra MAE on every built-in
/// PCSS takes (the area lights, the many-caster scenes included); its first frame is printed
/// beside it.
#[test]
fn after_its_history_it_beats_pcss_on_every_area_light_built_in() {
    let pcss = Method::of(&dbuffer::render::methods::pcss::PCSS).expect("pcss");
    println!("| scene | method | class mismatch % | MAE | penumbra MAE | p99 |");
    let mut scored_scenes = 0;
    for name in scene::builtin::names() {
        let light = scene::load(name)
            .map(|s| s.light)
            .unwrap_or_else(|e| panic!("{e}"));
        if !pcss.takes(light.kind()) {
            continue;
        }
        let mut s = Scored::new(name, SIZE);
        let (_, first) = s.measure_as(
            rt(),
            Knobs::default().with(&FRAMES, 0),
            "raytraced (first frame)",
        );
        let (_, still) = s.measure_as(rt(), Knobs::default(), "raytraced (15 frames)");
        let (_, p) = s.measure(pcss, Knobs::default());
        assert!(
            still.penumbra_mae < p.penumbra_mae,
            "{name}: raytraced after 15 frames has penumbra MAE {:.4}, pcss {:.4}",
            still.penumbra_mae,
            p.penumbra_mae
        );
        // The history is worth having: more samples, less error.
        assert!(
            still.penumbra_mae < first.penumbra_mae,
            "{name}: 15 frames {:.4}, the first {:.4}",
            still.penumbra_mae,
            first.penumbra_mae
        );
        scored_scenes += 1;
    }
    assert!(scored_scenes >= 20, "only {scored_scenes} scenes scored");
}

/// With the denoiser off a pixel's V is the share of its rays that reached the light: a whole
/// number of rays over the rays per pixel; lit where the reference is lit and dark in umbra.
#[test]
fn the_raw_rays_are_whole_counts() {
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let (reference, _) = offline
        .render(
            &scene,
            &request(Method::REFERENCE, Knobs::default().with(&SAMPLES, 256)),
        )
        .unwrap_or_else(|e| panic!("{e}"));
    let knobs = Knobs::default().with(&DENOISE.0, 0).with(&RAYS, 4);
    let (frame, _) = offline
        .render(&scene, &request(rt(), knobs))
        .unwrap_or_else(|e| panic!("{e}"));
    let (mut lit, mut lit_dark, mut umbra, mut umbra_lit) = (0, 0, 0, 0);
    for (i, (&v, &r)) in frame
        .visibility
        .iter()
        .zip(&reference.visibility)
        .enumerate()
    {
        let rays = v * 4.0;
        assert!(
            (rays - rays.round()).abs() < 1e-6,
            "pixel {i}: V {v} is not a whole number of 4 rays"
        );
        if !reference.hit(i) {
            continue;
        }
        // The reference's 256 points and the rays' are not the same points: a pixel at the
        // edge of a class may see a ray the other way.
        if r == 1.0 {
            lit += 1;
            lit_dark += usize::from(v < 1.0);
        } else if r == 0.0 {
            umbra += 1;
            umbra_lit += usize::from(v > 0.0);
        }
    }
    println!(
        "lit {lit} ({lit_dark} with a ray blocked), umbra {umbra} ({umbra_lit} with one through)"
    );
    assert!(lit > 1000 && umbra > 100, "lit {lit}, umbra {umbra}");
    assert!(
        lit_dark * 200 < lit,
        "{lit_dark} of {lit} lit pixels had a ray blocked"
    );
    assert!(
        umbra_lit * 50 < umbra,
        "{umbra_lit} of {umbra} umbra pixels had a ray through"
    );
}

/// Two runs of the same frames — the camera moving between them, the history carried — give
/// the same images bit for bit, and consecutive frames differ (the sequence runs on).
#[test]
fn the_same_frames_give_the_same_images() {
    let scene = scene::load("fig8c-complex").unwrap_or_else(|e| panic!("{e}"));
    let run = || {
        let offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
        let mut session = offline.session(scene.clone());
        let req = request(rt(), Knobs::default());
        (0..4)
            .map(|k| {
                let mut camera = scene.camera;
                camera.eye += glam::Vec3::new(0.02 * k as f32, 0.0, 0.0);
                session.set_camera(camera);
                session
                    .frame(&offline.ctx, &req)
                    .unwrap_or_else(|e| panic!("{e}"))
                    .visibility
            })
            .collect::<Vec<_>>()
    };
    let (a, b) = (run(), run());
    for (k, (fa, fb)) in a.iter().zip(&b).enumerate() {
        assert!(fa == fb, "frame {k} differs between two runs");
    }
    assert!(a[0] != a[1], "the second frame is the first again");
}

/// A light that moves leaves little of its old shadow: 16 frames under one light, then the
/// light moved and 15 frames more, end within a small margin of 15 frames drawn under the new
/// light from the start (the history is rejected where the shadow changed, not averaged in).
#[test]
fn a_moved_light_leaves_little_ghost() {
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let mut moved = scene.clone();
    let Light::Area(mut disk) = scene.light else {
        panic!("fig7-concave has a disk light")
    };
    disk.center += glam::Vec3::new(0.6, 0.0, 0.3);
    moved.light = Light::Area(disk);
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let (reference, _) = offline
        .render(
            &moved,
            &request(Method::REFERENCE, Knobs::default().with(&SAMPLES, 256)),
        )
        .unwrap_or_else(|e| panic!("{e}"));
    let mask: Vec<bool> = (0..reference.len()).map(|i| reference.hit(i)).collect();
    let req = request(rt(), Knobs::default());
    let mut session = offline.session(scene.clone());
    for _ in 0..16 {
        session
            .draw(&offline.ctx, &req)
            .unwrap_or_else(|e| panic!("{e}"));
    }
    session.set_light(moved.light);
    for _ in 0..15 {
        session
            .draw(&offline.ctx, &req)
            .unwrap_or_else(|e| panic!("{e}"));
    }
    let after_move = session
        .frame(&offline.ctx, &req)
        .unwrap_or_else(|e| panic!("{e}"));
    let (fresh, _) = offline
        .render(&moved, &req)
        .unwrap_or_else(|e| panic!("{e}"));
    let m_moved = metrics::compare(&reference.visibility, &after_move.visibility, &mask);
    let m_fresh = metrics::compare(&reference.visibility, &fresh.visibility, &mask);
    println!(
        "after the move: penumbra MAE {:.4}, MAE {:.4}; fresh: {:.4}, {:.4}",
        m_moved.penumbra_mae, m_moved.mae, m_fresh.penumbra_mae, m_fresh.mae
    );
    assert!(
        m_moved.mae < 1.25 * m_fresh.mae + 0.001,
        "the old shadow lingers: MAE {:.4} after the move, {:.4} fresh",
        m_moved.mae,
        m_fresh.mae
    );
}

/// A still view fills the history first (the stated frames, then the one read); the next frame
/// of an animation carries it on: one frame drawn, its sequence continued, not begun again.
#[test]
fn a_still_view_fills_its_history_and_an_animation_carries_it() {
    use dbuffer::render::offline::render_in_history;
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let mut session = offline.session(scene.clone());
    let req = request(rt(), Knobs::default());
    let mut quiet = |_: usize, _: usize| {};
    let before = session.submits();
    let (still, _) = render_in_history(&offline.ctx, &mut session, &req, &mut quiet, true)
        .unwrap_or_else(|e| panic!("{e}"));
    let frames = u64::from(FRAMES.default);
    assert_eq!(session.submits() - before, frames + 1, "a still view");
    let Light::Area(mut disk) = scene.light else {
        panic!("fig7-concave has a disk light")
    };
    disk.center += glam::Vec3::new(0.05, 0.0, 0.0);
    session.set_light(Light::Area(disk));
    let before = session.submits();
    let (next, _) = render_in_history(&offline.ctx, &mut session, &req, &mut quiet, false)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        session.submits() - before,
        1,
        "the next frame of an animation"
    );
    assert!(next.visibility != still.visibility, "the light moved");
}
