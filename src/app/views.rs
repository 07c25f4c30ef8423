//! What the viewport shows of a rendered [`Frame`]: the final image, V, t, the classes, the error
//! against the reference, or the D-buffer's channels, each turned into colours by a display
//! [`Mapping`] (black/white range, colour map). Plain functions from read-back arrays to pixels:
//! the pixel inspector reads the same arrays, so what it reports never depends on the mapping.

use eframe::egui::{Color32, ColorImage};
use serde::{Deserialize, Serialize};

use crate::render::light_pass::NO_SURFACE;
use crate::render::Frame;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum View {
    /// The shaded image.
    Final,
    /// V per pixel.
    Visibility,
    /// t per pixel.
    T,
    /// The branch each pixel fell on: lit, penumbra (visible / hidden from the centre), umbra.
    Classes,
    /// |ΔV| against the reference.
    Error,
    /// The D-buffer seen from the light centre, channels isolated or combined.
    DBuffer,
}

impl View {
    pub const ALL: [View; 6] = [
        View::Final,
        View::Visibility,
        View::T,
        View::Classes,
        View::Error,
        View::DBuffer,
    ];

    pub fn name(self) -> &'static str {
        match self {
            View::Final => "final",
            View::Visibility => "V",
            View::T => "t",
            View::Classes => "classes",
            View::Error => "error",
            View::DBuffer => "D-buffer",
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            View::Final => "the shaded image",
            View::Visibility => "V, the visible fraction of the disk, per pixel",
            View::T => "t, the visibility parameter before V(t)",
            View::Classes => "lit / penumbra (visible or hidden from the centre) / umbra",
            View::Error => "|V − V_reference| against the reference at its current sample count",
            View::DBuffer => "the D-buffer from the light centre, one channel or several",
        }
    }
}

/// The D-buffer channels, in `dbuffer.exr` order (R, G, B, A).
pub const CHANNELS: [&str; 4] = ["|cx_o|", "|cx_uv|", "|cx_pv|", "|cx_s|"];

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ColorMap {
    Gray,
    Heat,
    Turbo,
}

impl ColorMap {
    pub const ALL: [ColorMap; 3] = [ColorMap::Gray, ColorMap::Heat, ColorMap::Turbo];

    pub fn name(self) -> &'static str {
        match self {
            ColorMap::Gray => "gray",
            ColorMap::Heat => "heat",
            ColorMap::Turbo => "turbo",
        }
    }

    /// The colour of `x` in 0..1 (clamped).
    pub fn color(self, x: f32) -> Color32 {
        let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        match self {
            ColorMap::Gray => {
                let g = (x * 255.0).round() as u8;
                Color32::from_rgb(g, g, g)
            }
            ColorMap::Heat => {
                // black → red → yellow → white
                let r = (x * 3.0).min(1.0);
                let g = (x * 3.0 - 1.0).clamp(0.0, 1.0);
                let b = (x * 3.0 - 2.0).clamp(0.0, 1.0);
                rgb(r, g, b)
            }
            ColorMap::Turbo => {
                // Polynomial fit of Google's Turbo (Mikhailov 2019), in f64 like its source.
                let x = f64::from(x);
                let poly = |c: [f64; 6]| c.iter().rev().fold(0.0, |acc, k| acc * x + k) as f32;
                let r = poly([
                    0.13572138,
                    4.6153926,
                    -42.66032258,
                    132.13108234,
                    -152.94239396,
                    59.28637943,
                ]);
                let g = poly([
                    0.09140261,
                    2.19418839,
                    4.84296658,
                    -14.18503333,
                    4.27729857,
                    2.82956604,
                ]);
                let b = poly([
                    0.1066733,
                    12.64194608,
                    -60.58204836,
                    110.36276771,
                    -89.90310912,
                    27.34824973,
                ]);
                rgb(r, g, b)
            }
        }
    }
}

