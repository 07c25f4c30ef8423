//! The error heatmap: `|V − V_ref|` per pixel through a perceptual colour map, with a legend bar
//! and its tick labels drawn by a tiny built-in bitmap font (so no font file is needed).

use image::{Rgb, RgbImage};

/// The error at which the colour map saturates; larger errors share its colour.
pub const FULL_SCALE: f32 = 0.5;
/// Pixels that do not count (no surface, or turned away from the light).
pub const MASKED_RGB: [u8; 3] = [28, 30, 38];

/// A perceptual dark-to-bright colour map (inferno-like, piecewise linear through 6 stops), for
/// `x` in [0, 1].
pub fn colormap(x: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 6] = [
        [0.0, 0.0, 4.0],
        [40.0, 11.0, 84.0],
        [101.0, 21.0, 110.0],
        [188.0, 55.0, 84.0],
        [249.0, 142.0, 9.0],
        [252.0, 255.0, 164.0],
    ];
    through(&STOPS, x)
}

/// FLIP's colour map for its error maps (magma, piecewise linear through 9 stops), `x` in [0, 1].
pub fn magma(x: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 9] = [
        [0.0, 0.0, 4.0],
        [28.0, 16.0, 68.0],
        [79.0, 18.0, 123.0],
        [129.0, 37.0, 129.0],
        [181.0, 54.0, 122.0],
        [229.0, 80.0, 100.0],
        [251.0, 135.0, 97.0],
        [254.0, 194.0, 135.0],
        [252.0, 253.0, 191.0],
    ];
    through(&STOPS, x)
}

/// The colour at `x` in [0, 1] (clamped; NaN as 0) of a map piecewise linear through `stops`
/// (at least two), evenly spaced.
fn through(stops: &[[f32; 3]], x: f32) -> [u8; 3] {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let f = x * (stops.len() - 1) as f32;
    let i = (f.floor() as usize).min(stops.len() - 2);
    let t = f - i as f32;
    [0, 1, 2].map(|k| (stops[i][k] + (stops[i + 1][k] - stops[i][k]) * t).round() as u8)
}

/// The colour of an error `|ΔV|`.
pub fn error_rgb(err: f32) -> [u8; 3] {
    colormap(err / FULL_SCALE)
}

const LEGEND_HEIGHT: u32 = 34;

/// Where a hard method's class differs from the exact hard shadow's: darkened where the exact one
/// is lit (a false shadow: acne, a shadow too large), lit where it is dark (a missed shadow: a
/// leak, a shadow too small).
pub const FALSE_SHADOW_RGB: [u8; 3] = [235, 45, 45];
pub const MISSED_SHADOW_RGB: [u8; 3] = [40, 140, 255];

/// A hard method against the exact hard shadow (classes lit iff V ≥ ½) over the method's own
/// image `color` (sRGB RGBA, dimmed for orientation): [`FALSE_SHADOW_RGB`] and
/// [`MISSED_SHADOW_RGB`] where the classes differ; masked pixels dark.
pub fn hard_mismatch(
    exact: &[f32],
    method: &[f32],
    mask: &[bool],
    color: &[[u8; 4]],
    width: u32,
    height: u32,
) -> RgbImage {
    let mut img = RgbImage::from_pixel(width, height, Rgb(MASKED_RGB));
    for (i, px) in img.pixels_mut().enumerate() {
        if !mask.get(i).copied().unwrap_or(false) {
            continue;
        }
        let (e, m) = (exact.get(i).copied(), method.get(i).copied());
        let (Some(e), Some(m)) = (e, m) else { continue };
        let grey = color.get(i).map_or(0, |c| c[0] / 3 + 20);
        *px = match (e >= 0.5, m >= 0.5) {
            (true, false) => Rgb(FALSE_SHADOW_RGB),
            (false, true) => Rgb(MISSED_SHADOW_RGB),
            _ => Rgb([grey, grey, grey]),
        };
    }
    img
}

/// The heatmap of `|method − reference|` over `width`×`height`, with a legend strip below it.
pub fn render(
    reference: &[f32],
    method: &[f32],
    mask: &[bool],
    width: u32,
    height: u32,
) -> RgbImage {
    let mut img = RgbImage::from_pixel(width, height + LEGEND_HEIGHT, Rgb([255, 255, 255]));
    for (i, ((r, m), on)) in reference.iter().zip(method).zip(mask).enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        if y >= height {
            break;
        }
        let rgb = if *on {
            error_rgb((m - r).abs())
        } else {
            MASKED_RGB
        };
        img.put_pixel(x, y, Rgb(rgb));
    }
    draw_legend(&mut img, height, width);
    img
}

