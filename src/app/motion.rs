//! The motion meter: while the light or a caster is dragged, how much the shown method's V
//! changes from frame to frame *other than as the truth does* — the temporal error of `compare
//! --orbit` (docs/method/metrics.md), live, over the last seconds, drawn small in the viewport.
//!
//! Per new frame during a drag, the probe reads V at a [`MOTION_GRID`]² grid of pixels (2.3 KiB,
//! never the frame), and on this thread the reference is cast at the same pixels with
//! [`MOTION_SAMPLES`] light samples — a low K, whose pattern rides with the light (the oracle's
//! samples are fixed in the light's frame), so its own noise does not move while the light does.
//! The error of a step is the mean over the grid samples with a surface in both frames of
//! `|ΔV − ΔV_ref|`. Where casting that reference takes longer than [`REFERENCE_BUDGET_MS`] (a
//! large scene, a slow machine), the meter stops casting it and shows the method's own
//! frame-to-frame change, mean `|ΔV|`, labelled as such.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use eframe::egui::{self, Color32, Pos2, Rect, Vec2};

use crate::geometry::oracle::Oracle;
use crate::render::passes::probe::{grid_pixel, MOTION_GRID};
use crate::scene::Scene;

/// The reference's light samples per grid pixel.
pub const MOTION_SAMPLES: usize = 16;
/// The most this thread may spend on the reference for one frame; over it the meter shows the
/// method alone.
pub const REFERENCE_BUDGET_MS: f64 = 30.0;
/// How far back the plot reaches.
pub const WINDOW: Duration = Duration::from_secs(6);
/// How long the plot stays after the drag ends.
const LINGER: Duration = Duration::from_secs(3);

/// What the meter measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Measure {
    /// Mean `|ΔV − ΔV_ref|` against the low-K reference.
    AgainstReference,
    /// Mean `|ΔV|` of the method alone: the reference could not keep up.
    MethodAlone,
}

impl Measure {
    /// What the plot's foot says it measures.
    pub fn short(self) -> String {
        match self {
            Measure::AgainstReference => {
                format!("|ΔV − ΔV_ref|, reference K = {MOTION_SAMPLES} on {MOTION_GRID}² px")
            }
            Measure::MethodAlone => "the method alone: the reference cannot keep up".into(),
        }
    }
}

/// A frame whose V is on its way back: its tag and the reference at its grid (if cast).
struct Asked {
    tag: u64,
    reference: Option<Vec<f32>>,
}

#[derive(Default)]
pub struct MotionMeter {
    asked: VecDeque<Asked>,
    /// The last frame's V and reference at the grid.
    previous: Option<(Vec<f32>, Option<Vec<f32>>)>,
    /// (when, value, what it measured).
    samples: VecDeque<(Instant, f32, Measure)>,
    next_tag: u64,
    /// The reference took too long once: the method alone from then on (until the scene
    /// changes).
    alone: bool,
    last_active: Option<Instant>,
}

impl MotionMeter {
    /// A drag made a new frame of `scene` at `width`×`height`: cast the reference at the grid
    /// (unless it cannot keep up) and return the tag the probe for that frame carries.
    pub fn frame(&mut self, scene: &Scene, width: u32, height: u32) -> u64 {
        self.next_tag += 1;
        self.last_active = Some(Instant::now());
        let reference = (!self.alone).then(|| {
            let t = Instant::now();
            let v = reference_at_grid(scene, width, height);
            if t.elapsed().as_secs_f64() * 1e3 > REFERENCE_BUDGET_MS {
                self.alone = true;
            }
            v
        });
        // Frames whose answers never came (a probe skipped while one was in flight) are
        // forgotten.
        while self.asked.len() > 4 {
            self.asked.pop_front();
        }
        self.asked.push_back(Asked {
            tag: self.next_tag,
            reference,
        });
        self.next_tag
    }

    /// The probe's V for the frame tagged `tag`.
    pub fn arrived(&mut self, tag: u64, values: Vec<f32>) {
        let Some(k) = self.asked.iter().position(|a| a.tag == tag) else {
            return;
        };
        let asked = self.asked.remove(k).map(|a| a.reference);
        let reference = asked.flatten().filter(|_| !self.alone);
        if let Some((before, before_ref)) = &self.previous {
            let (mut sum, mut n) = (0.0f64, 0usize);
            let against = match (&reference, before_ref) {
                (Some(r), Some(rb)) => Some((r, rb)),
                _ => None,
            };
            for i in 0..values.len().min(before.len()) {
                let dm = values[i] - before[i];
                let e = match against {
                    Some((r, rb)) => dm - (r[i] - rb[i]),
                    None => dm,
                };
                if e.is_finite() {
                    sum += f64::from(e.abs());
                    n += 1;
                }
            }
            if n > 0 {
                let measure = if against.is_some() {
                    Measure::AgainstReference
                } else {
                    Measure::MethodAlone
                };
                self.samples
                    .push_back((Instant::now(), (sum / n as f64) as f32, measure));
            }
        }
        self.previous = Some((values, reference));
        let now = Instant::now();
        while self
            .samples
            .front()
            .is_some_and(|(t, _, _)| now.duration_since(*t) > WINDOW)
        {
            self.samples.pop_front();
        }
    }

