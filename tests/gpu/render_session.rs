//! A session redoes light-space work only when the light or a caster changed: the geometry and
//! the D-buffer survive any number of camera moves; the camera pass runs every frame.

use dbuffer::geometry::{GeometryStats, VtVariant};
use dbuffer::render::methods::reference::SAMPLES;
use dbuffer::render::{FrameRequest, GpuContext, Knobs, Method, Session};
use dbuffer::scene;
use glam::Vec3;

fn ctx() -> GpuContext {
    GpuContext::headless().unwrap_or_else(|e| panic!("{e}"))
}

fn gpu_passes(frame: &dbuffer::render::Frame) -> Vec<&str> {
    frame.gpu_ms.iter().map(|(p, _)| p.as_str()).collect()
}

/// `passes` with the geometry stage's compute passes first where the D-buffer's last build ran
/// on the GPU (`--geometry auto` on an adapter that can).
fn with_stage<'a>(session: &Session, passes: &[&'a str]) -> Vec<&'a str> {
    let mut out = Vec::new();
    if session.gpu_geometry(Method::DBUFFER).is_some() {
        out.push("geometry_gpu");
    }
    out.extend_from_slice(passes);
    out
}

/// The counts of `method`'s last geometry build, on the CPU or read back from the GPU.
fn stats(ctx: &GpuContext, session: &Session, method: Method) -> GeometryStats {
    match session.geometry(method) {
        Some(g) => g.stats,
        None => {
            let gpu = session.gpu_geometry(method).expect("a geometry build");
            gpu.stats(ctx, session.prepared())
                .unwrap_or_else(|e| panic!("{e}"))
                .stats
        }
    }
}

#[test]
fn geometry_and_light_pass_run_only_when_something_moved() {
    let ctx = ctx();
    let scene = scene::load("table1-224").unwrap_or_else(|e| panic!("{e}"));
    let (light, camera) = (scene.light, scene.camera);
    let mut session = Session::new(&ctx, scene);
    let request = FrameRequest {
        width: 64,
        height: 64,
        dbuffer_size: 256,
        method: Method::DBUFFER,
        vt: VtVariant::Smoothstep,
        ..FrameRequest::default()
    };
    let first = session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    if ctx.timestamps {
        assert_eq!(
            gpu_passes(&first),
            with_stage(&session, &["shadow_map", "dbuffer_volumes", "camera_pass"])
        );
    }
    // The camera moves: only the camera pass runs again.
    let mut cam = camera;
    cam.eye.x += 0.3;
    session.set_camera(cam);
    let second = session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        session.geometry_builds(Method::DBUFFER).0,
        1,
        "one geometry build"
    );
    if ctx.timestamps {
        assert_eq!(
            gpu_passes(&second),
            ["camera_pass"],
            "the D-buffer was kept"
        );
    }
    assert_ne!(first.visibility, second.visibility, "the view moved");
    session.set_camera(camera);
    let third = session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        first.visibility, third.visibility,
        "the same view, the same frame"
    );

    session.set_light(light);
    session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        session.geometry_builds(Method::DBUFFER).0,
        1,
        "setting the same light is no change"
    );

    let moved = light.with_center(light.center() + Vec3::new(1.0, 0.0, 0.0));
    session.set_light(moved);
    let fourth = session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    session
        .frame(&ctx, &request)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        session.geometry_builds(Method::DBUFFER).0,
        2,
        "one rebuild after the light moved"
    );
    if ctx.timestamps {
        assert_eq!(
            gpu_passes(&fourth),
            with_stage(&session, &["shadow_map", "dbuffer_volumes", "camera_pass"])
        );
    }
    let changed = first
        .visibility
        .iter()
        .zip(&fourth.visibility)
        .filter(|(a, b)| (*a - *b).abs() > 0.1)
        .count();
    assert!(
        changed > 50,
        "the shadow moved with the light ({changed} pixels changed)"
    );
}

