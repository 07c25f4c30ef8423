//! A temporal method in the lab: picked, `raytraced` keeps drawing while its history fills with
//! the view standing still — a new frame each step, no input — and stops once the history is
//! full; moving the light starts it again.

use dbuffer::app::LabApp;
use dbuffer::render::methods::raytraced::{self, HISTORY};
use dbuffer::render::Method;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;

use crate::support::{self as support_lab, step_until_gpu};

fn serial(h: &Harness<'_, LabApp>) -> u64 {
    h.state().shown().map_or(0, |s| s.serial)
}

#[test]
fn raytraced_draws_until_its_history_is_full_then_rests() {
    let rt = Method::of(&raytraced::RAYTRACED).expect("raytraced is on the registry");
    let mut h = support_lab::lab_sized(Some("fig7-concave"), 900.0, 700.0);
    h.run();
    h.get_by_label(rt.name()).click();
    assert!(
        step_until_gpu(&mut h, 20, |h| h
            .state()
            .shown()
            .is_some_and(|s| s.method == rt)),
        "raytraced was not shown"
    );
    let start = serial(&h);
    // No input from here on: every step that draws is the history filling.
    let history = u64::from(HISTORY.default);
    step_until_gpu(&mut h, 3 * history as usize, |_| false);
    let filled = serial(&h);
    assert!(
        filled - start >= history - 2,
        "only {} frames drawn standing still; the history spans {history}",
        filled - start
    );
    step_until_gpu(&mut h, 10, |_| false);
    assert_eq!(
        serial(&h),
        filled,
        "still drawing after the history is full"
    );
}
