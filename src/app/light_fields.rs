//! The light's fields in the scene panel: its kind (converting the light in place), and per kind
//! what places and shapes it — a disk's centre, radius and normal; a rectangle's centre, width,
//! height, normal and spin about the normal; a polygon's vertices, size, normal and spin; a
//! segment's end points. Every change is one undoable edit of the scene file.

use eframe::egui::{self, RichText, Slider};
use glam::{DQuat, DVec3};

use super::doc::{normal_from, tilt_azimuth};
use super::{LabApp, Level};
use crate::scene::file::LightSpec;
use crate::scene::{LightKind, MAX_POLYGON_VERTICES};

fn number_row(ui: &mut egui::Ui, label: &str, values: &mut [f64], speed: f64) -> bool {
    super::panels::number_row(ui, label, values, speed)
}

/// The points of a rectangle or polygon spec (its corners), for the transforms below.
fn corners_of(light: &LightSpec) -> Vec<DVec3> {
    match light.kind() {
        LightKind::Polygon => light
            .vertices
            .iter()
            .flatten()
            .map(|v| DVec3::from(*v))
            .collect(),
        _ => Vec::new(),
    }
}

/// Tilt and azimuth of the normal, and a spin about it; a rotation of the light follows.
fn orientation_rows(ui: &mut egui::Ui, normal: [f64; 3], spin: Option<&mut f64>) -> Option<DQuat> {
    let (mut tilt, mut azimuth) = tilt_azimuth(normal);
    let t = ui.add(Slider::new(&mut tilt, 0.0..=80.0).text("Tilt °"));
    let a = ui.add(Slider::new(&mut azimuth, -180.0..=180.0).text("Azimuth °"));
    let mut rotation = None;
    if t.changed() || a.changed() {
        let from = DVec3::from(normal).try_normalize().unwrap_or(DVec3::NEG_Y);
        let to = DVec3::from(normal_from(tilt, azimuth));
        rotation = Some(DQuat::from_rotation_arc(from, to));
    }
    if let Some(spin) = spin {
        let before = *spin;
        if ui
            .add(Slider::new(spin, -180.0..=180.0).text("Spin °"))
            .on_hover_text("rotate the light about its normal")
            .changed()
        {
            let n = DVec3::from(normal).try_normalize().unwrap_or(DVec3::NEG_Y);
            let spun = DQuat::from_axis_angle(n, (*spin - before).to_radians());
            rotation = Some(rotation.map_or(spun, |r| r * spun));
        }
    }
    rotation
}

/// The angle of a rectangle's tangent about its normal, from the default tangent.
fn spin_of(normal: DVec3, tangent: DVec3) -> f64 {
    let n = normal.as_vec3();
    let base = crate::scene::rect_tangent(n, None).as_dvec3();
    let b = normal.cross(base);
    tangent.dot(b).atan2(tangent.dot(base)).to_degrees()
}

impl LabApp {
    pub(super) fn light_fields(&mut self, ui: &mut egui::Ui) {
        let mut light = self.doc.file.light.clone();
        let mut kind = light.kind();
        ui.horizontal(|ui| {
            ui.label("Kind");
            for (k, hint) in [
                (LightKind::Disk, "a one-sided disk (the D-buffer's light)"),
                (
                    LightKind::Rect,
                    "a one-sided rectangle (the rect lights engines ship)",
                ),
                (
                    LightKind::Polygon,
                    "a one-sided convex polygon of 3 to 16 vertices",
                ),
                (
                    LightKind::Line,
                    "a linear light: a segment from a to b, emitting all around",
                ),
            ] {
                ui.selectable_value(&mut kind, k, k.name())
                    .on_hover_text(hint);
            }
        });
        let mut changed = false;
        let kind_changed = kind != light.kind();
        if kind_changed {
            light = light.converted(kind);
            changed = true;
        }
        match kind {
            LightKind::Disk => changed |= disk_fields(ui, &mut light),
            LightKind::Rect => changed |= rect_fields(ui, &mut light),
            LightKind::Polygon => changed |= polygon_fields(ui, &mut light),
            LightKind::Line => changed |= line_fields(ui, &mut light),
        }
        if changed && self.doc.file.light != light {
            self.edit_scene(|e| e.light = light);
        }
        if kind_changed {
            if let Some(switched) = self.suit_methods_to_the_light() {
                self.set_status(switched, Level::Info);
            }
        }
    }
}

fn height_row(ui: &mut egui::Ui, center: &mut [f64; 3]) -> bool {
    ui.add(Slider::new(&mut center[1], -5.0..=20.0).text("Height"))
        .changed()
}

fn disk_fields(ui: &mut egui::Ui, light: &mut LightSpec) -> bool {
    let mut changed = false;
    let mut center = light.center.unwrap_or([0.0, 4.0, 0.0]);
    let mut radius = light.radius.unwrap_or(0.5);
    changed |= number_row(ui, "Centre", &mut center, 0.01);
    changed |= ui
        .add(
            Slider::new(&mut radius, 0.01..=5.0)
                .text("Radius")
                .logarithmic(true),
        )
        .changed();
    changed |= height_row(ui, &mut center);
    let normal = light.normal.unwrap_or([0.0, -1.0, 0.0]);
    if let Some(r) = orientation_rows(ui, normal, None) {
        light.normal = Some((r * DVec3::from(normal)).to_array());
        changed = true;
    }
    light.center = Some(center);
    light.radius = Some(radius);
    changed
}

