//! `montage.png`: every method `compare` drew on one page, so a comparison can be read at a glance
//! (and the README's pictures are a run's own file, not assembled by hand). One tile per method,
//! in the report's order (the reference first, then the registry's): a label with the method's
//! name and headline numbers (class mismatch %, penumbra MAE, and against `reference-hard` for a
//! hard method), then its image, its `|V − V_ref|` heatmap, its FLIP map against the reference's
//! image and — when the comparison has `reference-hard` — its mismatch against the exact hard
//! shadow. A footer says what the rows
//! are.
//!
//! Tiles are downscaled by a whole factor so that no cell is wider or taller than [`MAX_CELL`]
//! (a 512² comparison: 256² cells, seven to a row, 1856 px wide). The image is box-filtered; the
//! error rows keep the worst of each block (the largest `|ΔV|`, a mismatched pixel's colour over a
//! matching one's), so a one-pixel error line survives the reduction.
//!
//! Text is DejaVu Sans (`assets/fonts/`, the font the bench plot embeds) rasterised by `ab_glyph`,
//! the rasteriser already in the build through plotters.

use crate::render::truth;
use ab_glyph::{point, Font, FontRef, PxScale, ScaleFont};
use image::{Rgb, RgbImage};

use super::{heatmap, Against, Comparison, MethodResult};
use crate::render::Method;

pub const MONTAGE_PNG: &str = "montage.png";
/// The largest side of a cell (a downscaled image).
pub const MAX_CELL: u32 = 256;
/// Tiles per row.
pub const MAX_COLUMNS: u32 = 7;

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
/// Around tiles and between a tile's cells.
const GAP: u32 = 8;
const BACKGROUND: [u8; 3] = [24, 24, 28];
const TEXT: [u8; 3] = [235, 235, 235];
const DIM_TEXT: [u8; 3] = [170, 170, 178];
const NAME_PX: f32 = 15.0;
const NUMBERS_PX: f32 = 12.0;
/// The label above each tile's cells: a name and two lines of numbers.
const LABEL_HEIGHT: u32 = 52;
const FOOTER_HEIGHT: u32 = 44;

/// Where everything goes: the same for every comparison of a given size, method count and
/// row count (tests compute it to find a tile's cells).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// The whole factor each image is reduced by.
    pub factor: u32,
    /// A cell's size (a reduced image).
    pub cell: (u32, u32),
    /// Cells per tile, top to bottom: image, heatmap, FLIP, and the hard mismatch if any.
    pub cells: u32,
    pub columns: u32,
    pub rows: u32,
    pub width: u32,
    pub height: u32,
}

impl Layout {
    /// The layout of `tiles` tiles of `width`×`height` images with `cells` cells each.
    pub fn new(width: u32, height: u32, tiles: u32, cells: u32) -> Layout {
        let factor = width.max(height).div_ceil(MAX_CELL).max(1);
        let cell = (width.div_ceil(factor), height.div_ceil(factor));
        let columns = tiles.clamp(1, MAX_COLUMNS);
        let rows = tiles.div_ceil(columns).max(1);
        let tile_height = LABEL_HEIGHT + cells * cell.1 + cells.saturating_sub(1) * GAP;
        Layout {
            factor,
            cell,
            cells,
            columns,
            rows,
            width: columns * cell.0 + (columns + 1) * GAP,
            height: rows * tile_height + (rows + 1) * GAP + FOOTER_HEIGHT,
        }
    }

    /// The layout of `c`'s montage.
    pub fn of(c: &Comparison) -> Layout {
        Layout::planned(c.request.width, c.request.height, &c.outline().drawn)
    }

    /// The layout of a montage of `drawn` at `width`×`height`, known before any frame: a fourth
    /// row when `reference-hard` is among them.
    pub fn planned(width: u32, height: u32, drawn: &[Method]) -> Layout {
        let cells = if drawn.contains(&truth::HARD) { 4 } else { 3 };
        Layout::new(width, height, super::tiles(drawn).len() as u32, cells)
    }

    /// Top-left corner of tile `i` (its label).
    pub fn tile(&self, i: u32) -> (u32, u32) {
        let (col, row) = (i % self.columns, i / self.columns);
        let tile_height = LABEL_HEIGHT + self.cells * self.cell.1 + (self.cells - 1) * GAP;
        (
            GAP + col * (self.cell.0 + GAP),
            GAP + row * (tile_height + GAP),
        )
    }

    /// Top-left corner of cell `k` (0 image, 1 heatmap, 2 FLIP, 3 hard mismatch) of tile `i`.
    pub fn cell(&self, i: u32, k: u32) -> (u32, u32) {
        let (x, y) = self.tile(i);
        (x, y + LABEL_HEIGHT + k * (self.cell.1 + GAP))
    }
}

