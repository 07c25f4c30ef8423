//! Rectangle and polygon lights in the lab: drawn as their shape, a polygon's vertex and a
//! rectangle's corner dragged as handles, the light converted in place between the four kinds,
//! and the light as seen from a pixel drawn as the polygon.

use dbuffer::app::{LabApp, Selection};
use dbuffer::render::Method;
use dbuffer::scene::{Light, LightKind, Outline};
use eframe::egui;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;

use crate::support::{self as support_lab, step_until_gpu};

fn lab(scene: &str) -> Harness<'static, LabApp> {
    support_lab::lab_sized(Some(scene), 900.0, 760.0)
}

fn light(h: &Harness<'_, LabApp>) -> Light {
    h.state().scene().expect("scene").light
}

fn click(h: &mut Harness<'_, LabApp>, label: &str) {
    h.get_by_label(label).click();
    h.run();
}

/// Drag from `from` by `by` pixels in steps, as a hand would.
fn drag(h: &mut Harness<'_, LabApp>, from: egui::Pos2, by: egui::Vec2) {
    h.drag_at(from);
    h.step();
    for k in 1..=4 {
        h.hover_at(from + by * (k as f32 / 5.0));
        h.step();
    }
    h.drop_at(from + by);
    h.run();
}

#[test]
fn a_polygon_light_is_drawn_as_itself_and_its_vertex_drags_alone() {
    let mut h = lab("polygon-triangle");
    h.run();
    assert_eq!(h.state().settings.method(), Method::DBUFFER);
    click(&mut h, "light");
    h.key_press(egui::Key::F);
    h.run();
    h.snapshot("app-polygon-light");
    let before = *light(&h).as_area().expect("a polygon");
    let corners = before.corners().expect("corners");
    let v0 = corners.vertices()[0];
    let at = h.state().screen_pos(v0).expect("vertex 0 in view");
    // Outward from the centroid, on screen.
    let centre = h.state().screen_pos(before.center).expect("centre in view");
    let out = (at - centre).normalized() * 25.0;
    drag(&mut h, at, out);
    assert_eq!(h.state().selection, Selection::LightEnd(0));
    let after = *light(&h).as_area().expect("still a polygon");
    let moved = after.corners().expect("corners");
    assert!(
        (moved.vertices()[0] - v0).length() > 0.05,
        "vertex 0 {} → {}",
        v0,
        moved.vertices()[0]
    );
    assert_eq!(
        moved.vertices()[1..],
        corners.vertices()[1..],
        "the others stay"
    );
    // In the polygon's plane: the normal is the same.
    assert!(after.normal.dot(before.normal) > 0.9999);
}

#[test]
fn a_rect_corner_resizes_it_about_its_centre() {
    let mut h = lab("rect-strip");
    h.run();
    click(&mut h, "light");
    h.key_press(egui::Key::F);
    h.run();
    let before = *light(&h).as_area().expect("a rectangle");
    let Outline::Rect { size, .. } = before.outline else {
        panic!("{:?}", before.outline)
    };
    let corner = before.corners().expect("corners").vertices()[2];
    let at = h.state().screen_pos(corner).expect("corner in view");
    let centre = h.state().screen_pos(before.center).expect("centre in view");
    // Inward: framed, the 3 m strip spans the viewport, and its corners lie near its edges.
    drag(&mut h, at, (centre - at).normalized() * 30.0);
    assert_eq!(
        h.state().selection,
        Selection::LightEnd(2),
        "the corner was picked"
    );
    let after = *light(&h).as_area().expect("still a rectangle");
    let Outline::Rect { size: resized, .. } = after.outline else {
        panic!("{:?}", after.outline)
    };
    assert!(
        resized[0] < size[0] * 0.98 || resized[1] < size[1] * 0.98,
        "{size:?} → {resized:?}"
    );
    assert!(
        (after.center - before.center).length() < 1e-4,
        "the centre stays"
    );
}

#[test]
fn the_light_converts_in_place_between_every_kind() {
    let mut h = lab("rect-fig7");
    h.run();
    click(&mut h, "light");
    let centre = light(&h).center();
    for kind in [
        LightKind::Polygon,
        LightKind::Disk,
        LightKind::Line,
        LightKind::Rect,
        LightKind::Polygon,
    ] {
        click(&mut h, kind.name());
        let l = light(&h);
        assert_eq!(l.kind(), kind);
        assert!(
            (l.center() - centre).length() < 1e-2,
            "{kind}: {} moved from {centre}",
            l.center()
        );
        // The method shown takes the light (a line gets the one made for it).
        assert!(h.state().settings.method().takes(kind), "{kind}");
    }
}

#[test]
fn the_light_as_seen_from_a_pixel_is_the_polygon() {
    let mut h = lab("rect-fusion");
    h.run();
    click(&mut h, Method::DBUFFER_FUSED.name());
    let frame = h.state_mut().read_shown(false).expect("the frame");
    let (w, hgt) = (frame.width, frame.height);
    let i = (0..frame.visibility.len())
        .step_by(5)
        .find(|&i| frame.hit(i) && (0.3..0.7).contains(&frame.visibility[i]))
        .expect("a penumbra pixel");
    let x = frame.position(i).expect("a surface");
    let rect = h.state().viewport_rect().expect("viewport");
    let (px, py) = ((i as u32 % w) as f32, (i as u32 / w) as f32);
    h.hover_at(egui::pos2(
        rect.left() + (px + 0.5) / w as f32 * rect.width(),
        rect.top() + (py + 0.5) / hgt as f32 * rect.height(),
    ));
    step_until_gpu(&mut h, 200, |h| {
        h.state().pixel_light().is_some_and(|l| l.position == x)
    });
    h.run();
    let panel = h.state().pixel_light().expect("the panel").clone();
    assert_eq!(panel.corners.len(), 4, "the rectangle's corners");
    // The reference's rays land inside the rectangle (its corners bound them).
    let (lo, hi) = panel
        .corners
        .iter()
        .fold((glam::Vec2::MAX, glam::Vec2::MIN), |(lo, hi), c| {
            (lo.min(*c), hi.max(*c))
        });
    assert!(panel
        .reference
        .iter()
        .all(|s| s.at.cmpge(lo - 1e-3).all() && s.at.cmple(hi + 1e-3).all()));
    // In a penumbra some rays are blocked and some free, and dbuffer-fused lists its chords.
    let blocked = panel.blocked_fraction();
    assert!(blocked > 0.05 && blocked < 0.95, "{blocked}");
    assert!(
        panel.fused.as_ref().is_some_and(|f| !f.chords.is_empty()),
        "the cut chords"
    );
}