    /// The drag ended: the next one starts a new series (the pose jumped meanwhile).
    pub fn drag_ended(&mut self) {
        self.previous = None;
        self.asked.clear();
    }

    /// Another scene: start again, casting the reference again.
    pub fn reset(&mut self) {
        *self = MotionMeter::default();
    }

    /// Whether to draw the plot: during a drag and shortly after.
    pub fn showing(&self) -> bool {
        self.last_active
            .is_some_and(|t| t.elapsed() < LINGER && !self.samples.is_empty())
    }

    /// The values over the last [`WINDOW`] and what the newest measured.
    pub fn series(&self) -> (Vec<f32>, Option<Measure>) {
        (
            self.samples.iter().map(|s| s.1).collect(),
            self.samples.back().map(|s| s.2),
        )
    }
}

/// V of the reference at the grid pixels of a `width`×`height` view (NaN where no surface), at
/// [`MOTION_SAMPLES`] samples.
fn reference_at_grid(scene: &Scene, width: u32, height: u32) -> Vec<f32> {
    use rayon::prelude::*;
    let oracle = Oracle::from_scene(scene, MOTION_SAMPLES);
    (0..MOTION_GRID * MOTION_GRID)
        .into_par_iter()
        .map(|i| {
            let (x, y) = grid_pixel(i, MOTION_GRID, width, height);
            let (origin, dir) = scene.camera.pixel_ray(x, y, width, height);
            match oracle.bvh().closest_hit(origin, dir, 0.0, f32::INFINITY) {
                Some(hit) => oracle.visibility(origin + dir * hit.t),
                None => f32::NAN,
            }
        })
        .collect()
}

impl super::LabApp {
    /// The motion meter's plot, top right of the viewport, while a drag moves the light or a
    /// caster (and shortly after).
    pub(super) fn draw_motion(&self, ui: &egui::Ui, rect: Rect) {
        if !self.motion.showing() {
            return;
        }
        let (values, measure) = self.motion.series();
        let Some(measure) = measure else { return };
        let size = Vec2::new(260.0f32.min(rect.width() - 16.0), 74.0);
        let area = Rect::from_min_size(
            Pos2::new(rect.right() - size.x - 8.0, rect.top() + 8.0),
            size,
        );
        if size.x < 120.0 {
            return;
        }
        let painter = ui.painter().with_clip_rect(area);
        painter.rect_filled(area, 4.0, Color32::from_black_alpha(170));
        let title = match measure {
            Measure::AgainstReference => "temporal error",
            Measure::MethodAlone => "frame-to-frame |ΔV|",
        };
        let top = values.iter().copied().fold(0.01f32, f32::max);
        painter.text(
            area.left_top() + Vec2::new(6.0, 3.0),
            egui::Align2::LEFT_TOP,
            format!(
                "{title}: {:.4} (max {top:.3})",
                values.last().copied().unwrap_or(0.0)
            ),
            egui::FontId::proportional(11.0),
            Color32::WHITE,
        );
        let plot = Rect::from_min_max(
            area.left_top() + Vec2::new(6.0, 18.0),
            area.right_bottom() - Vec2::new(6.0, 14.0),
        );
        if values.len() >= 2 {
            let n = values.len() - 1;
            let points: Vec<Pos2> = values
                .iter()
                .enumerate()
                .map(|(k, v)| {
                    Pos2::new(
                        plot.left() + plot.width() * k as f32 / n as f32,
                        plot.bottom() - plot.height() * (v / top).clamp(0.0, 1.0),
                    )
                })
                .collect();
            painter.add(egui::Shape::line(
                points,
                egui::Stroke::new(1.5, Color32::from_rgb(250, 170, 60)),
            ));
        }
        painter.text(
            area.left_bottom() + Vec2::new(6.0, -2.0),
            egui::Align2::LEFT_BOTTOM,
            format!("last {} s · {}", WINDOW.as_secs(), measure.short()),
            egui::FontId::proportional(9.0),
            Color32::GRAY,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_is_the_change_less_the_references() {
        let mut m = MotionMeter::default();
        let scene = crate::scene::load("fig7-concave").unwrap();
        let a = m.frame(&scene, 64, 64);
        let n = (MOTION_GRID * MOTION_GRID) as usize;
        m.arrived(a, vec![0.5; n]);
        assert!(m.series().0.is_empty(), "one frame is no step");
        let b = m.frame(&scene, 64, 64);
        // The same scene: the reference did not move, so the error is the method's change.
        m.arrived(b, vec![0.75; n]);
        let (values, measure) = m.series();
        assert_eq!(values.len(), 1);
        assert!((values[0] - 0.25).abs() < 1e-6, "{values:?}");
        assert!(measure.is_some());
        assert!(m.showing());
        // An answer for a frame it did not ask about is ignored.
        m.arrived(99, vec![0.0; n]);
        assert_eq!(m.series().0.len(), 1);
    }
}