/// `img` as a PNG at the encoder's best compression: a page meant to be kept and shared (a
/// 512² comparison: about 0.3 MB instead of 0.8 MB at the fast level the other files use).
pub fn encode(img: &RgbImage) -> image::ImageResult<Vec<u8>> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    use image::{ExtendedColorType, ImageEncoder};
    let mut png = Vec::new();
    PngEncoder::new_with_quality(&mut png, CompressionType::Best, FilterType::Adaptive)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            ExtendedColorType::Rgb8,
        )?;
    Ok(png)
}

/// The montage of `c`.
pub fn render(c: &Comparison) -> RgbImage {
    let mut page = Page::new(Layout::of(c));
    let against = c.against();
    for (i, r) in c.results.iter().enumerate() {
        page.tile(i as u32, r, &against);
    }
    page.finish()
}

/// A montage being drawn, a tile as each method arrives (in any order): the page is the
/// layout's size from the start, whatever the images' size, and each tile is reduced from its
/// method's frame while that frame is held.
pub struct Page {
    img: RgbImage,
    layout: Layout,
    font: Option<FontRef<'static>>,
}

impl Page {
    pub fn new(layout: Layout) -> Page {
        Page {
            img: RgbImage::from_pixel(layout.width, layout.height, Rgb(BACKGROUND)),
            layout,
            font: FontRef::try_from_slice(FONT).ok(),
        }
    }

    /// Draw tile `i`: `r`'s label and cells, measured `against` its yardsticks.
    pub fn tile(&mut self, i: u32, r: &MethodResult, against: &Against<'_>) {
        let Page { img, layout, font } = self;
        let layout = *layout;
        let (w, h) = (r.frame.width, r.frame.height);
        let reference = against.reference;
        let (tx, ty) = layout.tile(i);
        if let Some(font) = &font {
            label(img, font, r, (tx, ty), layout.cell.0);
        }
        let color = &r.frame.color;
        let image = reduce(w, h, layout.factor, |idx| {
            let [r, g, b, _] = color.get(idx).copied().unwrap_or([0, 0, 0, 0]);
            Block::Mean([r, g, b])
        });
        paste(img, &image, layout.cell(i, 0));
        let (hx, hy) = layout.cell(i, 1);
        if truth::is_soft(r.method) {
            let cell = RgbImage::from_pixel(layout.cell.0, layout.cell.1, Rgb(heatmap::MASKED_RGB));
            paste(img, &cell, (hx, hy));
            if let Some(font) = &font {
                let x = hx + 6;
                let y = hy + 6;
                text(
                    img,
                    font,
                    "the reference",
                    (x, y),
                    NUMBERS_PX,
                    DIM_TEXT,
                    hx + layout.cell.0,
                );
            }
        } else {
            let v = &r.frame.visibility;
            let heat = reduce(w, h, layout.factor, |idx| {
                if against.mask.get(idx).copied().unwrap_or(false) {
                    let e = (v.get(idx).copied().unwrap_or(0.0)
                        - reference.get(idx).copied().unwrap_or(0.0))
                    .abs();
                    Block::Worst(e, heatmap::error_rgb(e))
                } else {
                    Block::Masked
                }
            });
            paste(img, &heat, (hx, hy));
        }
        // FLIP: the worst of each block, as the |ΔV| cell.
        let flip = &r.flip;
        let cell = reduce(w, h, layout.factor, |idx| {
            let v = flip.get(idx).copied().unwrap_or(0.0);
            Block::Worst(v, heatmap::magma(v))
        });
        paste(img, &cell, layout.cell(i, 2));
        if layout.cells < 4 {
            return;
        }
        let (ex, ey) = layout.cell(i, 3);
        match (against.exact, r.hard.is_some()) {
            (Some(exact), true) => {
                let mismatch =
                    heatmap::hard_mismatch(exact, &r.frame.visibility, against.mask, color, w, h);
                let raw = mismatch.as_raw();
                let cell = reduce(w, h, layout.factor, |idx| {
                    let p = [raw[3 * idx], raw[3 * idx + 1], raw[3 * idx + 2]];
                    if p == heatmap::FALSE_SHADOW_RGB {
                        Block::Worst(2.0, p)
                    } else if p == heatmap::MISSED_SHADOW_RGB {
                        Block::Worst(1.0, p)
                    } else {
                        Block::Mean(p)
                    }
                });
                paste(img, &cell, (ex, ey));
            }
            _ => {
                let cell =
                    RgbImage::from_pixel(layout.cell.0, layout.cell.1, Rgb(heatmap::MASKED_RGB));
                paste(img, &cell, (ex, ey));
                if let Some(font) = &font {
                    text(
                        img,
                        font,
                        "not a hard method",
                        (ex + 6, ey + 6),
                        NUMBERS_PX,
                        DIM_TEXT,
                        ex + layout.cell.0,
                    );
                }
            }
        }
    }

