//! The view pass's CPU twin: the same views drawn from a frame read back into a [`Frame`]. The
//! GPU pass ([`super::view`]) is what the lab shows; this twin is what `tests/gpu/view_pass.rs` holds
//! it to, and what a picture of a read-back frame is drawn with.

use super::view::{ColorMap, Mapping, View, ViewParams};
use crate::render::frame_data::Frame;

/// Background of pixels that hit no surface, and of map texels with no data.
pub const NO_DATA: [u8; 4] = [20, 24, 48, 255];

/// Colours of the classes view, by [`crate::geometry::Branch::code`].
pub const BRANCH_COLORS: [([u8; 4], &str); 4] = [
    ([40, 60, 160, 255], "umbra"),
    ([230, 120, 40, 255], "penumbra, hidden from centre"),
    ([250, 200, 90, 255], "penumbra, visible from centre"),
    ([200, 196, 186, 255], "lit"),
];

/// The range view's mark (`RANGE_MARK` of `shaders/passes/view.wgsl`): magenta.
pub const RANGE_MARK: [u8; 4] = [255, 0, 255, 255];

/// The range view's dimmed grey of an image pixel's sRGB bytes: 0.4 × the mean of its channels.
pub fn range_grey(c: [u8; 4]) -> [u8; 4] {
    let mean = (f32::from(c[0]) + f32::from(c[1]) + f32::from(c[2])) / 255.0;
    let g = mean * (0.4 / 3.0);
    rgb(g, g, g)
}

pub fn branch_name(code: u8) -> &'static str {
    BRANCH_COLORS
        .get(usize::from(code))
        .map_or("?", |(_, name)| *name)
}

fn rgb(r: f32, g: f32, b: f32) -> [u8; 4] {
    let c = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    [c(r), c(g), c(b), 255]
}

impl ColorMap {
    /// The colour of `x` in 0..1 (clamped; NaN as 0).
    pub fn color(self, x: f32) -> [u8; 4] {
        let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        match self {
            ColorMap::Gray => rgb(x, x, x),
            ColorMap::Heat => rgb(x * 3.0, x * 3.0 - 1.0, x * 3.0 - 2.0),
            ColorMap::Turbo => {
                // Polynomial fit of Google's Turbo (Mikhailov 2019), its coefficients as
                // published (the GPU evaluates them in f32: one level apart at most).
                let x = f64::from(x);
                let poly = |c: [f64; 6]| c.iter().rev().fold(0.0, |acc, k| acc * x + k) as f32;
                rgb(
                    poly([
                        0.13572138,
                        4.6153926,
                        -42.66032258,
                        132.13108234,
                        -152.94239396,
                        59.28637943,
                    ]),
                    poly([
                        0.09140261,
                        2.19418839,
                        4.84296658,
                        -14.18503333,
                        4.27729857,
                        2.82956604,
                    ]),
                    poly([
                        0.1066733,
                        12.64194608,
                        -60.58204836,
                        110.36276771,
                        -89.90310912,
                        27.34824973,
                    ]),
                )
            }
        }
    }
}

impl Mapping {
    /// 0..1 for a value between black and white.
    pub fn normalise(&self, v: f32) -> f32 {
        let span = self.white - self.black;
        if span.abs() < f32::EPSILON {
            if v >= self.white {
                1.0
            } else {
                0.0
            }
        } else {
            (v - self.black) / span
        }
    }

    pub fn color(&self, v: f32) -> [u8; 4] {
        self.map.color(self.normalise(v))
    }
}

/// The shown scalar of pixel `i` for the fit and the scalar views; `None` where there is none.
pub fn scalar(frame: &Frame, reference: Option<&[f32]>, view: View, i: usize) -> Option<f32> {
    if !frame.hit(i) {
        return None;
    }
    match view {
        View::Visibility => frame.visibility.get(i).copied(),
        View::T => (i < frame.len()).then(|| frame.t(i)),
        View::Error => Some((frame.visibility.get(i)? - reference?.get(i)?).abs()),
        View::Cost => frame.cost.get(i).map(|c| c[0]),
        View::Flip => reference?.get(i).copied(),
        _ => None,
    }
}

