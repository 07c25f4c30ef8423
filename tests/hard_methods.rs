//! The hard-shadow methods of issue 13 against the exact hard shadow: one ray per pixel to the
//! light's centre through the oracle's BVH (`geometry::oracle` with a zero-radius light), over the
//! pixels the camera sees facing the light. Numbers are printed
//! (`cargo test --release --test hard_methods -- --nocapture`).

use dbuffer::geometry::bvh::Bvh;
use dbuffer::geometry::hard_volume::point_light;
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::view;
use dbuffer::render::offline::Offline;
use dbuffer::render::{Frame, FrameRequest, Knobs, Method};
use dbuffer::scene::{self, Scene};

/// The exact hard shadow of `scene` per pixel (1 lit, 0 hidden), and the pixels that count.
fn hard_truth(scene: &Scene, frame: &Frame) -> (Vec<f32>, Vec<bool>) {
    let (w, h) = (frame.width, frame.height);
    let bvh = Bvh::build(scene.all_triangles());
    let receivers = view::receivers(scene, &bvh, w, h);
    let oracle = Oracle::new(scene.all_triangles(), point_light(scene.light.center()), 1);
    let truth = receivers
        .iter()
        .map(|r| r.map_or(0.0, |r| oracle.visibility(r.position)))
        .collect();
    let mask = receivers
        .iter()
        .enumerate()
        .map(|(i, r)| frame.hit(i) && r.is_some_and(|r| r.faces_light))
        .collect();
    (truth, mask)
}

/// Pixels whose hard class (lit iff V ≥ 0.5) differs from the truth's, of those that count.
fn mismatch(truth: &[f32], v: &[f32], mask: &[bool]) -> (usize, usize) {
    let mut bad = 0;
    let mut n = 0;
    for ((&t, &m), &on) in truth.iter().zip(v).zip(mask) {
        if on {
            n += 1;
            bad += usize::from((t >= 0.5) != (m >= 0.5));
        }
    }
    (bad, n)
}

fn render(offline: &mut Offline, scene: &Scene, method: Method, size: u32, knobs: Knobs) -> Frame {
    let request = FrameRequest {
        width: size,
        height: size,
        dbuffer_size: 512,
        method,
        knobs,
        ..FrameRequest::default()
    };
    offline
        .render(scene, &request)
        .unwrap_or_else(|e| panic!("{method}: {e}"))
        .0
}

fn method(name: &str) -> Method {
    name.parse().unwrap_or_else(|e| panic!("{e}"))
}