    /// The page with its footer.
    pub fn finish(mut self) -> RgbImage {
        if let Some(font) = &self.font {
            footer(&mut self.img, font, &self.layout);
        }
        self.img
    }
}

/// A tile's label: the name, then its numbers against the area reference, then (a hard method)
/// against `reference-hard`.
fn label(img: &mut RgbImage, font: &FontRef<'_>, r: &MethodResult, (x, y): (u32, u32), w: u32) {
    let right = x + w;
    let name = match r.history {
        Some(0) => format!("{} (first frame)", r.method.name()),
        Some(n) => format!("{} ({n} frames)", r.method.name()),
        None => r.method.name().to_string(),
    };
    text(img, font, &name, (x, y + 2), NAME_PX, TEXT, right);
    let numbers = if truth::is_soft(r.method) {
        format!("{} px counted", r.metrics.pixels)
    } else {
        format!(
            "class {:.2} % · pen. MAE {:.3}",
            r.metrics.class_mismatch_pct, r.metrics.penumbra_mae
        )
    };
    text(img, font, &numbers, (x, y + 20), NUMBERS_PX, TEXT, right);
    if let Some(hard) = &r.hard {
        let line = format!(
            "vs hard {:.3} % ({} edge, {} int.)",
            hard.mismatch_pct, hard.edge_px, hard.interior_px
        );
        text(img, font, &line, (x, y + 35), NUMBERS_PX, DIM_TEXT, right);
    }
}

/// What the rows are, and the heatmap's colour bar.
fn footer(img: &mut RgbImage, font: &FontRef<'_>, layout: &Layout) {
    let y = layout.height - FOOTER_HEIGHT;
    let right = layout.width - GAP;
    let rows = if layout.cells == 4 {
        "rows: image · |V − V_ref| · FLIP against the reference's image · against reference-hard \
         (red: false shadow, blue: missed)"
    } else {
        "rows: image · |V − V_ref| · FLIP against the reference's image"
    };
    text(img, font, rows, (GAP, y + 2), NUMBERS_PX, TEXT, right);
    let bar = (
        GAP,
        y + 22,
        160u32.min(layout.width.saturating_sub(2 * GAP)),
        10,
    );
    for dx in 0..bar.2 {
        let rgb = heatmap::colormap(dx as f32 / bar.2.max(1) as f32);
        for dy in 0..bar.3 {
            put(img, bar.0 + dx, bar.1 + dy, rgb);
        }
    }
    let legend = format!(
        "|ΔV| 0 … {:.1}+; FLIP 0 … 1 in magma   (cells reduced {}×: the image averaged, errors the worst of each block)",
        heatmap::FULL_SCALE,
        layout.factor
    );
    text(
        img,
        font,
        &legend,
        (bar.0 + bar.2 + 8, y + 20),
        NUMBERS_PX,
        DIM_TEXT,
        right,
    );
}

/// What a source pixel contributes to its block.
enum Block {
    /// Averaged with the block's other `Mean` pixels.
    Mean([u8; 3]),
    /// Ranked: the block shows its highest-ranked pixel's colour.
    Worst(f32, [u8; 3]),
    /// Not counted: [`heatmap::MASKED_RGB`] if the whole block is.
    Masked,
}

/// A `width`×`height` picture reduced by `factor`, each block from its pixels' [`Block`]s: the
/// worst `Worst` if any, else the mean of the `Mean`s, else masked.
fn reduce(width: u32, height: u32, factor: u32, pixel: impl Fn(usize) -> Block) -> RgbImage {
    let (cw, ch) = (width.div_ceil(factor), height.div_ceil(factor));
    let mut out = RgbImage::new(cw, ch);
    for (bx, by, px) in out.enumerate_pixels_mut() {
        let mut sum = [0u32; 3];
        let mut n = 0u32;
        let mut worst: Option<(f32, [u8; 3])> = None;
        for y in by * factor..((by + 1) * factor).min(height) {
            for x in bx * factor..((bx + 1) * factor).min(width) {
                match pixel((y * width + x) as usize) {
                    Block::Mean(c) => {
                        for k in 0..3 {
                            sum[k] += u32::from(c[k]);
                        }
                        n += 1;
                    }
                    Block::Worst(e, c) => {
                        if worst.is_none_or(|(w, _)| e > w) {
                            worst = Some((e, c));
                        }
                    }
                    Block::Masked => {}
                }
            }
        }
        *px = Rgb(match (worst, n) {
            (Some((_, c)), _) => c,
            (None, 0) => heatmap::MASKED_RGB,
            (None, n) => sum.map(|s| ((s + n / 2) / n) as u8),
        });
    }
    out
}

