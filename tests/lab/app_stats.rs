//! The Stats panel lists the GPU passes of the method shown: switched from `dbuffer-fused` to
//! `dbuffer`, the fused method's own passes (timed a frame or more after their frame, so some
//! arrive after the switch) leave the list.

use dbuffer::app::LabApp;
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
