//! The lab as a user drives it: the whole eframe app on the wgpu (lavapipe) adapter, through its
//! widgets and the mouse. Snapshot thresholds are in `kittest.toml`.

use dbuffer::app::{LabApp, LabOptions, Level, Selection, View};
use dbuffer::render::Method;
use eframe::egui;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;

use crate::support::{
    self as support_lab, drop_file, step_until_gpu, step_until_worker, worker, Worker,
};
use std::time::Duration;

/// The lab in a test window tall enough for the left panel with every method of the registry
/// and the view's range controls open (its last section, Selection, must stay clickable).
fn lab(scene: Option<&str>) -> Harness<'static, LabApp> {
    support_lab::lab_sized(scene, 900.0, 720.0)
}

/// The frame the viewport shows, read back whole (`split`: its right side).
fn shown_frame(h: &mut Harness<'_, LabApp>, split: bool) -> dbuffer::render::Frame {
    h.state_mut().read_shown(split).expect("a frame")
}

/// V of the shown frame at a pixel.
fn v_at(h: &mut Harness<'_, LabApp>, x: u32, y: u32) -> f32 {
    let f = shown_frame(h, false);
    f.visibility[(y * f.width + x) as usize]
}

/// Long enough for any reference a test asks for on a loaded machine: the waits end as soon as
/// what they wait for has arrived, so only a broken worker ever waits this long.
const WORKER_LIMIT: Duration = Duration::from_secs(120);

/// Step the window until the reference worker has finished (it casts its rays on its own
/// thread, in real time).
fn until_reference_done(h: &mut Harness<'_, LabApp>) {
    let done = step_until_worker(h, Worker::Area, WORKER_LIMIT, |h| {
        h.state().core().is_some_and(|c| {
            !c.worker.busy() && c.session.reference_progress().is_some_and(|(d, t)| d == t)
        })
    });
    assert!(done, "the reference did not finish");
    h.run();
}

/// Step the window until the frame shown is `reference-hard`'s (its rays are cast on a worker
/// thread, in real time).
fn until_reference_hard_shown(h: &mut Harness<'_, LabApp>) {
    let shown = step_until_worker(h, Worker::Hard, WORKER_LIMIT, |h| {
        h.state()
            .shown()
            .is_some_and(|s| s.method == Method::REFERENCE_HARD)
    });
    assert!(shown, "reference-hard did not arrive");
    h.run();
}

fn click(h: &mut Harness<'_, LabApp>, label: &str) {
    h.get_by_label(label).click();
    h.run();
}

#[test]
fn starts_on_the_default_scene_with_soft_shadows() {
    let mut h = lab(None);
    h.run();
    let app = h.state();
    assert_eq!(app.scene_name(), dbuffer::app::DEFAULT_SCENE);
    assert_ne!(app.status().1, Level::Error, "{}", app.status().0);
    assert!(app.shown().is_some(), "the first frame is shown");
    let rect = app.viewport_rect().expect("a viewport");
    let f = shown_frame(&mut h, false);
    // Rendered at the resolution setting (half the viewport's pixels).
    assert_eq!(f.width, (rect.width() * 0.5).round() as u32);
    let lit: Vec<f32> = (0..f.visibility.len())
        .filter(|&i| f.hit(i))
        .map(|i| f.visibility[i])
        .collect();
    let dark = lit.iter().filter(|v| **v < 0.05).count();
    let bright = lit.iter().filter(|v| **v > 0.95).count();
    let soft = lit.iter().filter(|v| (0.1..0.9).contains(*v)).count();
    assert!(
        dark > 50 && bright > 50 && soft > 20,
        "umbra {dark}, lit {bright}, penumbra {soft}"
    );
}

#[test]
fn every_method_and_variant_switches_and_shows_at_once() {
    use egui_kittest::kittest::NodeT;
    let mut h = lab(None);
    h.run();
    let light = h.state().scene().expect("scene").light.kind();
    for &m in Method::all() {
        if m.refuses(light).is_some() {
            // Greyed for this scene's light (linear-ssm under the default disk).
            assert!(
                h.get_by_label(m.name()).accesskit_node().is_disabled(),
                "{m}"
            );
            continue;
        }
        click(&mut h, m.name());
        if m.is_reference() {
            until_reference_done(&mut h);
        }
        if m == Method::REFERENCE_HARD {
            until_reference_hard_shown(&mut h);
        }
        let app = h.state();
        assert_eq!(app.settings.method(), m);
        let shown = app.shown().expect("a frame").method;
        assert_eq!(shown, m, "status: {:?}", app.status());
        assert_ne!(app.status().1, Level::Error, "{m}: {:?}", app.status());
    }
    click(&mut h, Method::DBUFFER.name());
    let mut images = Vec::new();
    for vt in dbuffer::geometry::VtVariant::ALL {
        click(&mut h, vt.name());
        assert_eq!(h.state().settings.vt(), vt);
        images.push(shown_frame(&mut h, false).visibility);
    }
    // smoothstep, sqrt, exact and linear give four different V images.
    for i in 0..images.len() {
        for j in i + 1..images.len() {
            assert_ne!(images[i], images[j], "variants {i} and {j} look the same");
        }
    }
}

