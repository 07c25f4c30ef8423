//! What a scene's cells say: the points of error against cost, the front of the cells no other
//! beats on both, and the two tables — the least error at 1×, 2× and 4× the D-buffer's frame,
//! and the cheapest cell within 2×, 5× and 10× the reference's noise floor.

use serde::{Deserialize, Serialize};

use super::run::{Cell, SceneStudy};
use crate::render::Method;

/// Which error a plot and its tables rank by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ErrorAxis {
    PenumbraMae,
    Flip,
}

impl ErrorAxis {
    pub fn of(self, cell: &Cell) -> Option<f64> {
        let e = cell.error?;
        Some(match self {
            ErrorAxis::PenumbraMae => e.penumbra_mae,
            ErrorAxis::Flip => e.flip,
        })
    }

    pub fn label(self) -> &'static str {
        match self {
            ErrorAxis::PenumbraMae => "penumbra MAE",
            ErrorAxis::Flip => "FLIP (mean)",
        }
    }
}

/// A measured cell on the plane: its index in the scene's cells, its cost (frame ms) and error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    pub cell: usize,
    pub cost: f64,
    pub error: f64,
}

/// The scene's measured cells as points, in the cells' order (registry, then setting).
pub fn points(scene: &SceneStudy, axis: ErrorAxis) -> Vec<Point> {
    scene
        .cells
        .iter()
        .enumerate()
        .filter_map(|(i, c)| {
            let cost = c.cost.as_ref()?.frame_ms;
            let error = axis.of(c)?;
            (cost.is_finite() && cost > 0.0 && error.is_finite()).then_some(Point {
                cell: i,
                cost,
                error,
            })
        })
        .collect()
}

/// The points no other point beats on both axes (at most its cost and at most its error, one of
/// them less), cheapest first: the front.
pub fn front(points: &[Point]) -> Vec<Point> {
    let mut sorted: Vec<Point> = points.to_vec();
    sorted.sort_by(|a, b| a.cost.total_cmp(&b.cost).then(a.error.total_cmp(&b.error)));
    let mut out: Vec<Point> = Vec::new();
    for p in sorted {
        if out.last().is_none_or(|last| p.error < last.error) {
            out.push(p);
        }
    }
    out
}

/// The D-buffer's frame on the scene: the paper's method at the study's map size (else at any
/// size it was measured at, the cheapest), the cost the equal-cost table is stated against.
pub fn dbuffer_frame(scene: &SceneStudy, map_size: u32) -> Option<f64> {
    let dbuffer = scene
        .cells
        .iter()
        .filter(|c| c.method == Method::DBUFFER.name())
        .filter_map(|c| Some((c.map_size, c.cost.as_ref()?.frame_ms)));
    let all: Vec<(u32, f64)> = dbuffer.collect();
    all.iter()
        .find(|(m, _)| *m == map_size)
        .or_else(|| all.iter().min_by(|a, b| a.1.total_cmp(&b.1)))
        .map(|&(_, ms)| ms)
}

/// One row of the equal-cost table: within `budget_ms` (`times` the D-buffer's frame), the cell
/// of least error, if any is that cheap.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AtCost {
    pub times: f64,
    pub budget_ms: f64,
    pub best: Option<usize>,
}

/// One row of the equal-error table: the cheapest cell whose error is at most `target` (`times`
/// the noise floor), if any reaches it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AtError {
    pub times: f64,
    pub target: f64,
    pub cheapest: Option<usize>,
}

/// The equal-cost rows at 1×, 2× and 4× the D-buffer's frame.
pub fn equal_cost(points: &[Point], dbuffer_ms: f64) -> Vec<AtCost> {
    [1.0, 2.0, 4.0]
        .into_iter()
        .map(|times| {
            let budget_ms = times * dbuffer_ms;
            let best = points
                .iter()
                .filter(|p| p.cost <= budget_ms)
                .min_by(|a, b| a.error.total_cmp(&b.error).then(a.cost.total_cmp(&b.cost)))
                .map(|p| p.cell);
            AtCost {
                times,
                budget_ms,
                best,
            }
        })
        .collect()
}

/// The equal-error rows at 2×, 5× and 10× the noise floor (a floor of 0, as from a reference at
/// the budget's K, is taken as 0.001: the reference's own error against analytic cases).
pub fn equal_error(points: &[Point], noise_floor: f64) -> Vec<AtError> {
    let floor = if noise_floor > 0.0 { noise_floor } else { 1e-3 };
    [2.0, 5.0, 10.0]
        .into_iter()
        .map(|times| {
            let target = times * floor;
            let cheapest = points
                .iter()
                .filter(|p| p.error <= target)
                .min_by(|a, b| a.cost.total_cmp(&b.cost).then(a.error.total_cmp(&b.error)))
                .map(|p| p.cell);
            AtError {
                times,
                target,
                cheapest,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(cell: usize, cost: f64, error: f64) -> Point {
        Point { cell, cost, error }
    }

    #[test]
    fn the_front_keeps_what_nothing_beats() {
        let pts = [
            p(0, 10.0, 0.05),
            p(1, 20.0, 0.01),
            p(2, 15.0, 0.06),
            p(3, 5.0, 0.2),
            p(4, 40.0, 0.01),
            p(5, 30.0, 0.002),
        ];
        let f: Vec<usize> = front(&pts).iter().map(|p| p.cell).collect();
        assert_eq!(f, vec![3, 0, 1, 5]);
    }

    #[test]
    fn tables_pick_the_least_error_within_a_cost_and_the_cheapest_within_an_error() {
        let pts = [p(0, 10.0, 0.05), p(1, 20.0, 0.01), p(2, 45.0, 0.003)];
        let c = equal_cost(&pts, 10.0);
        assert_eq!(
            c.iter().map(|r| r.best).collect::<Vec<_>>(),
            vec![Some(0), Some(1), Some(1)]
        );
        let e = equal_error(&pts, 0.001);
        assert_eq!(
            e.iter().map(|r| r.cheapest).collect::<Vec<_>>(),
            vec![None, Some(2), Some(1)]
        );
    }
}
