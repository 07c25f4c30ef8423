//! Geometry runs again only when the light or a caster changed; the passes run every frame.

use dbuffer::geometry::VtVariant;
use dbuffer::render::session::Session;
use dbuffer::render::{FrameRequest, GpuContext, Method};
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