#[test]
fn the_shadow_map_is_shared_and_methods_without_volumes_build_none() {
    let ctx = ctx();
    let scene = scene::load("table1-224").unwrap_or_else(|e| panic!("{e}"));
    let mut session = Session::new(&ctx, scene);
    let request = |method| FrameRequest {
        width: 48,
        height: 48,
        dbuffer_size: 256,
        method,
        ..FrameRequest::default()
    };
    let hard = session.frame(&ctx, &request(Method::HARD)).unwrap();
    let pcf = session
        .frame(&ctx, &request("pcf".parse().unwrap()))
        .unwrap();
    assert!(session.geometry(Method::HARD).is_none());
    assert_eq!(
        session.geometry_builds(Method::DBUFFER).0,
        0,
        "no volumes for shadow maps"
    );
    if ctx.timestamps {
        assert_eq!(gpu_passes(&hard), ["shadow_map", "camera_pass"]);
        assert_eq!(
            gpu_passes(&pcf),
            ["camera_pass"],
            "the map is made once per light"
        );
    }
    let dbuffer = session.frame(&ctx, &request(Method::DBUFFER)).unwrap();
    if ctx.timestamps {
        assert_eq!(
            gpu_passes(&dbuffer),
            with_stage(&session, &["dbuffer_volumes", "camera_pass"])
        );
    }
}

#[test]
fn the_reference_converges_and_restarts_when_the_view_changes() {
    let ctx = ctx();
    let scene = scene::load("fig7-concave").unwrap_or_else(|e| panic!("{e}"));
    let (light, camera) = (scene.light, scene.camera);
    let mut session = Session::new(&ctx, scene);
    let request = FrameRequest {
        width: 48,
        height: 48,
        dbuffer_size: 256,
        method: Method::REFERENCE,
        knobs: Knobs::default().with(&SAMPLES, 16),
        ..FrameRequest::default()
    };
    assert_eq!(session.reference_progress(), None);
    assert!(
        session.frame(&ctx, &request).is_err(),
        "no reference has been computed for this view"
    );
    let mut frames = Vec::new();
    for k in 1..=4u32 {
        let progress = session.advance_reference(&ctx, &request, 4).unwrap();
        assert_eq!(progress, (4 * k, 16));
        assert_eq!(session.converging(), k < 4);
        frames.push(
            session
                .frame(&ctx, &request)
                .unwrap_or_else(|e| panic!("{e}")),
        );
    }
    // Complete: the frame shows exactly the reference V.
    let done = session
        .reference_visibility(&request)
        .expect("a reference")
        .to_vec();
    assert_eq!(frames[3].visibility, done);
    assert_ne!(
        frames[0].visibility, done,
        "4 of 16 samples is not the whole answer"
    );

    // Moving the light or the camera starts it over, and the old one is not shaded.
    let moved = light.with_center(light.center() + Vec3::new(0.5, 0.0, 0.0));
    session.set_light(moved);
    assert!(session.frame(&ctx, &request).is_err(), "a stale reference");
    assert_eq!(
        session.advance_reference(&ctx, &request, 4).unwrap(),
        (4, 16)
    );
    let mut cam = camera;
    cam.eye.x += 0.5;
    session.set_camera(cam);
    assert_eq!(
        session.advance_reference(&ctx, &request, 4).unwrap(),
        (4, 16)
    );
}