#[test]
fn every_view_and_overlay_changes_the_viewport() {
    let mut h = lab(None);
    h.run();
    let mut shots = Vec::new();
    for (label, view) in [
        ("final", View::Final),
        ("V", View::Visibility),
        ("t", View::T),
        ("classes", View::Classes),
        ("error", View::Error),
        ("cost", View::Cost),
        ("NaN / range", View::Range),
        ("|cx_o|", View::DBuffer),
        ("|cx_uv|", View::DBuffer),
        ("|cx_pv|", View::DBuffer),
        ("|cx_s|", View::DBuffer),
    ] {
        click(&mut h, label);
        assert_eq!(h.state().settings.view, view, "{label}");
        shots.push((label, h.render().expect("render")));
    }
    for i in 0..shots.len() {
        for j in i + 1..shots.len() {
            assert!(
                shots[i].1 != shots[j].1,
                "views {} and {} look the same",
                shots[i].0,
                shots[j].0
            );
        }
    }
    click(&mut h, "final");
    let before = h.render().expect("render");
    for label in [
        "Face classes",
        "Umbra volume",
        "Penumbra volume",
        "Silhouette edges",
    ] {
        click(&mut h, label);
        let on = h.render().expect("render");
        assert!(on != before, "{label} drew nothing");
        click(&mut h, label);
    }
    let o = h.state().settings.overlays;
    assert!(!o.classes && !o.umbra_volume && !o.penumbra_volume && !o.silhouettes);
    click(&mut h, "Light outline");
    assert!(!h.state().settings.overlays.light_outline);
}

/// The reference engine set to the GPU: the split view's reference is traced there (batches
/// picked up frame by frame, the CPU's worker idle) and converges to the CPU's reference of the
/// view, but for grazing rays.
#[test]
fn the_split_views_reference_converges_on_the_gpu() {
    let mut h = lab(None);
    h.state_mut().settings.reference_engine = "gpu".into();
    h.run();
    click(&mut h, "Split view");
    let done = step_until_gpu(&mut h, 2000, |h| {
        h.state().core().is_some_and(|c| {
            !c.reference_busy()
                && c.tracing_progress().is_some_and(|(_, d, t)| d == t)
                && h.state()
                    .shown_split()
                    .and_then(|s| s.reference)
                    .is_some_and(|(d, t)| d == t)
        })
    });
    assert!(done, "the GPU's reference did not finish");
    let core = h.state().core().expect("a core");
    assert_eq!(core.reference_engine(), dbuffer::render::truth::Engine::Gpu);
    assert!(core.gpu_worker.news() > 0, "batches came back from the GPU");
    assert_eq!(core.worker.steps(), 0, "the CPU's worker cast nothing");
    let scene = h.state().scene().expect("scene").clone();
    let right = shown_frame(&mut h, true);
    let k = h.state().settings.reference_samples;
    let cpu =
        dbuffer::render::reference::compute(&scene, right.width, right.height, k, &mut |_, _| {});
    let mean = cpu
        .visibility
        .iter()
        .zip(&right.visibility)
        .map(|(a, b)| f64::from((a - b).abs()))
        .sum::<f64>()
        / cpu.visibility.len().max(1) as f64;
    assert!(mean < 1e-3, "mean |ΔV| {mean} against the CPU's reference");
}

#[test]
fn split_view_shows_two_methods() {
    let mut h = lab(None);
    h.run();
    click(&mut h, "Split view");
    until_reference_done(&mut h);
    let app = h.state();
    assert!(app.settings.split);
    let left = app.shown().expect("left").method;
    let right = app.shown_split().expect("right").method;
    assert_eq!((left, right), (Method::DBUFFER, Method::REFERENCE));
    // The reference on the right has converged (K = 16) and differs from the method.
    assert_ne!(
        shown_frame(&mut h, false).visibility,
        shown_frame(&mut h, true).visibility
    );
    h.run();
    assert!(h.state().settings.split, "still split after more frames");
}

#[test]
fn snapshots() {
    let mut h = lab(Some("table1-224"));
    h.run();
    h.snapshot("app-table1-224");
    click(&mut h, "classes");
    click(&mut h, "Umbra volume");
    click(&mut h, "Penumbra volume");
    h.snapshot("app-classes-volumes");
    click(&mut h, "|cx_pv|");
    h.snapshot("app-dbuffer-pv");
}

/// The hard-shadow techniques in the lab: Crow's volume and the centre's silhouettes
/// over `shadow-volume`, the edges `hybrid` rebuilt from its depth map (they come back from the
/// GPU a frame or more later), and the extended light map's channels.
#[test]
fn hard_methods_show_their_overlays_and_maps() {
    let method = |n: &str| n.parse::<Method>().expect("a method");
    let mut h = lab(Some("fig7-concave"));
    h.run();
    click(&mut h, "shadow-volume");
    click(&mut h, "Umbra volume");
    click(&mut h, "Silhouette edges");
    let sides = |h: &Harness<'_, LabApp>, m: &str| {
        h.state()
            .core()
            .and_then(|c| c.session.geometry(method(m)))
            .map_or((0, 0), |g| {
                let volume: usize = g.casters.iter().map(|c| c.volumes.indices.len() / 3).sum();
                let edges: usize = g.casters.iter().map(|c| c.silhouettes.len()).sum();
                (volume, edges)
            })
    };
    let (volume, edges) = sides(&h, "shadow-volume");
    assert!(
        volume > 0 && edges > 0,
        "{volume} volume triangles, {edges} edges"
    );
    assert_eq!(
        h.state().shown().expect("shown").method,
        method("shadow-volume")
    );
    h.snapshot("app-shadow-volume-volumes");

    // Its edges come back from the GPU a frame or more later: step until they have.
    h.get_by_label("hybrid").click();
    step_until_gpu(&mut h, 100, |h| sides(h, "hybrid").1 > 0);
    let tops = sides(&h, "hybrid").1;
    assert!(tops > 0, "{tops} reconstructed edges");
    assert_eq!(h.state().shown().expect("shown").method, method("hybrid"));
    h.run();
    h.snapshot("app-hybrid-edges");

    click(&mut h, "extended-light-map");
    click(&mut h, "light R");
    let app = h.state();
    assert_eq!(app.settings.view, View::DBuffer);
    let names: Vec<&str> = app
        .core()
        .and_then(|c| c.session.light_maps(method("extended-light-map")))
        .map(|m| m.channels.iter().map(|c| c.name).collect())
        .unwrap_or_default();
    assert_eq!(names, ["light R", "light G", "light B", "distance (A)"]);
    assert_ne!(app.status().1, Level::Error, "{:?}", app.status());
    h.snapshot("app-elm-light-r");
}

