//! LDR-FLIP (Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström and Fairchild, "FLIP: A
//! Difference Evaluator for Alternating Images", HPG 2020): how different two sRGB images look
//! to a person flipping between them, per pixel in [0, 1]. `compare` scores each method's shaded
//! image against the reference's with it (docs/method/metrics.md); the lab's error view shows
//! its map beside |ΔV|.
//!
//! Written here from the paper rather than bound from NVIDIA's C++ (the `nv-flip` crate): the
//! metric is some 200 lines of arithmetic on two images, and a binding would bring a C++ build
//! (`cc`) into every build of the lab and of CI for it. The steps, as the paper and NVIDIA's
//! reference code give them:
//!
//! 1. **Colour pipeline**: sRGB → linear RGB → XYZ → YCxCz (an opponent space, linear in
//!    light); each channel filtered by the contrast sensitivity of the eye at `ppd` pixels per
//!    degree (the achromatic and red-green channels one Gaussian, blue-yellow a sum of two; the
//!    filters are separable, radius `⌈3·√(0.04 / 2π²)·ppd⌉`); back to linear RGB clamped to the
//!    unit cube, then CIELAB with the Hunt adjustment (a and b scaled by L/100); the HyAB
//!    distance |ΔL| + ‖Δ(a, b)‖ raised to 0.7, remapped so that 40 % of the largest distance
//!    (green against blue) is 0.95.
//! 2. **Feature pipeline**: on the unfiltered achromatic channel, edges (first derivative of a
//!    Gaussian, σ = ½·0.082·ppd) and points (second derivative), each kernel's positive and
//!    negative weights normalised to ±1; the larger difference of the two images' edge and point
//!    magnitudes, over √2, raised to 0.5.
//! 3. **FLIP** = colour error ^ (1 − feature error).
//!
//! Borders repeat the edge pixel (as NVIDIA's C++ does). Checked against NVIDIA's own Python
//! package (`flip-evaluator` 1.7) on fixed image pairs in the tests below.

use rayon::prelude::*;

/// Pixels per degree of visual angle FLIP assumes by default: a 0.7 m wide 3840-pixel monitor
/// seen from 0.7 m (NVIDIA's default, 67.0 in their tools).
pub const DEFAULT_PPD: f32 = 0.7 * 3840.0 / 0.7 * std::f32::consts::PI / 180.0;

/// Largest `ppd` accepted: its filters' radius grows with it (at 67 ppd, 10 and 9 pixels).
pub const MAX_PPD: f32 = 1000.0;

const QC: f32 = 0.7;
const QF: f32 = 0.5;
const PC: f32 = 0.4;
const PT: f32 = 0.95;
/// Peak-to-trough width of the eye's edge detector, in degrees.
const FEATURE_W: f32 = 0.082;

/// sRGB → XYZ (D65), NVIDIA's exact fractions.
const RGB_TO_XYZ: [[f32; 3]; 3] = [
    [
        10135552.0 / 24577794.0,
        8788810.0 / 24577794.0,
        4435075.0 / 24577794.0,
    ],
    [
        2613072.0 / 12288897.0,
        8788810.0 / 12288897.0,
        887015.0 / 12288897.0,
    ],
    [
        1425312.0 / 73733382.0,
        8788810.0 / 73733382.0,
        70074185.0 / 73733382.0,
    ],
];

/// XYZ → sRGB, NVIDIA's values as f32 holds them.
const XYZ_TO_RGB: [[f32; 3]; 3] = [
    [3.241_003_3, -1.537_398_9, -0.498_615_86],
    [-0.969_224_33, 1.875_930_1, 0.041554224],
    [0.055639423, -0.204_011_2, 1.057_148_9],
];

