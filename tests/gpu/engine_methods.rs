//! What engines ship today, against the ray-cast reference: shadow-map ray tracing (`smrt`).
//! Numbers are printed (`cargo test --release --test gpu engine_methods -- --nocapture`).

use dbuffer::geometry::bvh::Bvh;
use dbuffer::geometry::metrics::{self, Metrics};
use dbuffer::geometry::{view, VtVariant};
use dbuffer::render::methods::{reference::SAMPLES, smrt};
use dbuffer::render::offline::Offline;
use dbuffer::render::{Frame, FrameRequest, Knobs, Method};
use dbuffer::scene::{self, Scene};

const SIZE: u32 = 96;

fn render(offline: &mut Offline, scene: &Scene, method: Method, knobs: Knobs) -> Frame {
    let request = FrameRequest {
        width: SIZE,
        height: SIZE,
        dbuffer_size: 1024,
        method,
        vt: VtVariant::Exact,
        knobs: knobs.with(&SAMPLES, 256),
        read_dbuffer: false,
    };
    offline
        .render(scene, &request)
        .unwrap_or_else(|e| panic!("{method}: {e}"))
        .0
}

struct Scored {
    offline: Offline,
    scene: Scene,
    reference: Vec<f32>,
    mask: Vec<bool>,
}

impl Scored {
    fn new(name: &str) -> Scored {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
        let reference = render(&mut offline, &scene, Method::REFERENCE, Knobs::default());
        let receivers = view::receivers(&scene, &Bvh::build(scene.all_triangles()), SIZE, SIZE);
        let mask = dbuffer::compare::counted_pixels(&receivers, &reference);
        Scored {
            offline,
            scene,
            reference: reference.visibility,
            mask,
        }
    }

    fn measure(&mut self, method: Method, knobs: Knobs, label: &str) -> (Frame, Metrics) {
        let frame = render(&mut self.offline, &self.scene, method, knobs);
        let m = metrics::compare(&self.reference, &frame.visibility, &self.mask);
        println!(
            "| {} | {label} | {:.2} | {:.4} | {:.4} | {:.3} |",
            self.scene.name, m.class_mismatch_pct, m.mae, m.penumbra_mae, m.p99
        );
        (frame, m)
    }
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
        let mut s = Scored::new(name);
        // Every ray traced (the adaptive count stops a pixel at two rays where they agree).
        let rays = |n: u32| {
            Knobs::default()
                .with(&smrt::RAYS, n)
                .with(&smrt::ADAPTIVE.0, 0)
        };
        let (_, two) = s.measure(smrt, rays(2), "smrt 2 rays");
        let (_, eight) = s.measure(smrt, rays(8), "smrt 8 rays");
        let (_, many) = s.measure(smrt, rays(32), "smrt 32 rays");
        let (_, defaults) = s.measure(smrt, Knobs::default(), "smrt defaults (7 x 8)");
        let pcss = Method::of(&dbuffer::render::methods::pcss::PCSS).expect("pcss");
        let (_, p) = s.measure(pcss, Knobs::default(), "pcss");
        assert!(
            many.penumbra_mae < eight.penumbra_mae && eight.penumbra_mae < two.penumbra_mae,
            "{name}: penumbra MAE 2 / 8 / 32 rays {:.4} / {:.4} / {:.4}",
            two.penumbra_mae,
            eight.penumbra_mae,
            many.penumbra_mae
        );
        // The adaptive count (the defaults) ends a pixel at two agreeing rays, a penumbra
        // pixel included: never better than tracing all seven.
        let (_, seven) = s.measure(smrt, rays(7), "smrt 7 rays, every ray");
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
