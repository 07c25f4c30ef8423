//! The lab's "light as seen from this pixel" panel on a fusion scene, driven as a
//! user does: `dbuffer-fused` picked, the cursor on a pixel where two casters hide the disk
//! together. The panel's reference rays, its chords and its mask are checked against the
//! oracle, the fused twin and the GPU's V at that pixel.

use dbuffer::app::light_panel::{fused_params, PANEL_SAMPLES};
use dbuffer::app::LabApp;
use dbuffer::geometry::fused::{FusedPath, FusedTwin};
use dbuffer::geometry::oracle::Oracle;
use dbuffer::geometry::{PreparedCasters, VolumeParams};
use dbuffer::render::Method;
use eframe::egui;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;

use crate::support::{self as support_lab, step_until_gpu};

fn lab(scene: &str) -> Harness<'static, LabApp> {
    support_lab::lab_sized(Some(scene), 900.0, 900.0)
}

#[test]
fn the_light_as_seen_from_a_fused_pixel() {
    let mut h = lab("fusion-cross");
    h.run();
    h.get_by_label(Method::DBUFFER_FUSED.name()).click();
    h.run();
    let shown = h.state().shown().expect("a frame").clone();
    assert_eq!(shown.method, Method::DBUFFER_FUSED);
    let scene = h.state().scene().expect("scene").clone();
    let frame = h.state_mut().read_shown(false).expect("the frame");

    // The method's twin, set up as the frame was: pick a penumbra pixel where the disk is more
    // than one layer deep (two casters' chords combine) and the mask ran.
    let prepared = PreparedCasters::new(&scene);
    let geometry = prepared.build(
        &scene.light.area_or_centre(),
        &VolumeParams::for_scene(&scene),
    );
    let twin = FusedTwin::new(&scene, &prepared, &geometry, fused_params(&shown.request));
    let (w, hgt) = (frame.width, frame.height);
    let pick = (0..frame.visibility.len())
        .step_by(7)
        .filter(|&i| frame.hit(i) && (0.2..0.8).contains(&frame.visibility[i]))
        .find_map(|i| {
            let x = frame.position(i)?;
            let l = twin.light_from(x);
            let deep = l.layers.iter().copied().max().unwrap_or(0) >= 2;
            (l.path == FusedPath::Mask && l.exact.is_none() && deep && l.chords.len() >= 3)
                .then_some((i, x, l))
        });
    let (i, x, expected) = pick.expect("a pixel where the casters' shadows fuse");

    // Put the cursor on it.
    let rect = h.state().viewport_rect().expect("viewport");
    let (px, py) = ((i as u32 % w) as f32, (i as u32 / w) as f32);
    let pos = egui::pos2(
        rect.left() + (px + 0.5) / w as f32 * rect.width(),
        rect.top() + (py + 0.5) / hgt as f32 * rect.height(),
    );
    h.hover_at(pos);
    // The probe under the cursor is read back from the GPU a frame or more later.
    step_until_gpu(&mut h, 200, |h| {
        h.state().pixel_light().is_some_and(|l| l.position == x)
    });
    h.run();
    let _ = h.get_by_label("Light as seen from this pixel");
    let panel = h.state().pixel_light().expect("the panel computed").clone();
    assert!(
        (panel.position - x).length() < 1e-5,
        "the panel is for {} not the hovered {x}",
        panel.position
    );
    assert_eq!(panel.method, Method::DBUFFER_FUSED);

    // The chords drawn are the twin's list at that pixel, each cutting the disk.
    let fused = panel.fused.as_ref().expect("the fused view");
    assert_eq!(panel.chords_drawn(), expected.chords.len());
    // (The probe's position and the read-back frame's can differ in the last bit.)
    let ids = |c: &[dbuffer::geometry::fused::PointChord]| -> Vec<(u32, i32)> {
        c.iter().map(|c| (c.edge, c.chord.delta)).collect()
    };
    assert_eq!(ids(&fused.chords), ids(&expected.chords));
    assert!(panel.chords_drawn() >= 3, "{}", panel.chords_drawn());

    // Its reference rays agree with the oracle cast independently with 4× the rays.
    assert_eq!(panel.reference.len(), PANEL_SAMPLES);
    let truth = Oracle::from_scene(&scene, 4 * PANEL_SAMPLES).visibility(x) as f64;
    let blocked = panel.blocked_fraction();
    assert!(
        (blocked - (1.0 - truth)).abs() <= 0.03,
        "panel blocked {blocked:.4}, oracle 1 − V {:.4}",
        1.0 - truth
    );
    assert!(
        blocked > 0.1 && blocked < 0.9,
        "a penumbra pixel: {blocked}"
    );

    // The mask's lit samples are the twin's V, and the GPU's V at the pixel matches both the
    // mask and the panel's reference there.
    let lit = panel.mask_lit_fraction().expect("the mask ran");
    assert!(
        (lit - fused.v).abs() < 1e-9,
        "mask {lit} vs twin V {}",
        fused.v
    );
    let gpu = frame.visibility[i] as f64;
    assert!((gpu - lit).abs() <= 0.02, "GPU V {gpu:.4}, mask {lit:.4}");
    assert!(
        (gpu - (1.0 - blocked)).abs() <= 0.05,
        "GPU V {gpu:.4}, panel's reference {:.4}",
        1.0 - blocked
    );
    h.snapshot("app-light-from-pixel");

    // Every method gets the reference's rays; only dbuffer-fused its chords and mask.
    h.get_by_label(Method::DBUFFER.name()).click();
    h.hover_at(pos);
    step_until_gpu(&mut h, 200, |h| {
        h.state()
            .pixel_light()
            .is_some_and(|l| l.method == Method::DBUFFER)
    });
    let other = h.state().pixel_light().expect("the panel for dbuffer");
    assert_eq!(other.method, Method::DBUFFER);
    assert!(other.fused.is_none() && other.chords_drawn() == 0);
    assert!((other.position - x).length() < 1e-5);
    assert_eq!(other.blocked_fraction(), blocked);
}