#[test]
fn dbuffer_center_builds_its_own_volumes_and_invalidation_forces_a_rebuild() {
    let ctx = ctx();
    let scene = scene::load("fig1-large-light").unwrap_or_else(|e| panic!("{e}"));
    let mut session = Session::new(&ctx, scene);
    let request = |method| FrameRequest {
        width: 48,
        height: 48,
        dbuffer_size: 256,
        method,
        ..FrameRequest::default()
    };
    let disk = session.frame(&ctx, &request(Method::DBUFFER)).unwrap();
    let disk_stats = stats(&ctx, &session, Method::DBUFFER);
    let centre = session
        .frame(&ctx, &request(Method::DBUFFER_CENTER))
        .unwrap();
    assert_eq!(session.geometry_builds(Method::DBUFFER_CENTER).0, 1);
    // From the centre alone no face is a silhouette face.
    let s = stats(&ctx, &session, Method::DBUFFER_CENTER);
    assert_eq!(s.silhouette_a + s.silhouette_b, 0);
    assert!(disk_stats.silhouette_a + disk_stats.silhouette_b > 0);
    assert_ne!(disk.visibility, centre.visibility);
    // Switching back needs no rebuild: each method keeps its own.
    let back = session.frame(&ctx, &request(Method::DBUFFER)).unwrap();
    assert_eq!(session.geometry_builds(Method::DBUFFER).0, 1);
    assert_eq!(back.visibility, disk.visibility);
    session.invalidate_geometry();
    session.frame(&ctx, &request(Method::DBUFFER)).unwrap();
    assert_eq!(session.geometry_builds(Method::DBUFFER).0, 2);
}

/// `dbuffer-fused`'s whole-grid passes are drawn only over what the casters and proxies cover:
/// a caster moved far aside widens the light view (its texels near the view's border), and moved
/// back narrows it again; the maps after must equal a fresh session's, and so must V.
#[test]
fn a_caster_moved_back_leaves_nothing_of_the_wide_view() {
    let ctx = ctx();
    let fused = Method::DBUFFER_FUSED;
    for name in ["fusion-cross", "overlap"] {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        let index = scene
            .objects
            .iter()
            .position(|o| o.casts_shadow)
            .expect("a caster");
        let request = FrameRequest {
            width: 64,
            height: 64,
            dbuffer_size: 256,
            method: fused,
            ..FrameRequest::default()
        };
        let maps = |session: &mut Session| {
            session
                .frame(&ctx, &request)
                .unwrap_or_else(|e| panic!("{e}"));
            let maps = session
                .read_map_rows(&ctx, fused, 0..request.dbuffer_size)
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(maps.channels[1].name, "list length");
            (0..4).map(|c| maps.raw(1, c)).collect::<Vec<_>>()
        };
        let original = scene.objects[index].mesh.clone();
        let mut aside = original.clone();
        let (lo, hi) = scene.bounds();
        let shift = Vec3::new(hi.x - lo.x, 0.0, 0.0) * 0.4;
        aside.positions.iter_mut().for_each(|p| *p += shift);
        let mut session = Session::new(&ctx, scene.clone());
        session.set_object_mesh(&ctx, index, aside);
        let wide = maps(&mut session);
        session.set_object_mesh(&ctx, index, original);
        let kept = maps(&mut session);
        let kept_v = session.frame(&ctx, &request).map(|f| f.visibility);
        let mut fresh_session = Session::new(&ctx, scene.clone());
        let fresh = maps(&mut fresh_session);
        let fresh_v = fresh_session.frame(&ctx, &request).map(|f| f.visibility);
        let lists = |m: &[Vec<f32>]| m[2].iter().filter(|&&n| n > 0.0).count();
        assert!(lists(&fresh) > 100, "{name}: lists to compare");
        assert!(
            wide[2] != fresh[2],
            "{name}: the wide view's lists are elsewhere"
        );
        for c in 0..4 {
            assert!(
                kept[c] == fresh[c],
                "{name}: dbuffer-fused's map component {c} differs from a fresh session's"
            );
        }
        assert_eq!(kept_v.ok(), fresh_v.ok(), "{name}: V");
    }
}