/// The view's pixels (gamma-encoded RGBA bytes, row-major) and their size, as the view pass
/// draws them. `reference`: V of the same size, if there is one.
pub fn render(
    frame: &Frame,
    reference: Option<&[f32]>,
    params: &ViewParams,
) -> (u32, u32, Vec<[u8; 4]>) {
    let m = &params.mapping;
    let n = (frame.width * frame.height) as usize;
    let reference = reference.filter(|r| r.len() == n);
    let camera =
        |f: &dyn Fn(usize) -> [u8; 4]| (frame.width, frame.height, (0..n).map(f).collect());
    let color = |i: usize| {
        let c = frame.color.get(i).copied().unwrap_or_default();
        [c[0], c[1], c[2], 255]
    };
    match params.view {
        View::Final => camera(&color),
        View::Range => camera(&|i| {
            if frame.out_of_range(i) {
                RANGE_MARK
            } else {
                range_grey(color(i))
            }
        }),
        View::Visibility | View::T | View::Cost => {
            camera(&|i| scalar(frame, reference, params.view, i).map_or(NO_DATA, |v| m.color(v)))
        }
        View::Error | View::Flip => camera(&|i| match (frame.hit(i), reference) {
            (false, _) => NO_DATA,
            (true, None) => color(i),
            (true, Some(_)) => {
                scalar(frame, reference, params.view, i).map_or(NO_DATA, |v| m.color(v))
            }
        }),
        View::Classes => camera(&|i| {
            if frame.hit(i) {
                let b = frame.branch(i);
                BRANCH_COLORS.get(usize::from(b)).map_or(NO_DATA, |c| c.0)
            } else {
                NO_DATA
            }
        }),
        View::DBuffer => match &frame.maps {
            None => camera(&color),
            Some(maps) => {
                let size = maps.size;
                let count = maps.channels.len().min(4);
                let shown: Vec<usize> = (0..count).filter(|&c| params.channels[c]).collect();
                let texel = |i: u32| -> [u8; 4] {
                    let (x, y) = (i % size, i / size);
                    match shown.as_slice() {
                        [] => NO_DATA,
                        [c] => maps.channel(*c, x, y).map_or(NO_DATA, |v| m.color(v)),
                        several => {
                            let mut out = [0.0f32; 3];
                            let mut any = false;
                            for &c in several.iter().filter(|&&c| c < 3) {
                                if let Some(v) = maps.channel(c, x, y) {
                                    out[c] = m.normalise(v).clamp(0.0, 1.0);
                                    any = true;
                                }
                            }
                            if any {
                                rgb(out[0], out[1], out[2])
                            } else {
                                NO_DATA
                            }
                        }
                    }
                };
                (size, size, (0..size * size).map(texel).collect())
            }
        },
    }
}

/// The values the GPU's auto-fit samples (`probe.wgsl`'s `fit_value`), for the same grid.
pub fn fit_samples(
    frame: &Frame,
    reference: Option<&[f32]>,
    params: &ViewParams,
    grid: u32,
) -> Vec<f32> {
    (0..grid * grid)
        .map(|i| {
            let (gx, gy) = (i % grid, i / grid);
            let at = |n: u32, g: u32| (((g as f32 + 0.5) / grid as f32) * n as f32) as u32;
            if params.view == View::DBuffer {
                let Some(maps) = &frame.maps else {
                    return f32::NAN;
                };
                let count = maps.channels.len().min(4);
                let shown: Vec<usize> = (0..count).filter(|&c| params.channels[c]).collect();
                if shown.is_empty() {
                    return f32::NAN;
                }
                let c = shown[i as usize % shown.len()];
                return maps
                    .channel(c, at(maps.size, gx), at(maps.size, gy))
                    .unwrap_or(f32::NAN);
            }
            let p = (at(frame.height, gy) * frame.width + at(frame.width, gx)) as usize;
            scalar(frame, reference, params.view, p).unwrap_or(f32::NAN)
        })
        .collect()
}
