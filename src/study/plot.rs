//! A scene's plot: error against frame milliseconds, both axes logarithmic; each method a line
//! through its settings (cheapest first), the front of the cells nothing beats drawn through
//! them in black, the D-buffer's frame and the reference's noise floor as dashed guides. Drawn
//! with plotters into an RGB buffer and encoded as PNG, text in the embedded DejaVu Sans (as the
//! bench's plot).

use plotters::prelude::*;

use super::front::{dbuffer_frame, front, points, ErrorAxis};
use super::run::SceneStudy;
use crate::bench::plot::{register_fonts, FAMILY};

/// Colours of the methods, in registry order (cycled past the twentieth).
pub const PALETTE: [(u8, u8, u8); 20] = [
    (31, 100, 180),
    (220, 120, 30),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
    (57, 59, 121),
    (99, 121, 57),
    (140, 109, 49),
    (132, 60, 57),
    (123, 65, 115),
    (82, 84, 163),
    (181, 207, 107),
    (231, 186, 82),
    (214, 97, 107),
    (206, 109, 189),
];

/// The colour of the method at `index` in the registry.
pub fn colour(index: usize) -> (u8, u8, u8) {
    PALETTE[index % PALETTE.len()]
}

/// Errors below this are drawn at it (a log axis has no 0: the reference against itself).
pub const LEAST_ERROR: f64 = 1e-4;

fn decades(lo: f64, hi: f64) -> (f64, f64) {
    let lo = 10f64.powf(lo.max(1e-9).log10().floor());
    let mut hi = 10f64.powf(hi.max(1e-9).log10().ceil());
    if hi <= lo {
        hi = lo * 10.0;
    }
    (lo, hi)
}

fn plot_err(e: impl std::fmt::Display) -> String {
    format!("drawing the study's plot failed: {e}")
}

/// The plot of `scene` by `axis` as PNG bytes, `width`×`height` pixels; `map_size` names the
/// D-buffer's own frame (its cell at the study's map size).
pub fn scene_png(
    scene: &SceneStudy,
    axis: ErrorAxis,
    map_size: u32,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, String> {
    if !register_fonts() {
        return Err("the embedded font does not parse".into());
    }
    let pts = points(scene, axis);
    if pts.is_empty() {
        return Err(format!("{}: no cell was measured both ways", scene.name));
    }
    let ys = pts.iter().map(|p| p.error.max(LEAST_ERROR));
    let (x0, x1) = decades(
        pts.iter().map(|p| p.cost).fold(f64::INFINITY, f64::min),
        pts.iter().map(|p| p.cost).fold(0.0, f64::max),
    );
    let floor = scene.noise_floor.max(LEAST_ERROR);
    let (y0, y1) = decades(
        ys.clone().fold(f64::INFINITY, f64::min).min(floor),
        ys.fold(0.0, f64::max),
    );
    let mut buffer = vec![0u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{}: {} against frame time", scene.name, axis.label()),
                (FAMILY, 20),
            )
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("frame ms (GPU passes; wall for CPU-side methods), log")
            .y_desc(format!("{} against the reference, log", axis.label()))
            .axis_desc_style((FAMILY, 15))
            .label_style((FAMILY, 12))
            .x_label_formatter(&|x| short(*x))
            .y_label_formatter(&|y| short(*y))
            .light_line_style(RGBColor(236, 236, 236))
            .draw()
            .map_err(plot_err)?;
        let grey = RGBColor(120, 120, 120);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x0, floor), (x1, floor)],
                6,
                4,
                grey.stroke_width(1),
            ))
            .map_err(plot_err)?
            .label(format!("reference noise floor ({floor:.4})"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], grey));
        if let Some(ms) = dbuffer_frame(scene, map_size) {
            for times in [1.0, 2.0, 4.0] {
                let x = ms * times;
                if x > x0 && x < x1 {
                    chart
                        .draw_series(DashedLineSeries::new(
                            vec![(x, y0), (x, y1)],
                            3,
                            5,
                            RGBColor(170, 170, 170).stroke_width(1),
                        ))
                        .map_err(plot_err)?;
                }
            }
        }
        // Each method's settings, cheapest first.
        let mut order: Vec<&str> = Vec::new();
        for p in &pts {
            let m = scene.cells[p.cell].method.as_str();
            if !order.contains(&m) {
                order.push(m);
            }
        }
        for m in order {
            // A user's method (not in the registry) takes the colour after the registry's.
            let index = crate::render::Method::all()
                .iter()
                .position(|x| x.name() == m)
                .unwrap_or(crate::render::Method::all().len());
            let (r, g, b) = colour(index);
            let c = RGBColor(r, g, b);
            let mut line: Vec<(f64, f64)> = pts
                .iter()
                .filter(|p| scene.cells[p.cell].method == m)
                .map(|p| (p.cost, p.error.max(LEAST_ERROR)))
                .collect();
            line.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))
                .map_err(plot_err)?
                .label(m)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(3))
                });
            chart
                .draw_series(line.iter().map(|&p| Circle::new(p, 4, c.filled())))
                .map_err(plot_err)?;
        }
        let f: Vec<(f64, f64)> = front(&pts)
            .iter()
            .map(|p| (p.cost, p.error.max(LEAST_ERROR)))
            .collect();
        chart
            .draw_series(LineSeries::new(f.clone(), BLACK.stroke_width(1)))
            .map_err(plot_err)?
            .label("front: nothing cheaper and better")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK));
        chart
            .draw_series(f.iter().map(|&p| Circle::new(p, 7, BLACK.stroke_width(1))))
            .map_err(plot_err)?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(200, 200, 200))
            .label_font((FAMILY, 12))
            .draw()
            .map_err(plot_err)?;
        root.present().map_err(plot_err)?;
    }
    let image = image::RgbImage::from_raw(width, height, buffer)
        .ok_or_else(|| "the plot's buffer has the wrong size".to_string())?;
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(plot_err)?;
    Ok(png)
}

/// A tick label: 0.003, 0.05, 1.5, 20, 300.
fn short(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.1}")
    } else {
        let digits = (-v.log10().floor()) as usize;
        format!("{v:.digits$}")
    }
}
