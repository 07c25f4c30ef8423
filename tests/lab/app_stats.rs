//! The Stats panel lists the GPU passes of the method shown: switched from `dbuffer-fused` to
//! `dbuffer`, the fused method's own passes (timed a frame or more after their frame, so some
//! arrive after the switch) leave the list.

use dbuffer::app::{LabApp, View};
use dbuffer::render::Method;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;

use crate::support::{self as support_lab, step_until_gpu};

/// The passes listed once the method shown is `method` and timings of its frames came back.
fn passes_of(h: &mut Harness<'_, LabApp>, method: Method) -> Vec<String> {
    h.get_by_label(method.name()).click();
    let listed = step_until_gpu(h, 100, |h| {
        h.state().shown().is_some_and(|s| s.method == method) && !h.state().gpu_passes().is_empty()
    });
    assert!(listed, "no pass timings came back for {method}");
    // A few more frames: timings of frames recorded before the switch arrive late, if at all.
    for _ in 0..4 {
        step_until_gpu(h, 1, |_| false);
    }
    h.state().gpu_passes()
}

#[test]
fn the_stats_panel_lists_only_the_passes_of_the_method_shown() {
    let mut h = support_lab::lab_timed("fusion-cross", 900.0, 700.0);
    h.run();
    if !h.state().core().expect("a view session").ctx.timestamps {
        println!("skipped: the adapter has no timestamp queries (the Stats panel lists none)");
        return;
    }
    let plain = passes_of(&mut h, Method::DBUFFER);
    let fused = passes_of(&mut h, Method::DBUFFER_FUSED);
    let own: Vec<&String> = fused.iter().filter(|p| !plain.contains(p)).collect();
    assert!(
        !own.is_empty(),
        "dbuffer-fused times passes of its own: {fused:?} beside {plain:?}"
    );
    let after = passes_of(&mut h, Method::DBUFFER);
    let stale: Vec<&&String> = own.iter().filter(|p| after.contains(p)).collect();
    assert!(
        stale.is_empty(),
        "after switching back to dbuffer the Stats panel still lists {stale:?}: {after:?}"
    );
}

#[test]
fn the_range_view_counts_its_marks_in_the_stats_panel() {
    let mut h = support_lab::lab_sized(Some("fig7-concave"), 900.0, 720.0);
    h.run();
    assert_eq!(
        h.state().out_of_range_px(false),
        None,
        "no count before the view"
    );
    h.get_by_label("NaN / range").click();
    h.run();
    assert_eq!(h.state().settings.view, View::Range);
    let counted = step_until_gpu(&mut h, 100, |h| h.state().out_of_range_px(false).is_some());
    assert!(counted, "the probe's count came back");
    // On lavapipe the built-in D-buffer's V and t are in range everywhere here (the GPU test of
    // the range view spoils some pixels and counts them; the next test holds a count that is
    // not 0 to the frame's).
    let n = h.state().out_of_range_px(false).unwrap_or(u64::MAX);
    assert_eq!(n, 0);
    h.run();
    h.get_by_label("V/t out of range");
    h.get_by_label(&format!("{n} px"));
}

#[test]
fn the_range_count_is_the_shown_frames() {
    // wedges on fusion-cross: a few V a rounding step below 0 (docs/method/metrics.md).
    let mut h = support_lab::lab_sized(Some("fusion-cross"), 900.0, 720.0);
    h.run();
    h.get_by_label("wedges").click();
    h.run();
    h.get_by_label("NaN / range").click();
    h.run();
    let counted = step_until_gpu(&mut h, 100, |h| {
        h.state()
            .shown()
            .is_some_and(|s| s.method.name() == "wedges")
            && h.state().out_of_range_px(false).is_some()
    });
    assert!(counted, "the probe's count came back");
    let frame = h.state_mut().read_shown(false).expect("a frame");
    let gpu = h.state().out_of_range_px(false);
    println!("wedges on fusion-cross: {gpu:?} px out of range");
    assert_eq!(gpu, Some(frame.out_of_range_pixels() as u64));
}
