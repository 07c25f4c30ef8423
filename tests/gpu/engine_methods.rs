//! What engines ship today, against the ray-cast reference: shadow-map ray tracing (`smrt`).
//! Numbers are printed (`cargo test --release --test gpu engine_methods -- --nocapture`).

use dbuffer::render::methods::smrt;
use dbuffer::render::offline::Offline;
use dbuffer::render::{Frame, Knobs, Method};
use dbuffer::scene;

use crate::support::scored::{self, Scored};

const SIZE: u32 = 96;

fn render(
    offline: &mut Offline,
    scene: &dbuffer::scene::Scene,
    method: Method,
    knobs: Knobs,
) -> Frame {
    scored::render(offline, scene, method, knobs, SIZE)
}

fn smrt_method() -> Method {
    Method::of(&smrt::SMRT).expect("smrt is on the registry")
}

/// More rays, less error: the light points are a stratified lattice, so with every ray traced
/// the penumbra's error falls with the ray count on every scene; the defaults (adaptive count on)
/// are scored beside PCSS.
#[test]
fn smrt_converges_with_its_rays() {
    let smrt = smrt_method();
    println!("| scene | method | class mismatch % | MAE | penumbra MAE | p99 |");
    for name in [
        "table1-960",
        "fig1-large-light",
        "fig7-concave",
        "acute-corner",
        "rect-strip",
    ] {
        let mut s = Scored::new(name, SIZE);
        // Every ray traced (the adaptive count stops a pixel at two rays where they agree).
        let rays = |n: u32| {
            Knobs::default()
                .with(&smrt::RAYS, n)
                .with(&smrt::ADAPTIVE.0, 0)
        };
        let (_, two) = s.measure_as(smrt, rays(2), "smrt 2 rays");
        let (_, eight) = s.measure_as(smrt, rays(8), "smrt 8 rays");
        let (_, many) = s.measure_as(smrt, rays(32), "smrt 32 rays");
        let (_, defaults) = s.measure_as(smrt, Knobs::default(), "smrt defaults (7 x 8)");
        let pcss = Method::of(&dbuffer::render::methods::pcss::PCSS).expect("pcss");
        let (_, p) = s.measure_as(pcss, Knobs::default(), "pcss");
        assert!(
            many.penumbra_mae < eight.penumbra_mae && eight.penumbra_mae < two.penumbra_mae,
            "{name}: penumbra MAE 2 / 8 / 32 rays {:.4} / {:.4} / {:.4}",
            two.penumbra_mae,
            eight.penumbra_mae,
            many.penumbra_mae
        );
        // The adaptive count (the defaults) ends a pixel at two agreeing rays, a penumbra
        // pixel included: never better than tracing all seven.
        let (_, seven) = s.measure_as(smrt, rays(7), "smrt 7 rays, every ray");
        assert!(
            defaults.penumbra_mae >= seven.penumbra_mae - 1e-3,
            "{name}: adaptive {defaults:?} vs every ray {seven:?}"
        );
        println!(
            "| {name} | smrt defaults / pcss penumbra MAE | {:.2} |",
            defaults.penumbra_mae / p.penumbra_mae.max(1e-6)
        );
    }
}

/// The light points and step offsets come from the pixel alone: two renders of the same frame
/// are the same picture (no flicker with the camera and light still), and the ray cap narrows the
/// penumbra (less of the light's reach marched: more pixels fully lit).
#[test]
fn smrt_is_deterministic_and_its_ray_cap_narrows_the_penumbra() {
    let smrt = smrt_method();
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let a = render(&mut offline, &scene, smrt, Knobs::default());
    let b = render(&mut offline, &scene, smrt, Knobs::default());
    assert_eq!(
        a.visibility, b.visibility,
        "two renders of one frame differ"
    );
    let lit = |f: &Frame| f.visibility.iter().filter(|&&v| v >= 1.0).count();
    let capped = render(
        &mut offline,
        &scene,
        smrt,
        Knobs::default().with(&smrt::RAY_LENGTH.0, 20),
    );
    assert!(
        lit(&capped) > lit(&a),
        "a ray marched a fifth of the way lights {} pixels, the whole way {}",
        lit(&capped),
        lit(&a)
    );
}