fn rgb(r: f32, g: f32, b: f32) -> Color32 {
    let c = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    Color32::from_rgb(c(r), c(g), c(b))
}

/// Black and white points and a colour map; `auto` refits the range to every new image.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mapping {
    pub black: f32,
    pub white: f32,
    pub map: ColorMap,
    pub auto: bool,
}

impl Mapping {
    pub fn unit() -> Self {
        Self {
            black: 0.0,
            white: 1.0,
            map: ColorMap::Gray,
            auto: false,
        }
    }

    pub fn error() -> Self {
        Self {
            black: 0.0,
            white: 0.25,
            map: ColorMap::Heat,
            auto: false,
        }
    }

    pub fn auto() -> Self {
        Self {
            black: 0.0,
            white: 1.0,
            map: ColorMap::Turbo,
            auto: true,
        }
    }

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

    pub fn color(&self, v: f32) -> Color32 {
        self.map.color(self.normalise(v))
    }

    /// Fit black and white to `values`, from the 0.5th to the 99.5th percentile (extruded volume
    /// ends reach hundreds of metres and would squash everything else into one colour); leaves
    /// the range alone when there are no finite values.
    pub fn fit(&mut self, values: impl Iterator<Item = f32>) {
        let mut v: Vec<f32> = values.filter(|v| v.is_finite()).collect();
        if v.is_empty() {
            return;
        }
        let last = v.len() - 1;
        let lo_i = (last as f32 * 0.005).floor() as usize;
        let hi_i = ((last as f32 * 0.995).ceil() as usize).min(last);
        let (_, hi, _) = v.select_nth_unstable_by(hi_i, f32::total_cmp);
        let hi = *hi;
        let (_, lo, _) = v.select_nth_unstable_by(lo_i, f32::total_cmp);
        self.black = *lo;
        self.white = hi;
    }
}

/// Background of pixels that hit no surface, and of D-buffer texels with no data.
pub const NO_DATA: Color32 = Color32::from_rgb(20, 24, 48);

/// Colours of the classes view, by [`crate::geometry::Branch::code`].
pub const BRANCH_COLORS: [(Color32, &str); 4] = [
    (Color32::from_rgb(40, 60, 160), "umbra"),
    (
        Color32::from_rgb(230, 120, 40),
        "penumbra, hidden from centre",
    ),
    (
        Color32::from_rgb(250, 200, 90),
        "penumbra, visible from centre",
    ),
    (Color32::from_rgb(200, 196, 186), "lit"),
];

pub fn branch_name(code: u8) -> &'static str {
    BRANCH_COLORS
        .get(usize::from(code))
        .map_or("?", |(_, name)| *name)
}

/// Whether pixel `i` of the frame hit a surface.
pub fn hit(frame: &Frame, i: usize) -> bool {
    frame.position.get(i).is_some_and(|p| p[3] > 0.5)
}

/// One D-buffer texel: `|cx_o|` (`None` where no surface), `|cx_uv|`, `|cx_pv|` (`None` where no
/// volume), and `|cx_s|` of the umbra and of the penumbra.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Texel {
    pub o: Option<f32>,
    pub uv: Option<f32>,
    pub pv: Option<f32>,
    pub s_umbra: Option<f32>,
    pub s_penumbra: Option<f32>,
}

impl Texel {
    /// The value of channel `c` of [`CHANNELS`]; `|cx_s|` is the umbra's where it has one.
    pub fn channel(&self, c: usize) -> Option<f32> {
        match c {
            0 => self.o,
            1 => self.uv,
            2 => self.pv,
            _ => self.s_umbra.or(self.s_penumbra),
        }
    }
}