/// A scene from TOML text.
fn scene_from(name: &str, toml: &str) -> Scene {
    scene::SceneFile::parse(toml, name)
        .and_then(|f| f.build_named(std::path::Path::new("."), name, name))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// A headless device without `DEPTH32FLOAT_STENCIL8`: the stencil methods' 24-bit fallback, as
/// a device that lacks the feature (or a window that did not ask for it) gets.
fn offline_without_float_stencil() -> Offline {
    use dbuffer::render::context::wanted_limits;
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter =
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
            .unwrap_or_else(|e| panic!("{e}"));
    let desc = wgpu::DeviceDescriptor {
        label: Some("no float stencil"),
        required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
        required_limits: wanted_limits(&adapter.limits()),
        ..Default::default()
    };
    let (device, queue) =
        pollster::block_on(adapter.request_device(&desc)).unwrap_or_else(|e| panic!("{e}"));
    Offline {
        ctx: dbuffer::render::GpuContext::new(device, queue, adapter.get_info()),
        progress: None,
    }
}

/// Render `method` on `scene` and count its hard-class mismatches against the truth.
fn score(offline: &mut Offline, scene: &Scene, method: Method, size: u32, knobs: Knobs) -> Score {
    let frame = render(offline, scene, method, size, knobs);
    let (truth, mask) = hard_truth(scene, &frame);
    let (bad, pixels) = mismatch(&truth, &frame.visibility, &mask);
    let dark = |v: &[f32]| {
        v.iter()
            .zip(&mask)
            .filter(|(t, m)| **m && **t < 0.5)
            .count()
    };
    let s = Score {
        bad,
        pixels,
        dark_truth: dark(&truth),
        dark: dark(&frame.visibility),
    };
    println!(
        "{}: {method} {} of {} pixels mismatched ({:.3} %), in shadow {} (truth {})",
        scene.name,
        s.bad,
        s.pixels,
        s.pct(),
        s.dark,
        s.dark_truth
    );
    s
}

#[derive(Debug)]
struct Score {
    bad: usize,
    pixels: usize,
    dark_truth: usize,
    dark: usize,
}

impl Score {
    fn pct(&self) -> f64 {
        100.0 * self.bad as f64 / self.pixels.max(1) as f64
    }
}

/// The issue's bound for a method exact up to rasterisation.
const EXACT_PCT: f64 = 0.05;

#[test]
fn shadow_volume_is_exact_on_every_built_in() {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    println!(
        "adapter {}, DEPTH32FLOAT_STENCIL8: {}",
        offline.ctx.adapter_description(),
        offline
            .ctx
            .device
            .features()
            .contains(wgpu::Features::DEPTH32FLOAT_STENCIL8)
    );
    let sv = method("shadow-volume");
    for name in scene::builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        let s = score(&mut offline, &scene, sv, 128, Knobs::default());
        assert!(s.pct() <= EXACT_PCT, "{name}: {s:?}");
        assert!(s.dark_truth > 100, "{name}: the view shows a shadow");
    }
}

/// A wide slab 2 m above the ground and the camera 0.3 m above the ground under it, looking at
/// its umbra and out to the lit ground: the eye is inside the slab's shadow volume, where a
/// z-pass count starts at 1 and inverts the picture.
const INSIDE: &str = r#"
[camera]
eye = [0.0, 0.3, 0.0]
target = [5.0, 0.0, 1.5]
fov_y_deg = 70.0

[light]
center = [0.0, 4.0, 0.0]
normal = [0.0, -1.0, 0.0]
radius = 0.3

[[object]]
name = "ground"
mesh = "plane"
scale = 20.0
casts_shadow = false

[[object]]
name = "slab"
mesh = "cube"
translate = [0.3, 2.0, 0.0]
scale = [2.0, 0.2, 2.0]
"#;

#[test]
fn shadow_volume_with_the_camera_inside_a_volume() {
    use dbuffer::geometry::hard_volume::{scene_volumes, OpenMeshes};
    use dbuffer::geometry::PreparedCasters;
    let scene = scene_from("camera-inside", INSIDE);
    let volumes = scene_volumes(
        &PreparedCasters::new(&scene),
        scene.light.center(),
        OpenMeshes::TwoSided,
    );
    let inside: i32 = volumes
        .iter()
        .map(|(_, _, v)| v.count(scene.camera.eye))
        .sum();
    assert_eq!(inside, 1, "the eye is in the slab's shadow");
    for (label, mut offline) in [
        (
            "float depth",
            Offline::new().unwrap_or_else(|e| panic!("{e}")),
        ),
        ("24-bit depth", offline_without_float_stencil()),
    ] {
        let s = score(
            &mut offline,
            &scene,
            method("shadow-volume"),
            128,
            Knobs::default(),
        );
        assert!(s.pct() <= EXACT_PCT, "{label}: {s:?}");
        // Both sides of the shadow's edge are in view.
        assert!(
            s.dark_truth > s.pixels / 20 && s.pixels - s.dark_truth > s.pixels / 20,
            "{s:?}"
        );
    }
}

#[test]
fn shadow_volume_on_the_24_bit_fallback() {
    let mut offline = offline_without_float_stencil();
    for name in ["fig7-concave", "bunny", "table1-5760"] {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        let s = score(
            &mut offline,
            &scene,
            method("shadow-volume"),
            128,
            Knobs::default(),
        );
        assert!(s.pct() <= EXACT_PCT, "{name}: {s:?}");
    }
}
