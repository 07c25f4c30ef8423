//! A user's method (`--method file:PATH.wgsl`, `render::methods::user`): the shipped
//! `examples/methods/dbuffer_vt.wgsl`, the paper's D-buffer with V(t) written out in the file,
//! draws the built-in `dbuffer`'s frame bit for bit — colour, V, t and branch, cost — under every
//! V(t) variant, on a disk, a rectangle and a polygon light; and its knobs reach the shader.

use dbuffer::geometry::VtVariant;
use dbuffer::render::offline::Offline;
use dbuffer::render::{Frame, FrameRequest, Knobs, Method};
use dbuffer::scene::{self, Scene};

const SIDE: u32 = 64;

fn example(name: &str) -> String {
    format!("{}/examples/methods/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn load(name: &str) -> Scene {
    scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn render(offline: &mut Offline, scene: &Scene, method: Method, vt: VtVariant) -> Frame {
    let request = FrameRequest {
        width: SIDE,
        height: SIDE,
        dbuffer_size: 256,
        method,
        vt,
        knobs: Knobs::default(),
        read_cost: true,
        colour_only: false,
        ..FrameRequest::default()
    };
    offline
        .render(scene, &request)
        .unwrap_or_else(|e| panic!("{method}: {e}"))
        .0
}

#[test]
fn dbuffer_vt_is_the_built_in_dbuffer_bit_for_bit() {
    let user = Method::parse_with(&format!("file:{}", example("dbuffer_vt.wgsl")), &[])
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(user.name(), "user-dbuffer_vt");
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    for name in ["fig7-concave", "rect-fig7", "polygon-triangle"] {
        let scene = load(name);
        for vt in [
            VtVariant::Smoothstep,
            VtVariant::Sqrt,
            VtVariant::Exact,
            VtVariant::Linear,
        ] {
            let built_in = render(&mut offline, &scene, Method::DBUFFER, vt);
            let written = render(&mut offline, &scene, user, vt);
            // A frame with nothing in penumbra would hold V(t) to nothing.
            let penumbra = built_in
                .visibility
                .iter()
                .filter(|&&v| v > 0.01 && v < 0.99)
                .count();
            assert!(penumbra > 20, "{name}: {penumbra} penumbra pixels");
            assert!(
                built_in.color == written.color,
                "{name} {vt:?}: colour differs"
            );
            let bits = |f: &Frame| f.visibility.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert!(
                bits(&built_in) == bits(&written),
                "{name} {vt:?}: V differs"
            );
            assert!(
                built_in.t_branch == written.t_branch,
                "{name} {vt:?}: t differs"
            );
            assert!(built_in.cost == written.cost, "{name} {vt:?}: cost differs");
        }
    }
}

#[test]
fn a_knob_reaches_the_shader() {
    // V is the knob where a surface is: the default, then the value set.
    let dir = std::env::temp_dir().join(format!("dbuffer-user-knob-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("flat.wgsl");
    std::fs::write(
        &path,
        "// #include shared/camera.wgsl\n// knob: level 0..1 = 0.25\n\
         fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {\n    \
         return plain(knob_level());\n}\n",
    )
    .expect("write");
    let name = format!("file:{}", path.display());
    let scene = load("fig7-concave");
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    for (settings, want) in [(vec![], 0.25f32), (vec!["level=0.75".to_string()], 0.75)] {
        let m = Method::parse_with(&name, &settings).unwrap_or_else(|e| panic!("{e}"));
        let f = render(&mut offline, &scene, m, VtVariant::Smoothstep);
        let lit: Vec<f32> = (0..f.len())
            .filter(|&i| f.hit(i))
            .map(|i| f.visibility[i])
            .collect();
        assert!(lit.len() > 100, "{} surface pixels", lit.len());
        assert!(
            lit.iter().all(|&v| v == want),
            "{settings:?}: {:?}",
            &lit[..4]
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The lab's trial of a user's method before it switches to it: the example passes; a method
/// whose frame does not end within the limit is refused with a message naming its file, on a
/// device of its own, and the caller's device draws on. (On lavapipe a loop without exit ends
/// after about 65,535 steps, so its 64² frame takes some 100 ms: a limit of 20 ms stands in for
/// a frame that never ends.)
#[test]
fn a_trial_frame_refuses_a_method_that_does_not_finish_and_the_caller_draws_on() {
    let scene = load("fig7-concave");
    let good = Method::parse_with(&format!("file:{}", example("dbuffer_vt.wgsl")), &[])
        .expect("the example loads");
    let long = std::time::Duration::from_secs(60);
    dbuffer::render::offline::trial(good, &scene, long).expect("the example's trial passes");

    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/methods/endless.wgsl");
    let endless = Method::parse_with(&format!("file:{}", path.display()), &[])
        .expect("an endless loop is valid WGSL");
    let short = std::time::Duration::from_millis(20);
    let refused = dbuffer::render::offline::trial(endless, &scene, short)
        .expect_err("a frame past the limit is refused");
    assert!(
        refused.starts_with(&format!(
            "{}: a 64² trial frame did not finish",
            path.display()
        )),
        "{refused}"
    );
    // The caller's own device is untouched.
    let mut offline = Offline::new().expect("a device");
    let frame = render(&mut offline, &scene, Method::DBUFFER, VtVariant::Smoothstep);
    assert!(frame.visibility.iter().any(|&v| v > 0.5) && frame.visibility.iter().any(|&v| v < 0.5));
}

/// A user's file that calls `scene_occluded` gets the scene's BVH: the shipped
/// `examples/methods/traced.wgsl` traces a grid over the light with it, and needs a storage
/// buffer in the fragment stage, so an adapter without one refuses it up front while the
/// D-buffer example, which binds none, still runs there.
#[test]
fn the_scene_bvh_is_bound_for_a_file_that_traces_and_needs_storage() {
    let traced = Method::parse_with(&format!("file:{}", example("traced.wgsl")), &[])
        .expect("the traced example loads");
    let dbuffer_vt = Method::parse_with(&format!("file:{}", example("dbuffer_vt.wgsl")), &[])
        .expect("the example loads");
    let mut offline = Offline::new().expect("a device");
    assert_eq!(
        traced.refuses_on(&offline.ctx.caps),
        None,
        "lavapipe runs it"
    );
    let scene = load("fig7-concave");
    let frame = render(&mut offline, &scene, traced, VtVariant::Smoothstep);
    let partly = frame
        .visibility
        .iter()
        .filter(|&&v| v > 0.05 && v < 0.95)
        .count();
    assert!(
        partly > 20,
        "a penumbra is traced: {partly} pixels between 0 and 1"
    );
    let no_storage = wgpu::Limits {
        max_storage_buffers_per_shader_stage: 0,
        ..wgpu::Limits::downlevel_webgl2_defaults()
    };
    let caps = dbuffer::render::adapter::Capabilities::webgpu(
        &offline.ctx.adapter,
        wgpu::Features::empty(),
        no_storage,
    );
    let why = traced.refuses_on(&caps).unwrap_or_default();
    assert!(why.contains("storage buffer"), "refused as: {why}");
    assert_eq!(dbuffer_vt.refuses_on(&caps), None, "it binds no storage");
}