fn mul(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// The reference white: linear RGB (1, 1, 1) in XYZ.
fn white() -> [f32; 3] {
    mul(&RGB_TO_XYZ, [1.0; 3])
}

fn srgb_to_linear(c: u8) -> f32 {
    let x = f32::from(c) / 255.0;
    if x > 0.04045 {
        ((x + 0.055) / 1.055).powf(2.4)
    } else {
        x / 12.92
    }
}

fn xyz_to_ycxcz(xyz: [f32; 3], w: [f32; 3]) -> [f32; 3] {
    let (x, y, z) = (xyz[0] / w[0], xyz[1] / w[1], xyz[2] / w[2]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz(c: [f32; 3], w: [f32; 3]) -> [f32; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let x = y + c[1] / 500.0;
    let z = y - c[2] / 200.0;
    [x * w[0], y * w[1], z * w[2]]
}

fn xyz_to_lab(xyz: [f32; 3], w: [f32; 3]) -> [f32; 3] {
    let delta: f32 = 6.0 / 29.0;
    let f = |t: f32| {
        if t > delta * delta * delta {
            t.cbrt()
        } else {
            t / (3.0 * delta * delta) + 4.0 / 29.0
        }
    };
    let (x, y, z) = (f(xyz[0] / w[0]), f(xyz[1] / w[1]), f(xyz[2] / w[2]));
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// CIELAB with the Hunt adjustment of linear RGB `rgb` (clamped to the unit cube).
fn hunt_lab(rgb: [f32; 3], w: [f32; 3]) -> [f32; 3] {
    let rgb = rgb.map(|c| c.clamp(0.0, 1.0));
    let lab = xyz_to_lab(mul(&RGB_TO_XYZ, rgb), w);
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

fn hyab(a: [f32; 3], b: [f32; 3]) -> f32 {
    (a[0] - b[0]).abs() + ((a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// One 1D kernel over `-r..=r`.
struct Kernel {
    weights: Vec<f32>,
}

impl Kernel {
    fn radius(&self) -> i64 {
        (self.weights.len() / 2) as i64
    }
}

/// The contrast-sensitivity filter of one channel: `Σ terms[k] · (g_k ⊗ g_k)`, each `g_k` a
/// normalised 1D Gaussian.
struct Csf {
    terms: Vec<(f32, Kernel)>,
}

/// The CSF of a channel (a1, b1, a2, b2 of the paper's Table 1), over radius `r`.
fn csf(ppd: f32, r: i64, (a1, b1, a2, b2): (f32, f32, f32, f32)) -> Csf {
    let pi = std::f32::consts::PI;
    let dx = 1.0 / ppd;
    let mut terms = Vec::new();
    let mut total = 0.0f32;
    for (a, b) in [(a1, b1), (a2, b2)] {
        if a == 0.0 {
            continue;
        }
        let e: Vec<f32> = (-r..=r)
            .map(|x| (-pi * pi * (x as f32 * dx).powi(2) / b).exp())
            .collect();
        let s: f32 = e.iter().sum();
        // The 2D term a·√(π/b)·e(x)·e(y) sums to a·√(π/b)·s².
        let mass = a * (pi / b).sqrt() * s * s;
        total += mass;
        terms.push((
            mass,
            Kernel {
                weights: e.iter().map(|v| v / s).collect(),
            },
        ));
    }
    for t in &mut terms {
        t.0 /= total;
    }
    Csf { terms }
}

/// `img` (`w`×`h`, one channel) convolved with `k` along x, then with `k` along y, edges
/// repeated.
fn separable(img: &[f32], w: usize, h: usize, kx: &Kernel, ky: &Kernel) -> Vec<f32> {
    let mut tmp = vec![0.0f32; img.len()];
    let rx = kx.radius();
    tmp.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            let src = &img[y * w..(y + 1) * w];
            for (x, out) in row.iter_mut().enumerate() {
                let mut acc = 0.0;
                for (k, wt) in kx.weights.iter().enumerate() {
                    let sx = (x as i64 + k as i64 - rx).clamp(0, w as i64 - 1) as usize;
                    acc += wt * src[sx];
                }
                *out = acc;
            }
        });
    let mut out = vec![0.0f32; img.len()];
    let ry = ky.radius();
    out.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let mut acc = 0.0;
                for (k, wt) in ky.weights.iter().enumerate() {
                    let sy = (y as i64 + k as i64 - ry).clamp(0, h as i64 - 1) as usize;
                    acc += wt * tmp[sy * w + x];
                }
                *o = acc;
            }
        });
    out
}

fn filtered(img: &[f32], w: usize, h: usize, f: &Csf) -> Vec<f32> {
    let mut out = vec![0.0f32; img.len()];
    for (weight, k) in &f.terms {
        let part = separable(img, w, h, k, k);
        for (o, p) in out.iter_mut().zip(part) {
            *o += weight * p;
        }
    }
    out
}

/// The feature detectors' 1D kernels: the derivative (edge) or second derivative (point) part,
/// its positive weights summing to 1 and its negative ones to −1, and the Gaussian across it
/// summing to 1 (so their product is the paper's 2D kernel, normalised the same way).
fn feature_kernels(ppd: f32) -> (Kernel, Kernel, Kernel) {
    let sd = 0.5 * FEATURE_W * ppd;
    let r = (3.0 * sd).ceil() as i64;
    let g: Vec<f32> = (-r..=r)
        .map(|x| (-(x * x) as f32 / (2.0 * sd * sd)).exp())
        .collect();
    let gs: f32 = g.iter().sum();
    let signed = |d: Vec<f32>| {
        let pos: f32 = d.iter().filter(|v| **v > 0.0).sum();
        let neg: f32 = -d.iter().filter(|v| **v < 0.0).sum::<f32>();
        Kernel {
            weights: d
                .into_iter()
                .map(|v| if v > 0.0 { v / pos } else { v / neg.max(1e-30) })
                .collect(),
        }
    };
    let edge = signed((-r..=r).zip(&g).map(|(x, gv)| -(x as f32) * gv).collect());
    let point = signed(
        (-r..=r)
            .zip(&g)
            .map(|(x, gv)| ((x * x) as f32 / (sd * sd) - 1.0) * gv)
            .collect(),
    );
    let smooth = Kernel {
        weights: g.iter().map(|v| v / gs).collect(),
    };
    (edge, point, smooth)
}

/// The edge and point magnitudes of one achromatic image.
fn features(y: &[f32], w: usize, h: usize, k: &(Kernel, Kernel, Kernel)) -> (Vec<f32>, Vec<f32>) {
    let (edge, point, smooth) = k;
    let ex = separable(y, w, h, edge, smooth);
    let ey = separable(y, w, h, smooth, edge);
    let px = separable(y, w, h, point, smooth);
    let py = separable(y, w, h, smooth, point);
    let norm = |a: &[f32], b: &[f32]| -> Vec<f32> {
        a.iter()
            .zip(b)
            .map(|(a, b)| (a * a + b * b).sqrt())
            .collect()
    };
    (norm(&ex, &ey), norm(&px, &py))
}

/// An image in YCxCz, one plane per channel.
struct Opponent {
    planes: [Vec<f32>; 3],
}

fn opponent(rgb: &[[u8; 3]]) -> Opponent {
    let w = white();
    let mut planes = [
        Vec::with_capacity(rgb.len()),
        Vec::with_capacity(rgb.len()),
        Vec::with_capacity(rgb.len()),
    ];
    for p in rgb {
        let lin = p.map(srgb_to_linear);
        let c = xyz_to_ycxcz(mul(&RGB_TO_XYZ, lin), w);
        for k in 0..3 {
            planes[k].push(c[k]);
        }
    }
    Opponent { planes }
}

/// Why FLIP cannot compare two images.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlipError {
    #[error("FLIP compares images of one size: {0} pixels against {1} for {2}×{3}")]
    Size(usize, usize, u32, u32),
    #[error("FLIP's pixels per degree must be finite and in (0, {MAX_PPD}], found {0}")]
    Ppd(f32),
}

/// The LDR-FLIP map of `test` against `reference` (sRGB, row-major, `width`×`height`), each
/// value in [0, 1], at `ppd` pixels per degree ([`DEFAULT_PPD`] as NVIDIA's tools).
///
/// Computed in bands of [`BAND_PIXELS`] with a margin of the filters' radius above and below
/// each: every filter is separable with its borders repeated, so a band's rows come out bit
/// for bit as from the whole image, and the working planes (some 80 bytes a pixel) are a
/// band's, not the image's.
pub fn ldr_flip(
    reference: &[[u8; 3]],
    test: &[[u8; 3]],
    width: u32,
    height: u32,
    ppd: f32,
) -> Result<Vec<f32>, FlipError> {
    let rows = (BAND_PIXELS / width.max(1) as usize).max(1);
    ldr_flip_banded(reference, test, width, height, ppd, rows)
}

/// Pixels of one band of [`ldr_flip`] (its margins aside).
pub const BAND_PIXELS: usize = 1 << 20;

fn ldr_flip_banded(
    reference: &[[u8; 3]],
    test: &[[u8; 3]],
    width: u32,
    height: u32,
    ppd: f32,
    band_rows: usize,
) -> Result<Vec<f32>, FlipError> {
    let (w, h) = (width as usize, height as usize);
    let n = w * h;
    if reference.len() != n || test.len() != n {
        return Err(FlipError::Size(reference.len(), test.len(), width, height));
    }
    if !(ppd.is_finite() && ppd > 0.0 && ppd <= MAX_PPD) {
        return Err(FlipError::Ppd(ppd));
    }
    if n == 0 {
        return Ok(Vec::new());
    }
    let pi = std::f32::consts::PI;
    let r = (3.0 * (0.04f32 / (2.0 * pi * pi)).sqrt() * ppd).ceil() as i64;
    let filters = Filters {
        channels: [
            csf(ppd, r, (1.0, 0.0047, 0.0, 1e-5)),
            csf(ppd, r, (1.0, 0.0053, 0.0, 1e-5)),
            csf(ppd, r, (34.1, 0.04, 13.5, 0.025)),
        ],
        features: feature_kernels(ppd),
    };
    let margin = filters.radius();
    let mut out = Vec::with_capacity(n);
    let band_rows = band_rows.max(1);
    for y0 in (0..h).step_by(band_rows) {
        let y1 = (y0 + band_rows).min(h);
        // The band with its margins, cut at the image's own edges.
        let (m0, m1) = (y0.saturating_sub(margin), (y1 + margin).min(h));
        let map = flip_whole(
            &reference[m0 * w..m1 * w],
            &test[m0 * w..m1 * w],
            w,
            m1 - m0,
            &filters,
        );
        out.extend_from_slice(&map[(y0 - m0) * w..(y1 - m0) * w]);
    }
    Ok(out)
}

/// FLIP's filters at one `ppd`.
struct Filters {
    channels: [Csf; 3],
    features: (Kernel, Kernel, Kernel),
}

impl Filters {
    /// Rows of the image one output row depends on, either side.
    fn radius(&self) -> usize {
        let csf = self.channels.iter().flat_map(|c| &c.terms);
        let (edge, point, smooth) = &self.features;
        csf.map(|(_, k)| k.radius())
            .chain([edge.radius(), point.radius(), smooth.radius()])
            .max()
            .unwrap_or(0) as usize
    }
}

/// The FLIP map of a whole `w`×`h` image pair (borders repeated at its edges).
fn flip_whole(
    reference: &[[u8; 3]],
    test: &[[u8; 3]],
    w: usize,
    h: usize,
    filters: &Filters,
) -> Vec<f32> {
    let n = w * h;
    let wp = white();
    let prepare = |rgb: &[[u8; 3]]| {
        let o = opponent(rgb);
        let f = [0, 1, 2].map(|k| filtered(&o.planes[k], w, h, &filters.channels[k]));
        let lab: Vec<[f32; 3]> = (0..n)
            .into_par_iter()
            .map(|i| {
                let xyz = ycxcz_to_xyz([f[0][i], f[1][i], f[2][i]], wp);
                hunt_lab(mul(&XYZ_TO_RGB, xyz), wp)
            })
            .collect();
        let y: Vec<f32> = o.planes[0].iter().map(|v| (v + 16.0) / 116.0).collect();
        (lab, features(&y, w, h, &filters.features))
    };
    let (ref_lab, (ref_edge, ref_point)) = prepare(reference);
    let (test_lab, (test_edge, test_point)) = prepare(test);
    let green = hunt_lab([0.0, 1.0, 0.0], wp);
    let blue = hunt_lab([0.0, 0.0, 1.0], wp);
    let cmax = hyab(green, blue).powf(QC);
    let pccmax = PC * cmax;
    (0..n)
        .into_par_iter()
        .map(|i| {
            let e = hyab(ref_lab[i], test_lab[i]).powf(QC);
            let color = if e < pccmax {
                PT / pccmax * e
            } else {
                PT + (e - pccmax) / (cmax - pccmax) * (1.0 - PT)
            };
            let fe = (ref_edge[i] - test_edge[i])
                .abs()
                .max((ref_point[i] - test_point[i]).abs());
            let feature = (fe / std::f32::consts::SQRT_2).powf(QF);
            color.powf(1.0 - feature).clamp(0.0, 1.0)
        })
        .collect()
}

/// The mean of a FLIP map (NVIDIA's headline number: over every pixel).
pub fn mean(map: &[f32]) -> f64 {
    if map.is_empty() {
        return 0.0;
    }
    map.iter().map(|&v| f64::from(v)).sum::<f64>() / map.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 48×32 test pattern: a soft-edged dark disc on a lit floor, as a soft shadow looks.
    fn pattern(shift: f32, noise: u32) -> Vec<[u8; 3]> {
        let (w, h) = (48, 32);
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                let d = ((x - 20.0 - shift).powi(2) + (y - 16.0).powi(2)).sqrt();
                let v = ((d - 8.0) / 6.0).clamp(0.0, 1.0);
                // A deterministic grain of ±`noise` levels.
                let grain = if noise == 0 {
                    0
                } else {
                    (i as u32).wrapping_mul(2654435761) % (2 * noise + 1)
                };
                let g = (30.0 + 200.0 * v).round() as i32 + grain as i32 - noise as i32;
                let g = g.clamp(0, 255) as u8;
                [g, (f32::from(g) * 0.95) as u8, (f32::from(g) * 0.85) as u8]
            })
            .collect()
    }

    #[test]
    fn an_image_against_itself_is_zero_and_against_blank_is_large() {
        let a = pattern(0.0, 0);
        let same = ldr_flip(&a, &a, 48, 32, DEFAULT_PPD).unwrap();
        assert!(same.iter().all(|&v| v == 0.0), "{:?}", &same[..8]);
        let blank = vec![[0u8; 3]; a.len()];
        let m = mean(&ldr_flip(&a, &blank, 48, 32, DEFAULT_PPD).unwrap());
        assert!(m > 0.5, "FLIP of black against the pattern: {m}");
        let white = vec![[255u8; 3]; a.len()];
        let m = mean(&ldr_flip(&a, &white, 48, 32, DEFAULT_PPD).unwrap());
        assert!(m > 0.3, "FLIP of white against the pattern: {m}");
    }

    #[test]
    fn a_larger_change_scores_higher() {
        let a = pattern(0.0, 0);
        let m1 = mean(&ldr_flip(&a, &pattern(1.0, 0), 48, 32, DEFAULT_PPD).unwrap());
        let m4 = mean(&ldr_flip(&a, &pattern(4.0, 0), 48, 32, DEFAULT_PPD).unwrap());
        assert!(0.0 < m1 && m1 < m4, "{m1} {m4}");
    }

    /// NVIDIA's own implementation on the same pairs: `flip_evaluator.evaluate(a, b, "LDR")`
    /// of the Python package `flip-evaluator` 1.7 (its C++ core), the mean and the map at row
    /// 16, columns 10, 12, 14, 26 and 28. Not our own numbers: an independent implementation's.
    #[test]
    fn it_agrees_with_nvidias_flip() {
        let a = pattern(0.0, 0);
        // A pair's name, its test image, NVIDIA's mean and NVIDIA's map at five pixels.
        type Case = (&'static str, Vec<[u8; 3]>, f64, [f32; 5]);
        let cases: [Case; 4] = [
            (
                "shift 1",
                pattern(1.0, 0),
                0.117_321_8,
                [0.44043, 0.440788, 0.20182, 0.087461, 0.375279],
            ),
            (
                "shift 4",
                pattern(4.0, 0),
                0.305_287_8,
                [0.84927, 0.938081, 0.851059, 0.161217, 0.548623],
            ),
            (
                "grain 6",
                pattern(0.0, 6),
                0.025_242_4,
                [0.042099, 0.024507, 0.024962, 0.021182, 0.009896],
            ),
            (
                "blank",
                vec![[0u8; 3]; a.len()],
                0.900_885_8,
                [0.946414, 0.712661, 0.475449, 0.475449, 0.712661],
            ),
        ];
        for (name, b, want_mean, want_row) in cases {
            let map = ldr_flip(&a, &b, 48, 32, DEFAULT_PPD).unwrap();
            let m = mean(&map);
            assert!(
                (m - want_mean).abs() < 2e-3,
                "{name}: mean {m} against NVIDIA's {want_mean}"
            );
            for (x, want) in [10, 12, 14, 26, 28].into_iter().zip(want_row) {
                let got = map[16 * 48 + x];
                assert!(
                    (got - want).abs() < 0.01,
                    "{name}: ({x}, 16) {got} against NVIDIA's {want}"
                );
            }
        }
    }

    /// Bands with their margins give the whole image's map bit for bit, down to one row a band
    /// (32 rows against margins of 10).
    #[test]
    fn bands_are_the_whole_image_bit_for_bit() {
        let (a, b) = (pattern(0.0, 0), pattern(3.0, 6));
        let whole = ldr_flip_banded(&a, &b, 48, 32, DEFAULT_PPD, 32).unwrap();
        assert!(whole.iter().any(|&v| v > 0.1));
        for rows in [1, 3, 7, 31] {
            let banded = ldr_flip_banded(&a, &b, 48, 32, DEFAULT_PPD, rows).unwrap();
            assert!(banded == whole, "bands of {rows} rows");
        }
    }

    #[test]
    fn sizes_and_ppd_are_checked() {
        let a = pattern(0.0, 0);
        assert!(matches!(
            ldr_flip(&a, &a[1..], 48, 32, DEFAULT_PPD),
            Err(FlipError::Size(..))
        ));
        assert!(matches!(
            ldr_flip(&a, &a, 48, 32, f32::NAN),
            Err(FlipError::Ppd(_))
        ));
        assert!((DEFAULT_PPD - 67.02).abs() < 0.01, "{DEFAULT_PPD}");
    }
}