/// The D-buffer's volume channels are never cleared (a texel of an earlier frame is read as no
/// crossing by its frame tag), and `dbuffer-fused`'s maps drawn only where casters and proxies
/// were or will be: after the light
/// moves (the shadow shrinks, moves, grows) a frame must equal a fresh session's, the D-buffer
/// (the paper's, which `read_dbuffer` reads for either method) included.
#[test]
fn a_moved_light_leaves_nothing_of_the_old_d_buffer() {
    let ctx = ctx();
    for (name, method) in [
        ("table1-960", Method::DBUFFER),
        ("overlap", Method::DBUFFER),
        ("table1-960", Method::DBUFFER_FUSED),
        ("fusion-cross", Method::DBUFFER_FUSED),
    ] {
        let scene = scene::load(name).unwrap_or_else(|e| panic!("{e}"));
        let light = scene.light;
        let mut session = Session::new(&ctx, scene.clone());
        let request = FrameRequest {
            width: 64,
            height: 64,
            dbuffer_size: 128,
            read_dbuffer: true,
            method,
            ..FrameRequest::default()
        };
        session
            .frame(&ctx, &request)
            .unwrap_or_else(|e| panic!("{e}"));
        for (k, offset) in [
            Vec3::new(0.8, 0.0, 0.0),
            Vec3::new(-0.6, 1.0, 0.3),
            Vec3::new(0.0, -0.5, 0.0),
        ]
        .into_iter()
        .enumerate()
        {
            let moved = light.with_center(light.center() + offset);
            session.set_light(moved);
            let kept = session
                .frame(&ctx, &request)
                .unwrap_or_else(|e| panic!("{e}"));
            let mut fresh_scene = scene.clone();
            fresh_scene.light = moved;
            let fresh = Session::new(&ctx, fresh_scene)
                .frame(&ctx, &request)
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(
                kept.visibility, fresh.visibility,
                "{name}, {method}, move {k}: V"
            );
            let (a, b) = (kept.maps.expect("maps"), fresh.maps.expect("maps"));
            for slot in 0..3 {
                for c in 0..2 {
                    assert!(
                        a.raw(slot, c) == b.raw(slot, c),
                        "{name}, {method}, move {k}: light map {slot}.{c} differs from a fresh one"
                    );
                }
            }
        }
    }
}

/// The volume channels' frame tags run 1 … 255 and start over: the targets are cleared whole
/// then, or a texel drawn 255 light passes ago (and never since) would read as this frame's.
/// The first frame's light is far aside, and its shadow elsewhere than all later frames'.
#[test]
fn the_frame_tags_start_over_with_a_clear() {
    let ctx = ctx();
    let scene = scene::load("table1-224").unwrap_or_else(|e| panic!("{e}"));
    let light = scene.light;
    let aside = light.with_center(light.center() + Vec3::new(1.5, 0.0, 0.8));
    let request = FrameRequest {
        width: 48,
        height: 48,
        dbuffer_size: 64,
        read_dbuffer: true,
        method: Method::DBUFFER,
        ..FrameRequest::default()
    };
    let mut first = scene.clone();
    first.light = aside;
    let mut session = Session::new(&ctx, first);
    let frame = |session: &mut Session| {
        session
            .frame(&ctx, &request)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let crossings = |f: &dbuffer::render::Frame| {
        let maps = f.maps.as_ref().expect("maps");
        (1..3)
            .map(|slot| maps.raw(slot, 0).iter().filter(|&&v| v > 0.0).count())
            .sum::<usize>()
    };
    assert!(
        crossings(&frame(&mut session)) > 0,
        "the first frame's volumes"
    );
    session.set_light(light);
    let mut fresh_scene = scene.clone();
    fresh_scene.light = light;
    let fresh = frame(&mut Session::new(&ctx, fresh_scene));
    assert!(crossings(&fresh) > 0, "volumes to compare");
    // The light pass of frame 2 … 256: tags 2 … 255, then 1 again.
    for k in 2..=256 {
        if k > 2 {
            session.invalidate_light_maps();
        }
        let kept = frame(&mut session);
        if k == 2 || k >= 255 {
            let (a, b) = (kept.maps.expect("maps"), fresh.maps.as_ref().expect("maps"));
            for slot in 1..3 {
                for c in 0..2 {
                    assert!(
                        a.raw(slot, c) == b.raw(slot, c),
                        "light pass {k}: light map {slot}.{c} differs from a fresh session's"
                    );
                }
            }
            assert_eq!(kept.visibility, fresh.visibility, "light pass {k}: V");
        }
    }
}