/// The FLIP map of a method against the reference (per pixel in [0, 1]) in FLIP's own colour
/// map (magma), with a legend strip below it: ticks at 0, 0.2 … 1.
pub fn flip(map: &[f32], width: u32, height: u32) -> RgbImage {
    let mut img = RgbImage::from_pixel(width, height + LEGEND_HEIGHT, Rgb([255, 255, 255]));
    for (i, v) in map.iter().enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        if y >= height {
            break;
        }
        img.put_pixel(x, y, Rgb(magma(*v)));
    }
    legend(&mut img, (height, width), magma, 1.0, false);
    img
}

/// Each pixel's work (`cost[i][0]`) from black to the colour map's top at `max` (the method's
/// largest: each method counts its own unit), with a legend of 0 … max below; masked pixels dark.
pub fn cost(cost: &[[f32; 2]], mask: &[bool], width: u32, height: u32, max: f32) -> RgbImage {
    let mut img = RgbImage::from_pixel(width, height + LEGEND_HEIGHT, Rgb([255, 255, 255]));
    let top = max.max(1e-6);
    for (i, c) in cost.iter().enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        if y >= height {
            break;
        }
        let rgb = if mask.get(i).copied().unwrap_or(false) {
            colormap(c[0] / top)
        } else {
            MASKED_RGB
        };
        img.put_pixel(x, y, Rgb(rgb));
    }
    legend(&mut img, (height, width), colormap, max, true);
    img
}

/// Under an image of width `width` whose legend strip starts at `top`: a colour bar of `map`
/// over most of the width with six ticks from 0 to `full` (whole numbers when `counts`).
fn legend(
    img: &mut RgbImage,
    (top, width): (u32, u32),
    map: fn(f32) -> [u8; 3],
    full: f32,
    counts: bool,
) {
    let margin = 4;
    let (x0, x1) = (margin, width.saturating_sub(margin + 12));
    if x1 <= x0 + 10 {
        return;
    }
    for x in x0..=x1 {
        let f = (x - x0) as f32 / (x1 - x0) as f32;
        for y in top + 4..top + 10 {
            img.put_pixel(x, y, Rgb(map(f)));
        }
    }
    for k in 0..=5u32 {
        let f = k as f32 / 5.0;
        let x = x0 + ((x1 - x0) as f32 * f).round() as u32;
        for y in top + 10..top + 13 {
            img.put_pixel(x, y, Rgb([0, 0, 0]));
        }
        let text = if counts {
            format!("{}", (f * full).round())
        } else {
            format!("{:.1}", f * full)
        };
        let tw = text_width(&text, 1);
        let tx = x.saturating_sub(tw / 2).min(width.saturating_sub(tw));
        draw_text(img, &text, tx, top + 14, 1, [0, 0, 0]);
    }
}

/// A colour bar over most of the width, ticks at 0, 0.1 … 0.5 with labels, and "|dV|".
fn draw_legend(img: &mut RgbImage, top: u32, width: u32) {
    let scale = if width >= 256 { 2 } else { 1 };
    let label = "|dV|";
    let label_w = text_width(label, scale) + 4 * scale;
    let margin = 4 * scale;
    let x0 = label_w + margin;
    let x1 = width.saturating_sub(margin + 3 * 4 * scale);
    if x1 <= x0 + 10 {
        return; // too narrow for a legend
    }
    draw_text(img, label, 2, top + 4, scale, [0, 0, 0]);
    let bar_h = 6 * scale;
    for x in x0..=x1 {
        let f = (x - x0) as f32 / (x1 - x0) as f32;
        for y in top + 4..top + 4 + bar_h {
            img.put_pixel(x, y, Rgb(colormap(f)));
        }
    }
    let ticks = 5;
    for k in 0..=ticks {
        let f = k as f32 / ticks as f32;
        let x = x0 + ((x1 - x0) as f32 * f).round() as u32;
        for y in top + 4 + bar_h..top + 7 + bar_h {
            img.put_pixel(x, y, Rgb([0, 0, 0]));
        }
        let text = if k == ticks {
            format!("{:.1}+", f * FULL_SCALE)
        } else {
            format!("{:.1}", f * FULL_SCALE)
        };
        let tw = text_width(&text, 1);
        let tx = x.saturating_sub(tw / 2).min(width.saturating_sub(tw));
        draw_text(img, &text, tx, top + 8 + bar_h, 1, [0, 0, 0]);
    }
}

