//! Every built-in scene rendered at 128×128 (D-buffer 512², V(t) smoothstep) against its PNG in
//! `tests/snapshots/` (tolerance in `tests/snapshots/tolerance.toml`). `UPDATE_SNAPSHOTS=1`
//! writes missing or failing ones; a failure leaves `NAME.new.png` and `NAME.diff.png` beside.

use crate::support::snapshot;

use dbuffer::geometry::VtVariant;
use dbuffer::render::offline::Offline;
use dbuffer::render::{FrameRequest, Method};
use dbuffer::scene;

#[test]
fn every_built_in_matches_its_snapshot() {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    for name in scene::builtin::names() {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        // Each with the method of its light: the D-buffer for a disk, linear-ssm for a line.
        let method = if scene.light.as_area().is_some() {
            Method::DBUFFER
        } else {
            "linear-ssm".parse().unwrap()
        };
        let request = FrameRequest {
            width: 128,
            height: 128,
            dbuffer_size: 512,
            method,
            vt: VtVariant::Smoothstep,
            ..FrameRequest::default()
        };
        let (frame, _) = offline
            .render(&scene, &request)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let rgba: Vec<u8> = frame.color.iter().flatten().copied().collect();
        snapshot::check_snapshot(&format!("render-{name}"), 128, 128, &rgba);
    }
}

#[test]
fn hard_method_matches_its_snapshot() {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let scene = scene::load("fig8c-complex").unwrap_or_else(|e| panic!("{e}"));
    let request = FrameRequest {
        width: 128,
        height: 128,
        dbuffer_size: 512,
        method: Method::HARD,
        vt: VtVariant::Smoothstep,
        ..FrameRequest::default()
    };
    let (frame, _) = offline
        .render(&scene, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    let rgba: Vec<u8> = frame.color.iter().flatten().copied().collect();
    snapshot::check_snapshot("render-hard-fig8c-complex", 128, 128, &rgba);
}

/// One snapshot per method (fig7-concave, or line-fig9 for a method that needs a line light;
/// 96×96, D-buffer 512², default knobs; the reference with K = 64 so the test stays quick).
#[test]
fn every_method_matches_its_snapshot() {
    let mut offline = Offline::new().unwrap_or_else(|e| panic!("{e}"));
    let disk = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let line = scene::load("line-fig9").unwrap_or_else(|e| panic!("{e}"));
    for &method in Method::all() {
        let scene = if method.takes(disk.light.kind()) {
            &disk
        } else {
            &line
        };
        let request = FrameRequest {
            width: 96,
            height: 96,
            dbuffer_size: 512,
            method,
            knobs: dbuffer::render::Knobs::default()
                .with(&dbuffer::render::methods::reference::SAMPLES, 64),
            ..FrameRequest::default()
        };
        let (frame, _) = offline
            .render(scene, &request)
            .unwrap_or_else(|e| panic!("{method}: {e}"));
        let rgba: Vec<u8> = frame.color.iter().flatten().copied().collect();
        snapshot::check_snapshot(&format!("method-{method}-{}", scene.name), 96, 96, &rgba);
    }
}