fn rect_fields(ui: &mut egui::Ui, light: &mut LightSpec) -> bool {
    let mut changed = false;
    let mut center = light.center.unwrap_or([0.0, 4.0, 0.0]);
    let mut size = light.size.unwrap_or([1.0, 1.0]);
    changed |= number_row(ui, "Centre", &mut center, 0.01);
    for (i, label) in [(0, "Width"), (1, "Depth")] {
        changed |= ui
            .add(
                Slider::new(&mut size[i], 0.01..=10.0)
                    .text(label)
                    .logarithmic(true),
            )
            .changed();
    }
    changed |= height_row(ui, &mut center);
    let normal = DVec3::from(light.normal.unwrap_or([0.0, -1.0, 0.0]));
    // The tangent as the light has it (projected, or the default).
    let tangent = light
        .light()
        .as_area()
        .map_or(DVec3::X, |a| a.basis().0.as_dvec3());
    let mut spin = spin_of(normal, tangent);
    if let Some(r) = orientation_rows(ui, normal.to_array(), Some(&mut spin)) {
        light.normal = Some((r * normal).to_array());
        light.tangent = Some((r * tangent).to_array());
        changed = true;
    }
    light.center = Some(center);
    light.size = Some(size);
    ui.label(RichText::new("drag the rectangle or its corner handles in the viewport").small());
    changed
}

fn polygon_fields(ui: &mut egui::Ui, light: &mut LightSpec) -> bool {
    let mut points = corners_of(light);
    if points.len() < 3 {
        return false;
    }
    let mut changed = false;
    let area = light.light().as_area().copied();
    let centroid = area.map_or(DVec3::ZERO, |a| a.center.as_dvec3());
    let normal = area.map_or(DVec3::NEG_Y, |a| a.normal.as_dvec3());
    let mut center = centroid.to_array();
    if number_row(ui, "Centroid", &mut center, 0.01) | height_row(ui, &mut center) {
        let shift = DVec3::from(center) - centroid;
        points.iter_mut().for_each(|p| *p += shift);
        changed = true;
    }
    let reach = points
        .iter()
        .map(|p| p.distance(centroid))
        .fold(0.0, f64::max);
    let mut size = reach;
    if ui
        .add(
            Slider::new(&mut size, 0.01..=5.0)
                .text("Size")
                .logarithmic(true),
        )
        .on_hover_text("its farthest vertex from the centroid: scales it about the centroid")
        .changed()
        && reach > 0.0
    {
        let scale = size / reach;
        points
            .iter_mut()
            .for_each(|p| *p = centroid + (*p - centroid) * scale);
        changed = true;
    }
    // The spin is the first vertex's angle about the centroid, in the light's basis.
    let (u, w) = area.map_or((DVec3::X, DVec3::Z), |a| {
        let (u, w) = a.basis();
        (u.as_dvec3(), w.as_dvec3())
    });
    let first = points[0] - centroid;
    let mut spin = first.dot(w).atan2(first.dot(u)).to_degrees();
    if let Some(r) = orientation_rows(ui, normal.to_array(), Some(&mut spin)) {
        points
            .iter_mut()
            .for_each(|p| *p = centroid + r * (*p - centroid));
        changed = true;
    }
    let mut sides = points.len();
    if ui
        .add(Slider::new(&mut sides, 3..=MAX_POLYGON_VERTICES).text("Sides"))
        .on_hover_text("make it a regular polygon of this many sides, as wide as it is now")
        .changed()
    {
        if let Some(a) = area {
            let regular = a.inscribed_polygon(sides);
            if let Some(p) = regular.corners() {
                points = p.vertices().iter().map(|v| v.as_dvec3()).collect();
                changed = true;
            }
        }
    }
    egui::CollapsingHeader::new(format!("{} vertices", points.len()))
        .id_salt("polygon-vertices")
        .show(ui, |ui| {
            for (i, p) in points.iter_mut().enumerate() {
                let mut v = p.to_array();
                if number_row(ui, &format!("v{i}"), &mut v, 0.01) {
                    *p = DVec3::from(v);
                    changed = true;
                }
            }
        });
    ui.label(
        RichText::new(
            "counter-clockwise seen from below the light; drag a vertex handle in the viewport",
        )
        .small(),
    );
    if changed {
        let candidate: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
        // An edit that would make it concave or degenerate is not taken.
        if crate::scene::check_polygon(&points).is_none() {
            light.vertices = Some(candidate);
        } else {
            changed = false;
        }
    }
    changed
}

fn line_fields(ui: &mut egui::Ui, light: &mut LightSpec) -> bool {
    let mut changed = false;
    let mut a = light.a.unwrap_or([-1.0, 4.0, 0.0]);
    let mut b = light.b.unwrap_or([1.0, 4.0, 0.0]);
    changed |= number_row(ui, "End a", &mut a, 0.01);
    changed |= number_row(ui, "End b", &mut b, 0.01);
    let mut height = 0.5 * (a[1] + b[1]);
    if ui
        .add(Slider::new(&mut height, -5.0..=20.0).text("Height"))
        .changed()
    {
        let dy = height - 0.5 * (a[1] + b[1]);
        a[1] += dy;
        b[1] += dy;
        changed = true;
    }
    let length = (0..3).map(|i| (b[i] - a[i]).powi(2)).sum::<f64>().sqrt();
    ui.label(
        RichText::new(format!(
            "length {length:.3} m; drag an end (a, b) or the segment in the viewport"
        ))
        .small(),
    );
    light.a = Some(a);
    light.b = Some(b);
    changed
}