/// The new methods' overlays: the wedges (in the penumbra volume's outline, beside the hard
/// volume's sides) and a line light with its two ends and linear-ssm's samples.
#[test]
fn overlay_snapshots_of_wedges_and_a_line_light() {
    let mut h = lab(Some("table1-224"));
    h.run();
    click(&mut h, "wedges");
    click(&mut h, "Umbra volume");
    click(&mut h, "Penumbra volume");
    h.snapshot("app-wedges-overlay");
    h.state_mut().open_scene("line-fig9");
    h.run();
    click(&mut h, "light");
    click(&mut h, "Umbra volume");
    click(&mut h, "Penumbra volume");
    // Frame the casters and the light: the segment and its handles in view.
    h.key_press(egui::Key::F);
    h.run();
    h.snapshot("app-line-light");
}

#[test]
fn dragging_the_light_moves_the_shadow() {
    let mut h = lab(None);
    h.run();
    // The light first: the V view's range controls push the Selection section further down.
    click(&mut h, "light");
    click(&mut h, "V");
    assert_eq!(h.state().selection, Selection::Light);
    h.key_press(egui::Key::F);
    h.run();
    let start = h.state().scene().expect("scene").light.center();
    let at = h
        .state()
        .light_screen_pos()
        .expect("the light is in view after F");
    let rect = h.state().viewport_rect().expect("viewport");
    assert!(rect.contains(at), "{at:?} outside {rect:?}");
    // The darkest pixel (deepest umbra) before the move.
    let f = shown_frame(&mut h, false);
    let (x, y) = (0..f.visibility.len())
        .filter(|&i| f.hit(i))
        .min_by(|&a, &b| f.visibility[a].total_cmp(&f.visibility[b]))
        .map(|i| (i as u32 % f.width, i as u32 / f.width))
        .expect("a surface");
    let before = v_at(&mut h, x, y);
    assert!(before < 0.05, "{before}");

    h.drag_at(at);
    h.step();
    for k in 1..=6 {
        h.hover_at(at + egui::vec2(25.0 * k as f32, 0.0));
        h.step();
    }
    h.drop_at(at + egui::vec2(150.0, 0.0));
    h.run();
    let moved = h.state().scene().expect("scene").light.center();
    assert!((moved - start).length() > 0.5, "light {start} → {moved}");
    let after = v_at(&mut h, x, y);
    assert!(after > before + 0.5, "V at ({x}, {y}): {before} → {after}");
    // While dragging, only the probes' bytes came back: never a frame.
    let (_, most) = h.state().read_bytes().expect("frames were submitted");
    assert!(most <= 4096, "{most} bytes read back in one frame");

    // One drag, one undo step.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.run();
    assert_eq!(h.state().scene().expect("scene").light.center(), start);
    assert!((v_at(&mut h, x, y) - before).abs() < 1e-6);
}

/// The error view's FLIP choice: once the reference has converged the viewport shows the FLIP
/// map of the method's image against the reference's — not |ΔV|, and not the image — and the
/// reference shown against itself scores 0 everywhere.
#[test]
fn the_flip_view_shows_flip_against_the_reference() {
    let mut h = lab(None);
    h.run();
    click(&mut h, "error");
    until_reference_done(&mut h);
    let error = h.render().expect("render");
    click(&mut h, "FLIP");
    assert_eq!(h.state().settings.view, View::Flip);
    until_reference_done(&mut h);
    h.run();
    let flip = h.render().expect("render");
    assert!(flip != error, "the FLIP view is not the |ΔV| view");
    let shown = shown_frame(&mut h, false);
    let key = {
        let app = h.state();
        app.shown().expect("a frame").request
    };
    assert_eq!(key.method, Method::DBUFFER);
    // The map on the GPU is FLIP of the two images: recompute it from the reference's image.
    click(&mut h, "reference");
    until_reference_done(&mut h);
    h.run();
    let truth = shown_frame(&mut h, false);
    let rgb = |f: &dbuffer::render::Frame| -> Vec<[u8; 3]> {
        f.color.iter().map(|c| [c[0], c[1], c[2]]).collect()
    };
    let map = dbuffer::geometry::flip::ldr_flip(
        &rgb(&truth),
        &rgb(&shown),
        shown.width,
        shown.height,
        dbuffer::geometry::flip::DEFAULT_PPD,
    )
    .expect("FLIP");
    let mean = dbuffer::geometry::flip::mean(&map);
    assert!(
        mean > 0.0 && mean < 0.2,
        "D-buffer against the reference: {mean}"
    );
    let against_itself = dbuffer::geometry::flip::ldr_flip(
        &rgb(&truth),
        &rgb(&truth),
        truth.width,
        truth.height,
        dbuffer::geometry::flip::DEFAULT_PPD,
    )
    .expect("FLIP");
    assert!(against_itself.iter().all(|&v| v == 0.0));
}

/// While the light is dragged, the viewport plots the shown method's temporal error over the
/// last seconds (against a low-K reference at a grid of pixels, or the method's own change where
/// the reference cannot keep up): a value a new frame, each from the 2.3 KiB the probe reads.
#[test]
fn dragging_the_light_plots_the_temporal_error() {
    let mut h = lab(None);
    h.run();
    click(&mut h, "light");
    h.key_press(egui::Key::F);
    h.run();
    assert!(!h.state().motion_showing(), "no plot before a drag");
    let at = h
        .state()
        .light_screen_pos()
        .expect("the light is in view after F");
    h.drag_at(at);
    h.step();
    for k in 1..=6 {
        h.hover_at(at + egui::vec2(20.0 * k as f32, 0.0));
        h.step();
    }
    let (values, measure) = h.state().motion_series();
    assert!(values.len() >= 4, "a value a frame of the drag: {values:?}");
    assert!(
        values.iter().all(|v| v.is_finite() && *v >= 0.0),
        "{values:?}"
    );
    assert!(measure.is_some());
    assert!(h.state().motion_showing(), "the plot shows while dragging");
    // The shadow moved: some step changed V, and the reference's change did not cancel all of it
    // (the D-buffer is not the reference), or the method moved on its own.
    assert!(values.iter().any(|&v| v > 0.0), "{values:?}");
    // Still only probes come back while dragging.
    let (_, most) = h.state().read_bytes().expect("frames were submitted");
    assert!(most <= 4096, "{most} bytes read back in one frame");
    h.drop_at(at + egui::vec2(140.0, 0.0));
    h.run();
}