/// 3×5 glyphs, one `u16` per glyph, rows top to bottom, 3 bits a row (MSB left).
fn glyph(c: char) -> Option<u16> {
    Some(match c {
        '0' => 0b111_101_101_101_111,
        '1' => 0b010_110_010_010_111,
        '2' => 0b111_001_111_100_111,
        '3' => 0b111_001_111_001_111,
        '4' => 0b101_101_111_001_001,
        '5' => 0b111_100_111_001_111,
        '6' => 0b111_100_111_101_111,
        '7' => 0b111_001_010_010_010,
        '8' => 0b111_101_111_101_111,
        '9' => 0b111_101_111_001_111,
        '.' => 0b000_000_000_000_010,
        '+' => 0b000_010_111_010_000,
        '|' => 0b010_010_010_010_010,
        'd' => 0b001_001_111_101_111,
        'V' => 0b101_101_101_101_010,
        ' ' => 0,
        _ => return None,
    })
}

fn text_width(text: &str, scale: u32) -> u32 {
    text.chars().count() as u32 * 4 * scale
}

/// Draw `text` with its top-left at (x, y); unknown characters are skipped.
fn draw_text(img: &mut RgbImage, text: &str, x: u32, y: u32, scale: u32, rgb: [u8; 3]) {
    for (i, c) in text.chars().enumerate() {
        let Some(bits) = glyph(c) else { continue };
        let gx = x + i as u32 * 4 * scale;
        for row in 0..5u32 {
            for col in 0..3u32 {
                if bits >> (14 - (row * 3 + col)) & 1 == 1 {
                    for sy in 0..scale {
                        for sx in 0..scale {
                            let (px, py) = (gx + col * scale + sx, y + row * scale + sy);
                            if px < img.width() && py < img.height() {
                                img.put_pixel(px, py, Rgb(rgb));
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_colormaps_run_dark_to_bright() {
        let luma =
            |c: [u8; 3]| 0.3 * f32::from(c[0]) + 0.59 * f32::from(c[1]) + 0.11 * f32::from(c[2]);
        for map in [colormap, magma] {
            let mut last = -1.0;
            for k in 0..=20 {
                let l = luma(map(k as f32 / 20.0));
                assert!(l > last, "not monotonic at {k}");
                last = l;
            }
        }
        assert_eq!(magma(f32::NAN), magma(0.0));
        assert_eq!(error_rgb(2.0), colormap(1.0));
        assert_eq!(colormap(f32::NAN), colormap(0.0));
    }

    #[test]
    fn heatmap_pixels_and_legend() {
        let (w, h) = (300, 20);
        let n = (w * h) as usize;
        let reference = vec![0.5; n];
        let method: Vec<f32> = (0..n).map(|i| if i % 2 == 0 { 0.5 } else { 0.0 }).collect();
        let mut mask = vec![true; n];
        mask[3] = false;
        let img = render(&reference, &method, &mask, w, h);
        assert_eq!(img.dimensions(), (w, h + LEGEND_HEIGHT));
        assert_eq!(img.get_pixel(0, 0).0, colormap(0.0));
        assert_eq!(img.get_pixel(1, 0).0, colormap(1.0));
        assert_eq!(img.get_pixel(3, 0).0, MASKED_RGB);
        // The legend holds the bar's colours and black label pixels.
        let legend: Vec<[u8; 3]> = (0..w)
            .flat_map(|x| (h..h + LEGEND_HEIGHT).map(move |y| (x, y)))
            .map(|(x, y)| img.get_pixel(x, y).0)
            .collect();
        assert!(legend.contains(&[0, 0, 0]));
        assert!(legend.iter().any(|c| *c == colormap(1.0)));
        for c in "0123456789.+|dV ".chars() {
            assert!(glyph(c).is_some(), "{c}");
        }
    }
}