fn paste(img: &mut RgbImage, cell: &RgbImage, (x, y): (u32, u32)) {
    for (cx, cy, p) in cell.enumerate_pixels() {
        put(img, x + cx, y + cy, p.0);
    }
}

fn put(img: &mut RgbImage, x: u32, y: u32, rgb: [u8; 3]) {
    if x < img.width() && y < img.height() {
        img.put_pixel(x, y, Rgb(rgb));
    }
}

/// Draw `s` with its top-left at (x, y), `px` pixels high, clipped at `right`.
fn text(
    img: &mut RgbImage,
    font: &FontRef<'_>,
    s: &str,
    (x, y): (u32, u32),
    px: f32,
    rgb: [u8; 3],
    right: u32,
) {
    let scaled = font.as_scaled(PxScale::from(px));
    let baseline = y as f32 + scaled.ascent();
    let mut caret = x as f32;
    let mut last = None;
    for c in s.chars() {
        let id = scaled.glyph_id(c);
        if let Some(prev) = last {
            caret += scaled.kern(prev, id);
        }
        let glyph = id.with_scale_and_position(PxScale::from(px), point(caret, baseline));
        caret += scaled.h_advance(id);
        last = Some(id);
        let Some(outline) = font.outline_glyph(glyph) else {
            continue;
        };
        let bounds = outline.px_bounds();
        outline.draw(|gx, gy, coverage| {
            let px = bounds.min.x as i64 + i64::from(gx);
            let py = bounds.min.y as i64 + i64::from(gy);
            if px < 0 || py < 0 || px >= i64::from(right) {
                return;
            }
            let (px, py) = (px as u32, py as u32);
            if px >= img.width() || py >= img.height() {
                return;
            }
            let under = img.get_pixel(px, py).0;
            let a = coverage.clamp(0.0, 1.0);
            let mix =
                |k: usize| (f32::from(under[k]) * (1.0 - a) + f32::from(rgb[k]) * a).round() as u8;
            img.put_pixel(px, py, Rgb([mix(0), mix(1), mix(2)]));
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_512_comparison_of_17_methods_fits_2400_pixels() {
        let l = Layout::new(512, 512, 17, 3);
        assert_eq!(l.factor, 2);
        assert_eq!(l.cell, (256, 256));
        assert_eq!((l.columns, l.rows), (7, 3));
        assert!(l.width <= 2400, "{l:?}");
        // Tiles do not overlap, and the last one's last cell is inside the picture.
        let (x, y) = l.cell(16, 2);
        assert!(x + 256 <= l.width && y + 256 <= l.height - FOOTER_HEIGHT);
        assert!(l.tile(1).0 >= l.tile(0).0 + 256);
        assert!(l.tile(7).1 >= l.cell(0, 2).1 + 256);
        // Small images are not enlarged.
        assert_eq!(Layout::new(72, 64, 3, 2).cell, (72, 64));
    }

    #[test]
    fn reduction_keeps_a_one_pixel_error() {
        // A 4×4 picture, one hot pixel, reduced by 2: its block shows it; the others average.
        let img = reduce(4, 4, 2, |i| {
            if i == 5 {
                Block::Worst(0.4, [255, 0, 0])
            } else if i >= 12 {
                Block::Masked
            } else {
                Block::Mean([100, 100, 100])
            }
        });
        assert_eq!(img.dimensions(), (2, 2));
        assert_eq!(img.get_pixel(0, 0).0, [255, 0, 0]);
        assert_eq!(img.get_pixel(1, 0).0, [100, 100, 100]);
        // The bottom-right block: two Mean pixels (row 2), two masked (row 3).
        assert_eq!(img.get_pixel(1, 1).0, [100, 100, 100]);
    }

    #[test]
    fn text_marks_pixels_and_stays_inside() {
        let font = FontRef::try_from_slice(FONT).expect("the embedded font parses");
        let mut img = RgbImage::from_pixel(60, 20, Rgb(BACKGROUND));
        text(
            &mut img,
            &font,
            "shadow-volume 0.05 %",
            (2, 2),
            12.0,
            TEXT,
            40,
        );
        let marked: Vec<(u32, u32)> = img
            .enumerate_pixels()
            .filter(|(_, _, p)| p.0 != BACKGROUND)
            .map(|(x, y, _)| (x, y))
            .collect();
        assert!(marked.len() > 30, "{} pixels", marked.len());
        assert!(
            marked.iter().all(|(x, _)| *x < 40),
            "clipped at the right edge"
        );
    }
}