pub fn texel(frame: &Frame, x: u32, y: u32) -> Option<Texel> {
    let n = frame.dbuffer_size;
    if x >= n || y >= n {
        return None;
    }
    let i = (y * n + x) as usize;
    let o = *frame.distance.get(i)?;
    let u = *frame.umbra.get(i)?;
    let p = *frame.penumbra.get(i)?;
    let some = |v: f32| (v > 0.0 && v.is_finite()).then_some(v);
    Some(Texel {
        o: (f64::from(o) < NO_SURFACE * 0.5).then_some(o),
        uv: some(u[0]),
        pv: some(p[0]),
        s_umbra: some(u[0]).and(some(u[1])),
        s_penumbra: some(p[0]).and(some(p[1])),
    })
}

fn image(width: u32, height: u32, pixels: Vec<Color32>) -> ColorImage {
    ColorImage::new([width as usize, height as usize], pixels)
}

pub fn final_image(frame: &Frame) -> ColorImage {
    let pixels = frame
        .color
        .iter()
        .map(|c| Color32::from_rgba_unmultiplied(c[0], c[1], c[2], 255))
        .collect();
    image(frame.width, frame.height, pixels)
}

/// A per-pixel scalar through `mapping`; pixels without a surface are [`NO_DATA`].
pub fn scalar_image(frame: &Frame, values: &[f32], mapping: &mut Mapping) -> ColorImage {
    if mapping.auto {
        mapping.fit(
            values
                .iter()
                .enumerate()
                .filter(|(i, _)| hit(frame, *i))
                .map(|(_, v)| *v),
        );
    }
    let pixels = values
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            if hit(frame, i) {
                mapping.color(v)
            } else {
                NO_DATA
            }
        })
        .collect();
    image(frame.width, frame.height, pixels)
}

pub fn classes_image(frame: &Frame) -> ColorImage {
    let pixels = frame
        .branch
        .iter()
        .enumerate()
        .map(|(i, &b)| {
            if hit(frame, i) {
                BRANCH_COLORS.get(usize::from(b)).map_or(NO_DATA, |c| c.0)
            } else {
                NO_DATA
            }
        })
        .collect();
    image(frame.width, frame.height, pixels)
}

/// |V − reference| through `mapping`; `None` when the reference is of another size.
pub fn error_image(frame: &Frame, reference: &[f32], mapping: &mut Mapping) -> Option<ColorImage> {
    if reference.len() != frame.visibility.len() {
        return None;
    }
    let errors: Vec<f32> = frame
        .visibility
        .iter()
        .zip(reference)
        .map(|(v, r)| (v - r).abs())
        .collect();
    Some(scalar_image(frame, &errors, mapping))
}

