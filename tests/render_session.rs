//! Geometry runs again only when the light or a caster changed; the passes run every frame.

use dbuffer::geometry::VtVariant;
use dbuffer::render::session::Session;
use dbuffer::render::{FrameRequest, GpuContext, Method, MethodParams};
use dbuffer::scene;
use glam::Vec3;

#[test]
fn geometry_is_rebuilt_only_when_something_moved() {
    let ctx = GpuContext::headless().unwrap_or_else(|e| panic!("{e}"));
    let scene = scene::load("table1-224").unwrap_or_else(|e| panic!("{e}"));
    let light = scene.light;
    let mut session = Session::new(&ctx, scene);
    let request = FrameRequest {
        width: 64,
        height: 64,
        dbuffer_size: 256,
        method: Method::DBuffer,
        vt: VtVariant::Smoothstep,
        ..FrameRequest::default()
    };
    let first = session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    let second = session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        session.geometry_builds(),
        1,
        "two frames of a still scene: one geometry build"
    );
    assert_eq!(first.visibility, second.visibility);

    session.set_light(light);
    session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        session.geometry_builds(),
        1,
        "setting the same light is no change"
    );

    let mut moved = light;
    moved.center += Vec3::new(1.0, 0.0, 0.0);
    session.set_light(moved);
    let third = session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        session.geometry_builds(),
        2,
        "one rebuild after the light moved"
    );
    let changed = first
        .visibility
        .iter()
        .zip(&third.visibility)
        .filter(|(a, b)| (*a - *b).abs() > 0.1)
        .count();
    assert!(
        changed > 50,
        "the shadow moved with the light ({changed} pixels changed)"
    );
}

#[test]
fn the_reference_converges_over_frames_and_restarts_when_the_view_changes() {
    let ctx = GpuContext::headless().unwrap_or_else(|e| panic!("{e}"));
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let (light, camera) = (scene.light, scene.camera);
    let mut session = Session::new(&ctx, scene);
    let request = FrameRequest {
        width: 48,
        height: 48,
        dbuffer_size: 256,
        method: Method::Reference,
        params: MethodParams {
            reference_samples: 16,
            reference_step: 4,
            ..MethodParams::default()
        },
        ..FrameRequest::default()
    };
    assert_eq!(session.reference_progress(), None);
    assert!(!session.converging());
    let mut frames = Vec::new();
    for k in 1..=4u32 {
        frames.push(
            session
                .frame(&ctx, &request)
                .unwrap_or_else(|e| panic!("{e}")),
        );
        assert_eq!(session.reference_progress(), Some((4 * k, 16)));
        assert_eq!(session.converging(), k < 4);
    }
    // Complete: the frame shows exactly the reference V, and more frames change nothing.
    let done = session
        .reference_visibility()
        .expect("a reference")
        .to_vec();
    assert_eq!(frames[3].visibility, done);
    assert_ne!(
        frames[0].visibility, done,
        "4 of 16 samples is not the whole answer"
    );
    let again = session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again.visibility, done);
    assert_eq!(session.reference_progress(), Some((16, 16)));

    // Moving the light or the camera starts it over.
    let mut moved = light;
    moved.center.x += 0.5;
    session.set_light(moved);
    session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(session.reference_progress(), Some((4, 16)));
    let mut cam = camera;
    cam.eye.x += 0.5;
    session.set_camera(cam);
    session
        .advance_reference(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(session.reference_progress(), Some((4, 16)));
}

#[test]
fn dbuffer_center_builds_its_own_volumes_and_invalidation_forces_a_rebuild() {
    let ctx = GpuContext::headless().unwrap_or_else(|e| panic!("{e}"));
    let scene = scene::load("fig1-large-light").unwrap_or_else(|e| panic!("{e}"));
    let mut session = Session::new(&ctx, scene);
    let request = |method| FrameRequest {
        width: 48,
        height: 48,
        dbuffer_size: 256,
        method,
        ..FrameRequest::default()
    };
    let disk = session.frame(&ctx, &request(Method::DBuffer)).unwrap();
    let disk_stats = session.geometry().stats;
    assert_eq!(session.geometry_builds(), 1);
    let centre = session
        .frame(&ctx, &request(Method::DBufferCenter))
        .unwrap();
    assert_eq!(
        session.geometry_builds(),
        2,
        "the centre's volumes are built"
    );
    // From the centre alone no face is a silhouette face.
    let s = session.geometry().stats;
    assert_eq!(s.silhouette_a + s.silhouette_b, 0);
    assert!(disk_stats.silhouette_a + disk_stats.silhouette_b > 0);
    assert_ne!(disk.visibility, centre.visibility);
    // Methods without volumes leave them as they are.
    session.frame(&ctx, &request(Method::Pcss)).unwrap();
    assert_eq!(session.geometry_builds(), 2);
    session.invalidate_geometry();
    session
        .frame(&ctx, &request(Method::DBufferCenter))
        .unwrap();
    assert_eq!(session.geometry_builds(), 3);
    let back = session.frame(&ctx, &request(Method::DBuffer)).unwrap();
    assert_eq!(session.geometry_builds(), 4);
    assert_eq!(back.visibility, disk.visibility);
}