#[test]
fn a_malformed_scene_is_reported_and_the_scene_kept() {
    let dir = std::env::temp_dir().join(format!("dbuffer-app-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let bad = dir.join("broken.toml");
    std::fs::write(
        &bad,
        "[camera]\neye = [0, 3, 6]\ntarget = [0, 0, 0]\nfov_y_deg = 45\n[light]\ncenter = [0, 4, 0]\nnormal = [0, -1, 0]\nradius = 0\n",
    )
    .expect("write");
    let mut h = lab(None);
    h.run();
    let frames = h.state().frames_rendered();
    h.get_by_label("Scene path").focus();
    h.get_by_label("Scene path")
        .type_text(&bad.display().to_string());
    h.run();
    click(&mut h, "Open path");
    let app = h.state();
    let (text, level) = app.status();
    assert_eq!(level, Level::Error);
    assert!(
        text.contains("broken.toml") && text.contains("light.radius"),
        "{text}"
    );
    assert_eq!(app.scene_name(), dbuffer::app::DEFAULT_SCENE);
    assert!(app.shown().is_some());
    assert!(app.frames_rendered() >= frames);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_window_keeps_making_frames_while_the_reference_converges() {
    let mut h = lab(None);
    h.state_mut().settings.reference_samples = 4096;
    h.run();
    click(&mut h, "reference");
    // Window frames between reference steps: the rays are cast on the worker thread, not in the
    // frame, so the window runs on while a step is under way.
    let start = std::time::Instant::now();
    let steps = |h: &Harness<'_, LabApp>| h.state().core().expect("a core").worker.steps();
    let mut between = Vec::new();
    let mut last = (steps(&h), h.state().window_frames());
    let mut changes = 0;
    while between.len() < 5 && start.elapsed() < WORKER_LIMIT {
        let seen = worker(&h, Worker::Area).news();
        h.step();
        // A window frame every 5 ms at most (a 200 Hz display), sooner when a step has ended.
        worker(&h, Worker::Area).wait_for_news(seen, Duration::from_millis(5));
        let now = (steps(&h), h.state().window_frames());
        if now.0 != last.0 {
            changes += 1;
            // The first interval started mid-step: count whole ones only.
            if changes > 1 {
                between.push(now.1 - last.1);
            }
            last = now;
        }
    }
    assert!(
        between.len() >= 5,
        "the reference took {changes} steps in two minutes"
    );
    // Rays cast inside the frame would give one window frame per step, every time. A loaded
    // machine can slow one window frame past a step (~90 ms), so the typical interval counts.
    let mut sorted = between.clone();
    sorted.sort_unstable();
    assert!(
        sorted[sorted.len() / 2] >= 2 && between.iter().sum::<u64>() >= 2 * between.len() as u64,
        "window frames between reference steps: {between:?}"
    );
    let app = h.state();
    let (done, total) = app
        .core()
        .and_then(|c| c.session.reference_progress())
        .expect("the reference is on the GPU");
    assert!(done > 0 && done < total, "{done}/{total}: still converging");
    assert!(app.window_frames() > 10);
}

/// `reference-hard` casts its rays on a worker thread, as the reference does: the window keeps
/// making frames from the click until V arrives (showing the last picture and a note
/// meanwhile), and what arrives is the exact hard shadow of the view shown.
#[test]
fn the_window_keeps_making_frames_while_reference_hard_is_cast() {
    let mut h = lab(None);
    // Full resolution: enough rays that casting them takes many window frames' time.
    h.state_mut().settings.render_scale = 1.0;
    h.run();
    assert_eq!(h.state().shown().expect("a frame").method, Method::DBUFFER);
    let steps = |h: &Harness<'_, LabApp>| h.state().core().expect("a core").hard_worker.steps();
    let before = steps(&h);
    let frames = h.state().window_frames();
    h.get_by_label(Method::REFERENCE_HARD.name()).click();
    let start = std::time::Instant::now();
    let mut waiting_note = false;
    while steps(&h) == before && start.elapsed() < WORKER_LIMIT {
        let seen = worker(&h, Worker::Hard).news();
        h.step();
        let shown = h.state().shown().expect("the last frame stays shown");
        if shown.method == Method::DBUFFER {
            waiting_note |= shown
                .note
                .as_deref()
                .is_some_and(|n| n.starts_with("reference-hard:"));
        }
        // A window frame every 2 ms at most, sooner when the rays have arrived.
        worker(&h, Worker::Hard).wait_for_news(seen, Duration::from_millis(2));
    }
    let between = h.state().window_frames() - frames;
    println!(
        "reference-hard: {between} window frames in {:.0} ms from the click to V's arrival",
        start.elapsed().as_secs_f64() * 1e3
    );
    assert!(
        steps(&h) > before,
        "reference-hard did not arrive in two minutes"
    );
    // The click's frame asks for it; the window ran on while the worker cast the rays.
    assert!(
        between >= 3,
        "{between} window frames from the click to V's arrival"
    );
    assert!(waiting_note, "the last picture, with a note, while waiting");
    until_reference_hard_shown(&mut h);
    assert_ne!(
        h.state().status().1,
        Level::Error,
        "{:?}",
        h.state().status()
    );
    assert!(h.state().shown().expect("shown").note.is_none());
    // What it shows is the exact hard shadow of this view, pixel for pixel.
    let f = shown_frame(&mut h, false);
    let scene = h.state().core().expect("a core").session.scene().clone();
    let exact = dbuffer::render::reference::compute_hard(&scene, f.width, f.height).visibility;
    let hits: Vec<usize> = (0..f.len()).filter(|&i| f.hit(i)).collect();
    let wrong = hits
        .iter()
        .filter(|&&i| f.visibility[i] != exact[i])
        .count();
    assert_eq!(wrong, 0, "of {} pixels", hits.len());
    println!("{}x{}: {} pixels, all exact", f.width, f.height, hits.len());
    let dark = hits.iter().filter(|&&i| exact[i] == 0.0).count();
    assert!(
        dark > 100 && dark < hits.len() - 100,
        "{dark} dark of {}",
        hits.len()
    );
}

#[test]
fn a_dropped_model_opens_and_a_dropped_bad_file_keeps_the_scene() {
    let mut h = lab(None);
    h.run();
    let first = shown_frame(&mut h, false);

    // A file the lab does not open: the status says which kinds it does.
    let dir = std::env::temp_dir().join(format!("dbuffer-drop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let notes = dir.join("notes.txt");
    std::fs::write(&notes, "not a scene").expect("write");
    drop_file(&mut h, &notes);
    let (text, level) = h.state().status();
    assert_eq!(level, Level::Error);
    assert!(
        text.contains("notes.txt") && text.contains(".glb"),
        "{text}"
    );
    assert_eq!(h.state().scene_name(), dbuffer::app::DEFAULT_SCENE);

    // A truncated model: refused, the scene stays.
    let broken = dir.join("broken.glb");
    std::fs::write(&broken, b"glTF\x02\x00\x00\x00").expect("write");
    drop_file(&mut h, &broken);
    let (text, level) = h.state().status();
    assert_eq!(level, Level::Error);
    assert!(text.contains("broken.glb"), "{text}");
    assert_eq!(h.state().scene_name(), dbuffer::app::DEFAULT_SCENE);

    // The glTF model of assets/ opens and is drawn.
    let fox = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/Fox.glb");
    drop_file(&mut h, &fox);
    let (text, level) = h.state().status();
    assert_ne!(level, Level::Error, "{text}");
    assert!(text.contains("Fox"), "{text}");
    assert_eq!(h.state().scene_name(), "Fox");
    let fox_frame = shown_frame(&mut h, false);
    assert_ne!(
        fox_frame.visibility, first.visibility,
        "the viewport shows the new scene"
    );

    // A model as shipped, with what its reader did not draw said in the status and the panel:
    // the quantized Fox with WebP textures (textures ignored, its skin in the rest pose).
    let shipped =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/models/shipped/fox-webp.glb");
    drop_file(&mut h, &shipped);
    let (text, level) = h.state().status();
    assert_eq!(level, Level::Warning, "{text}");
    assert!(text.contains("fox-webp"), "{text}");
    let warnings = h.state().scene_warnings();
    assert!(
        warnings.iter().any(|w| w.contains("EXT_texture_webp"))
            && warnings.iter().any(|w| w.contains("rest pose")),
        "{warnings:?}"
    );
    assert!(
        text.contains(&warnings[0]),
        "the status names the first: {text}"
    );
    // And a built-in scene after it carries none of the model's notes.
    h.state_mut().open_scene(dbuffer::app::DEFAULT_SCENE);
    h.run();
    assert!(
        !h.state()
            .scene_warnings()
            .iter()
            .any(|w| w.contains("EXT_texture_webp")),
        "{:?}",
        h.state().scene_warnings()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The number of frames an APNG says it has, and its size.
fn apng_frames(path: &std::path::Path) -> (u32, u32, u32) {
    let file = std::fs::File::open(path).expect("animation.png");
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .expect("a PNG");
    let info = reader.info();
    let frames = info.animation_control.expect("an APNG").num_frames;
    (frames, info.width, info.height)
}

#[test]
fn record_orbit_writes_the_frames_and_an_apng_of_the_current_view() {
    let dir = std::env::temp_dir().join(format!("dbuffer-record-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut h = lab(None);
    h.run();
    let (w, h_px) = {
        let s = h.state().shown().expect("a frame");
        (s.request.width, s.request.height)
    };
    click(&mut h, "File");
    click(&mut h, "Record orbit…");
    h.get_by_label("Folder").focus();
    h.get_by_label("Folder")
        .type_text(&dir.display().to_string());
    h.run();
    h.state_mut().record.frames = 3;
    click(&mut h, "Record");
    for _ in 0..50 {
        if h.state().record.progress().is_none() {
            break;
        }
        h.step();
    }
    let (text, level) = h.state().status();
    assert_eq!(level, Level::Info, "{text}");
    assert!(text.contains("recorded 3 frames"), "{text}");
    let frames: Vec<Vec<u8>> = (0..3)
        .map(|k| std::fs::read(dir.join(format!("frame-{k:04}.png"))).expect("a frame file"))
        .collect();
    assert_ne!(frames[0], frames[1], "the light moved between frames");
    assert_eq!(apng_frames(&dir.join("animation.png")), (3, w, h_px));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene with a line light: the disk-only methods are greyed (their reason on hover) and the
/// lab shows the method made for a line; an end of the segment drags alone.
#[test]
fn a_line_light_greys_the_disk_methods_and_its_ends_drag() {
    use egui_kittest::kittest::NodeT;
    let mut h = lab(Some("line-fig2"));
    h.run();
    let linear: Method = "linear-ssm".parse().unwrap();
    assert_eq!(
        h.state().settings.method(),
        linear,
        "dbuffer cannot take a line light"
    );
    assert_ne!(
        h.state().status().1,
        Level::Error,
        "{}",
        h.state().status().0
    );
    for disk_only in ["dbuffer", "dbuffer-center", "pcss", "wedges"] {
        assert!(
            h.get_by_label(disk_only).accesskit_node().is_disabled(),
            "{disk_only} must be greyed under a line light"
        );
    }
    assert!(!h.get_by_label("linear-ssm").accesskit_node().is_disabled());
    // A soft shadow: some pixels strictly between lit and umbra.
    let f = shown_frame(&mut h, false);
    let soft = (0..f.visibility.len())
        .filter(|&i| f.hit(i) && f.visibility[i] > 0.1 && f.visibility[i] < 0.9)
        .count();
    assert!(soft > 100, "{soft} penumbra pixels");

    click(&mut h, "light");
    h.key_press(egui::Key::F);
    h.run();
    let line = *h
        .state()
        .scene()
        .expect("scene")
        .light
        .as_line()
        .expect("a line light");
    let b = h.state().screen_pos(line.b).expect("end b in view");
    h.drag_at(b);
    h.step();
    for k in 1..=4 {
        h.hover_at(b + egui::vec2(0.0, 15.0 * k as f32));
        h.step();
    }
    h.drop_at(b + egui::vec2(0.0, 60.0));
    h.run();
    assert_eq!(h.state().selection, Selection::LightEnd(1));
    let moved = *h.state().scene().expect("scene").light.as_line().unwrap();
    assert!(
        (moved.b - line.b).length() > 0.1,
        "b {} → {}",
        line.b,
        moved.b
    );
    assert_eq!(moved.a, line.a, "a stays");
}

/// A window shrunk to nothing (minimised, or a 0×0 viewport) makes no frame and no error; grown
/// again, the lab renders as before.
#[test]
fn a_zero_sized_window_renders_nothing_and_recovers() {
    let mut h = lab(None);
    h.run();
    assert!(h.state().shown().is_some());
    for size in [
        egui::vec2(0.0, 0.0),
        egui::vec2(900.0, 0.0),
        egui::vec2(1.0, 1.0),
    ] {
        h.set_size(size);
        for _ in 0..5 {
            h.step();
        }
        let (text, level) = h.state().status();
        assert_ne!(level, Level::Error, "{size:?}: {text}");
    }
    h.set_size(egui::vec2(900.0, 720.0));
    h.run();
    // Grown again, it shows a frame of the viewport's size (the one it had: still valid).
    let shown = h.state().shown().expect("a frame after growing again");
    let rect = h.state().viewport_rect().expect("viewport");
    let scale = h.state().settings.render_scale;
    assert_eq!(
        (shown.request.width, shown.request.height),
        (
            (rect.width() * scale).round() as u32,
            (rect.height() * scale).round() as u32
        )
    );
}

/// The GPU device lost (here destroyed, which wgpu reports as a lost device): the lab does not
/// panic, says so on the status line and keeps its window running.
#[test]
fn a_lost_device_is_reported_not_a_panic() {
    let mut h = lab(Some("fig7-concave"));
    h.run();
    let frames = h.state().window_frames();
    h.state()
        .core()
        .expect("a render core")
        .ctx
        .device
        .destroy();
    // Something that needs a new frame: another method.
    click(&mut h, "hard");
    for _ in 0..10 {
        h.step();
    }
    let (text, level) = h.state().status();
    assert_eq!(level, Level::Error, "{text}");
    assert!(
        text.contains("device was lost") && text.contains("start dbuffer again"),
        "{text}"
    );
    assert!(h.state().window_frames() > frames);
}

/// Moving the cursor over the viewport changes the inspector's rows and the light panel, and
/// egui lays the right panel out anew for a pass: the reference must not start over (its
/// samples only ever grow while nothing in the scene, the camera or the size changes).
#[test]
fn hovering_never_restarts_the_reference() {
    let mut h = lab(Some("fig7-concave"));
    h.state_mut().settings.reference_samples = 4096;
    h.state_mut().settings.split = true;
    h.state_mut().settings.split_method = "reference".into();
    h.run();
    let done = |h: &Harness<'_, LabApp>| {
        h.state()
            .core()
            .and_then(|c| c.worker.progress())
            .map_or(0, |(_, done, _)| done)
    };
    let rect = h.state().viewport_rect().expect("viewport");
    let mut last = done(&h);
    let mut restarts = 0;
    for k in 0..40 {
        let t = k as f32 / 40.0;
        h.hover_at(egui::pos2(
            rect.left() + rect.width() * (0.2 + 0.6 * t),
            rect.top() + rect.height() * (0.3 + 0.5 * (1.0 - t)),
        ));
        let seen = worker(&h, Worker::Area).news();
        h.step();
        // A cursor move every 15 ms at most, sooner when the reference has new samples.
        worker(&h, Worker::Area).wait_for_news(seen, Duration::from_millis(15));
        let now = done(&h);
        restarts += usize::from(now < last);
        last = now;
    }
    assert_eq!(restarts, 0, "the reference started over {restarts} times");
    // The cursor at rest, the samples go on growing from where they were.
    let grew = step_until_worker(&mut h, Worker::Area, WORKER_LIMIT, |h| done(h) > last);
    assert!(grew && done(&h) >= last, "the reference made progress");
}

/// `dbuffer gui --bench N`: the scripted window goes through its five phases in each of its
/// rounds, renders only where a phase asks for it (never in `blank`, `image` or `still`; in
/// `orbit` and `light`, as the camera or the light moves), puts the camera and the light back
/// where they were, and writes its JSON: each phase over the rounds, and the orbit over the
/// floor as the median of the rounds' ratios.
#[test]
fn the_window_bench_runs_its_phases_and_puts_the_scene_back() {
    use dbuffer::app::window_bench::{Phase, PHASES, ROUNDS};
    const FRAMES: u32 = 3;
    let out =
        std::env::temp_dir().join(format!("dbuffer-window-bench-{}.json", std::process::id()));
    let _ = std::fs::remove_file(&out);
    let bench_out = out.clone();
    let mut h = Harness::builder()
        .with_size(egui::vec2(900.0, 720.0))
        .with_max_steps(500)
        .wgpu()
        .build_eframe(move |cc| {
            let mut app = LabApp::new(
                cc,
                LabOptions {
                    deterministic: true,
                    window_bench: Some(FRAMES),
                    window_bench_out: Some(bench_out),
                    ..LabOptions::default()
                },
            );
            app.settings.dbuffer_size = 256;
            app.settings.render_scale = 0.5;
            app
        });
    h.step();
    let camera = h.state().camera;
    let light = h.state().scene().expect("a scene").light;
    let mut steps = 0;
    while h.state().window_bench_outcome().is_none() && steps < 600 {
        h.step();
        steps += 1;
    }
    let report = match h.state().window_bench_outcome() {
        Some(Ok(r)) => r,
        other => panic!("the bench did not end with a report: {other:?}"),
    };
    let phases: Vec<Phase> = report.phases.iter().map(|p| p.phase).collect();
    assert_eq!(phases, PHASES.to_vec());
    assert_eq!(report.rounds.len(), ROUNDS as usize);
    for round in &report.rounds {
        let order: Vec<Phase> = round.iter().map(|p| p.phase).collect();
        assert_eq!(order, PHASES.to_vec(), "every round runs the five phases");
        for p in round {
            assert_eq!(p.frames, FRAMES);
            assert!(p.fps > 0.0 && p.seconds > 0.0, "{p:?}");
            let moving = matches!(p.phase, Phase::Orbit | Phase::Light);
            if moving {
                assert!(
                    p.renders >= 1 && p.renders <= u64::from(FRAMES),
                    "{:?}: a render a frame at most, {p:?}",
                    p.phase
                );
            } else {
                assert_eq!(p.renders, 0, "{:?} renders nothing: {p:?}", p.phase);
            }
        }
    }
    for p in &report.phases {
        let of: Vec<&_> = report
            .rounds
            .iter()
            .flatten()
            .filter(|r| r.phase == p.phase)
            .collect();
        assert_eq!(p.frames, FRAMES * ROUNDS, "{p:?}");
        let mut fps: Vec<f64> = of.iter().map(|r| r.fps).collect();
        fps.sort_by(f64::total_cmp);
        assert_eq!(
            p.fps,
            fps[fps.len() / 2],
            "the median round's frames a second"
        );
        assert_eq!(p.renders, of.iter().map(|r| r.renders).sum::<u64>());
    }
    let mut ratios: Vec<f64> = report.rounds.iter().map(|r| r[3].fps / r[0].fps).collect();
    assert_eq!(report.orbit_over_floor_rounds, ratios);
    ratios.sort_by(f64::total_cmp);
    assert_eq!(report.orbit_over_floor, Some(ratios[ratios.len() / 2]));
    assert_eq!(h.state().camera, camera, "the orbit puts the camera back");
    let after = h.state().scene().expect("a scene").light;
    assert!(
        (after.center() - light.center()).length() < 1e-6,
        "the light is put back: {:?} against {:?}",
        after.center(),
        light.center()
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&out).expect("the JSON was written")).expect("JSON");
    assert_eq!(json["phases"].as_array().map(Vec::len), Some(5));
    assert_eq!(json["phases"][3]["phase"], "orbit");
    let _ = std::fs::remove_file(&out);
}

/// The inspector's "light as seen from this pixel" panel makes what it casts against on a
/// worker thread and keeps its BVH when only the light moves: the rays after a light drag are
/// cast on the BVH made before it, and agree with an oracle made afresh for the moved light;
/// another scene gets a BVH of its own.
#[test]
fn the_light_panel_keeps_its_bvh_when_the_light_moves() {
    use dbuffer::app::light_panel::PANEL_SAMPLES;
    use dbuffer::geometry::oracle::Oracle;

    let mut h = lab(Some("fig7-concave"));
    h.run();
    click(&mut h, "light");
    assert_eq!(h.state().selection, Selection::Light);
    h.key_press(egui::Key::F);
    h.run();
    // A penumbra pixel of the shown frame, under the cursor.
    let f = shown_frame(&mut h, false);
    let i = (0..f.visibility.len())
        .filter(|&i| f.hit(i) && (0.2..0.8).contains(&f.visibility[i]))
        .nth(40)
        .expect("a penumbra pixel");
    let rect = h.state().viewport_rect().expect("viewport");
    let pos = egui::pos2(
        rect.left() + ((i as u32 % f.width) as f32 + 0.5) / f.width as f32 * rect.width(),
        rect.top() + ((i as u32 / f.width) as f32 + 0.5) / f.height as f32 * rect.height(),
    );
    h.hover_at(pos);
    assert!(step_until_gpu(&mut h, 200, |h| h
        .state()
        .pixel_light()
        .is_some()));
    let before = h.state().light_panel().oracle().expect("made").clone();
    let x = h.state().pixel_light().expect("shown").position;

    // Drag the light aside, then hover the pixel again.
    let at = h.state().light_screen_pos().expect("the light in view");
    h.drag_at(at);
    h.step();
    h.hover_at(at + egui::vec2(60.0, 0.0));
    h.step();
    h.drop_at(at + egui::vec2(120.0, 0.0));
    h.run();
    let scene = h.state().scene().expect("scene").clone();
    assert_ne!(scene.light, *before.light(), "the light moved");
    h.hover_at(pos);
    assert!(step_until_gpu(&mut h, 200, |h| h
        .state()
        .pixel_light()
        .is_some_and(|l| (l.position - x).length() < 1e-5)
        && h.state().light_panel().oracle().map(|o| *o.light())
            == Some(scene.light)));
    let after = h.state().light_panel().oracle().expect("made").clone();
    assert!(
        after.shares_bvh(&before),
        "a light move built the BVH again"
    );
    let panel = h.state().pixel_light().expect("shown").clone();
    let fresh = Oracle::from_scene(&scene, PANEL_SAMPLES);
    assert_eq!(after.sample_points(), fresh.sample_points());
    let blocked = panel.reference.iter().filter(|s| s.blocked).count();
    let visible = fresh.count_visible(panel.position, fresh.sample_points()) as usize;
    assert_eq!(
        blocked + visible,
        PANEL_SAMPLES,
        "the rays as a fresh oracle casts them"
    );

    // Another scene (new triangles): a BVH of its own.
    h.state_mut().open_scene("fig7-concave");
    h.key_press(egui::Key::F);
    h.run();
    h.hover_at(pos);
    assert!(step_until_gpu(&mut h, 200, |h| h
        .state()
        .pixel_light()
        .is_some()));
    let reopened = h.state().light_panel().oracle().expect("made");
    assert!(!reopened.shares_bvh(&before));
}

/// `gui --geometry gpu`: the light dragged over the caster, every build of the geometry stage
/// runs as the GPU's compute passes (no CPU stage output, the `geometry_gpu` pass timed among the
/// GPU's), and the lab shows what the CPU stage gives for the light where it was dropped.
#[test]
fn the_light_drags_with_the_geometry_stage_on_the_gpu() {
    let mut h = support_lab::lab_timed_with(
        LabOptions {
            scene: Some("fig7-concave".into()),
            geometry: Some(2),
            ..LabOptions::default()
        },
        900.0,
        720.0,
    );
    h.run();
    click(&mut h, "light");
    h.key_press(egui::Key::F);
    h.run();
    let start = h.state().scene().expect("scene").light.center();
    let at = h.state().light_screen_pos().expect("the light in view");
    h.drag_at(at);
    h.step();
    for k in 1..=4 {
        h.hover_at(at + egui::vec2(20.0 * k as f32, 10.0 * k as f32));
        h.step();
    }
    h.drop_at(at + egui::vec2(100.0, 50.0));
    h.run();
    let scene = h.state().scene().expect("scene").clone();
    assert!(
        (scene.light.center() - start).length() > 0.2,
        "the light moved"
    );
    let session = &h.state().core().expect("core").session;
    assert!(
        session.gpu_geometry(Method::DBUFFER).is_some(),
        "the GPU stage ran"
    );
    assert!(
        session.geometry(Method::DBUFFER).is_none(),
        "the CPU stage's output is not the last build's"
    );
    let (builds, _) = session.geometry_builds(Method::DBUFFER);
    assert!(
        builds >= 3,
        "a build per light position of the drag: {builds}"
    );
    // Its timings come back a frame or more later.
    let timed = step_until_gpu(&mut h, 100, |h| {
        h.state()
            .gpu_passes()
            .iter()
            .any(|p| p == dbuffer::render::passes::geometry_gpu::SPAN)
    });
    assert!(
        timed,
        "the stage is a timed GPU pass: {:?}",
        h.state().gpu_passes()
    );

    // Its counts come back a frame or more later, without a wait: those of the last build, as
    // a read-back (which waits) gives them; the stats panel lists them.
    let counted = step_until_gpu(&mut h, 100, |h| {
        h.state()
            .core()
            .and_then(|c| c.session.gpu_geometry(Method::DBUFFER))
            .is_some_and(|g| g.last_counts().is_some())
    });
    assert!(counted, "the GPU stage's counts came back");
    {
        let core = h.state().core().expect("core");
        let gpu = core
            .session
            .gpu_geometry(Method::DBUFFER)
            .expect("GPU stage");
        let polled = gpu.last_counts().expect("counts").to_vec();
        let read: Vec<_> = gpu
            .read_back(&core.ctx)
            .expect("read back")
            .into_iter()
            .map(|r| r.counts)
            .collect();
        assert_eq!(polled, read);
        assert!(polled
            .iter()
            .any(|c| c.umbra_edges > 0 && c.penumbra_triangles > 0));
        assert!(gpu.refused_warnings().is_empty());
    }
    let row = h
        .state()
        .core()
        .and_then(|c| c.session.gpu_geometry(Method::DBUFFER))
        .and_then(|g| g.last_counts())
        .map(|c| {
            let (u, p) = c.iter().fold((0, 0), |(u, p), c| {
                (u + c.umbra_edges, p + c.penumbra_edges)
            });
            format!("{u} umbra, {p} penumbra")
        })
        .expect("counts");
    h.run();
    assert!(
        h.query_by_label(&row).is_some(),
        "the stats list the silhouette edges as '{row}'"
    );

    // The frame shown against the CPU stage's for the same light, request and map.
    let shown = h.state().shown().expect("shown").clone();
    let gpu = shown_frame(&mut h, false);
    let ctx = &h.state().core().expect("core").ctx;
    let mut request = shown.request;
    request.knobs = request
        .knobs
        .with(&dbuffer::render::methods::dbuffer::GEOMETRY, 1);
    let mut cpu_session = dbuffer::render::Session::new(ctx, scene);
    let cpu = cpu_session
        .frame(ctx, &request)
        .expect("the CPU path's frame");
    assert_eq!((gpu.width, gpu.height), (cpu.width, cpu.height));
    let lit = (0..gpu.len()).filter(|&i| gpu.hit(i)).count();
    let off = (0..gpu.len())
        .filter(|&i| gpu.hit(i) && (gpu.visibility[i] - cpu.visibility[i]).abs() > 0.02)
        .count();
    assert!(lit > 1000, "{lit} surface pixels");
    assert!(
        off * 200 <= lit,
        "{off} of {lit} pixels differ by more than 0.02 between the paths"
    );
    let penumbra = (0..gpu.len())
        .filter(|&i| gpu.hit(i) && (0.05..0.95).contains(&gpu.visibility[i]))
        .count();
    assert!(penumbra > 50, "a soft shadow: {penumbra} penumbra pixels");
}