/// The D-buffer with the channels `on` (of [`CHANNELS`]): one channel through the colour map;
/// several as an RGB composite of the first three (each through the range, in gray). `None`
/// when the frame carries no D-buffer.
pub fn dbuffer_image(frame: &Frame, on: [bool; 4], mapping: &mut Mapping) -> Option<ColorImage> {
    let n = frame.dbuffer_size;
    if n == 0 || frame.distance.len() != (n * n) as usize {
        return None;
    }
    let texels: Vec<Texel> = (0..n * n)
        .map(|i| texel(frame, i % n, i / n).unwrap_or_default())
        .collect();
    let selected: Vec<usize> = (0..4).filter(|&c| on[c]).collect();
    if mapping.auto {
        mapping.fit(
            texels
                .iter()
                .flat_map(|t| selected.iter().filter_map(|&c| t.channel(c))),
        );
    }
    let pixels = match selected.as_slice() {
        [] => vec![NO_DATA; texels.len()],
        [c] => texels
            .iter()
            .map(|t| t.channel(*c).map_or(NO_DATA, |v| mapping.color(v)))
            .collect(),
        several => texels
            .iter()
            .map(|t| {
                let mut rgb = [0.0f32; 3];
                let mut any = false;
                for &c in several.iter().filter(|&&c| c < 3) {
                    if let Some(v) = t.channel(c) {
                        rgb[c] = mapping.normalise(v);
                        any = true;
                    }
                }
                if any {
                    self::rgb(rgb[0], rgb[1], rgb[2])
                } else {
                    NO_DATA
                }
            })
            .collect(),
    };
    Some(image(n, n, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> Frame {
        Frame {
            width: 2,
            height: 1,
            color: vec![[10, 20, 30, 255], [40, 50, 60, 255]],
            visibility: vec![0.25, 0.75],
            t: vec![0.3, 0.9],
            branch: vec![1, 3],
            position: vec![[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]],
            dbuffer_size: 2,
            distance: vec![1.0, 2.0, NO_SURFACE as f32, 4.0],
            umbra: vec![[0.0, 0.0], [3.0, 2.5], [0.0, 0.0], [5.0, 4.5]],
            penumbra: vec![[1.5, 1.2], [0.0, 0.0], [0.0, 0.0], [6.0, 5.5]],
            gpu_ms: Vec::new(),
        }
    }

    #[test]
    fn mapping_ends_and_auto_fit() {
        let mut m = Mapping::unit();
        assert_eq!(m.color(0.0), Color32::BLACK);
        assert_eq!(m.color(1.0), Color32::WHITE);
        assert_eq!(m.color(7.0), Color32::WHITE, "clamped");
        m.fit([3.0, f32::NAN, -1.0, f32::INFINITY, 2.0].into_iter());
        assert_eq!((m.black, m.white), (-1.0, 3.0));
        m.fit(std::iter::empty());
        assert_eq!((m.black, m.white), (-1.0, 3.0), "no values: range kept");
        // A few far outliers do not set the range.
        m.fit((0..1000).map(|i| i as f32 / 1000.0).chain([300.0, 290.0]));
        assert!(m.black < 0.01 && (0.98..1.0).contains(&m.white), "{m:?}");
    }

    #[test]
    fn scalar_view_paints_misses_as_background() {
        let f = frame();
        let img = scalar_image(&f, &f.visibility, &mut Mapping::unit());
        assert_eq!(img.size, [2, 1]);
        assert_eq!(img.pixels[0], Color32::from_rgb(64, 64, 64));
        assert_eq!(img.pixels[1], NO_DATA);
    }

    #[test]
    fn texels_decode_sentinels() {
        let f = frame();
        let t = texel(&f, 0, 0).unwrap();
        assert_eq!((t.o, t.uv, t.pv), (Some(1.0), None, Some(1.5)));
        assert_eq!(
            t.channel(3),
            Some(1.2),
            "|cx_s| of the penumbra without an umbra"
        );
        let t = texel(&f, 0, 1).unwrap();
        assert_eq!(t.o, None, "NO_SURFACE is no surface");
        assert!(texel(&f, 2, 0).is_none());
    }

    #[test]
    fn dbuffer_isolation_and_composite() {
        let f = frame();
        let mut m = Mapping::auto();
        let img = dbuffer_image(&f, [false, true, false, false], &mut m).unwrap();
        assert_eq!((m.black, m.white), (3.0, 5.0), "fit to |cx_uv| only");
        assert_eq!(img.pixels[0], NO_DATA, "no umbra exit there");
        let mut m = Mapping::unit();
        m.white = 10.0;
        let img = dbuffer_image(&f, [true, true, true, false], &mut m).unwrap();
        // texel (1, 1): o = 4, uv = 5, pv = 6 → 0.4, 0.5, 0.6
        assert_eq!(img.pixels[3], Color32::from_rgb(102, 128, 153));
    }

    #[test]
    fn error_needs_a_reference_of_the_same_size() {
        let f = frame();
        assert!(error_image(&f, &[0.0], &mut Mapping::error()).is_none());
        let img = error_image(&f, &[0.0, 0.0], &mut Mapping::error()).unwrap();
        assert_eq!(
            img.pixels[0],
            Color32::WHITE,
            "0.25 is the top of the heat map"
        );
    }
}