#[test]
fn split_view_dbuffer_against_dbuffer_fused() {
    let mut h = lab("fusion-cross");
    h.run();
    h.state_mut().settings.split = true;
    h.state_mut().settings.split_method = Method::DBUFFER_FUSED.name().into();
    h.run();
    let left = h.state().shown().expect("left").method;
    let right = h.state().shown_split().expect("right").method;
    assert_eq!((left, right), (Method::DBUFFER, Method::DBUFFER_FUSED));
    let a = h.state_mut().read_shown(false).expect("left frame");
    let b = h.state_mut().read_shown(true).expect("right frame");
    // Where the bars' shadows cross, the two differ by more than a rounding.
    let differ = (0..a.visibility.len())
        .filter(|&i| a.hit(i) && (a.visibility[i] - b.visibility[i]).abs() > 0.1)
        .count();
    assert!(differ > 20, "{differ} pixels differ by more than 0.1");
}

/// The knot in the lab's split view, dbuffer | dbuffer-fused, at full resolution: the README's
/// picture of what the fused D-buffer changes (`docs/images/lab-fused-split-knot.png` is this snapshot).
/// Inside the knot's shadow the paper's method is brighter where loops hide the disk together.
#[test]
fn the_knot_in_split_view() {
    let mut h = lab("fig8c-complex");
    h.state_mut().settings.render_scale = 1.0;
    h.state_mut().settings.dbuffer_size = 1024;
    h.run();
    h.state_mut().settings.split = true;
    h.state_mut().settings.split_method = Method::DBUFFER_FUSED.name().into();
    h.run();
    let a = h.state_mut().read_shown(false).expect("left frame");
    let b = h.state_mut().read_shown(true).expect("right frame");
    // Where both are in penumbra, the one-chord D-buffer is the brighter one far more often.
    let (mut brighter, mut darker) = (0usize, 0usize);
    for i in 0..a.visibility.len() {
        if !a.hit(i) || !b.hit(i) {
            continue;
        }
        let d = a.visibility[i] - b.visibility[i];
        brighter += usize::from(d > 0.1);
        darker += usize::from(d < -0.1);
    }
    assert!(
        brighter > 200 && brighter > 3 * darker,
        "{brighter} pixels brighter under dbuffer, {darker} darker"
    );
    h.snapshot("app-fused-split-knot");
}
