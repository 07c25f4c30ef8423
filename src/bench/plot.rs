//! The geometry-scaling plot: milliseconds against caster triangles, log-log, as a PNG.
//!
//! Drawn with plotters into an RGB buffer (its bitmap backend, no encoder of its own) and encoded
//! with the crate's `image`; text is DejaVu Sans embedded from `assets/fonts/` (ab_glyph), so the
//! plot looks the same on every machine and needs no system fonts.

use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use super::{BenchError, ScalingPoint};

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
/// The family name the plot asks for; "sans-serif" too, plotters' default.
pub(crate) const FAMILY: &str = "dejavu-sans";

/// Register the embedded font with plotters under [`FAMILY`] (once); whether it parsed. The
/// plots of `compare --orbit` draw with it too.
pub(crate) fn register_fonts() -> bool {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    *REGISTERED.get_or_init(|| {
        register_font(FAMILY, FontStyle::Normal, FONT).is_ok()
            && register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    })
}

fn fonts() -> Result<(), BenchError> {
    if register_fonts() {
        Ok(())
    } else {
        Err(BenchError::Plot("the embedded font does not parse".into()))
    }
}

fn plot_err(e: impl std::fmt::Display) -> BenchError {
    BenchError::Plot(e.to_string())
}

/// Powers of ten that bracket `lo..hi` (both positive).
fn decades(lo: f64, hi: f64) -> (f64, f64) {
    let lo = 10f64.powf(lo.max(1e-9).log10().floor());
    let mut hi = 10f64.powf(hi.max(1e-9).log10().ceil());
    if hi <= lo {
        hi = lo * 10.0;
    }
    (lo, hi)
}

/// The plot as PNG bytes, `width`×`height` pixels: per light move (classes, silhouettes,
/// volumes) and once per mesh (adjacency), with a 1 ms line.
pub fn scaling_png(
    points: &[ScalingPoint],
    width: u32,
    height: u32,
) -> Result<Vec<u8>, BenchError> {
    if points.is_empty() {
        return Err(BenchError::Plot("no scaling points to plot".into()));
    }
    if !(200..=8192).contains(&width) || !(150..=8192).contains(&height) {
        return Err(BenchError::Plot(format!(
            "plot size {width}x{height}: expected 200x150 to 8192x8192"
        )));
    }
    fonts()?;
    let build: Vec<(f64, f64)> = points
        .iter()
        .map(|p| (p.triangles as f64, p.build_ms.median.max(1e-4)))
        .collect();
    let prepare: Vec<(f64, f64)> = points
        .iter()
        .map(|p| (p.triangles as f64, p.prepare_ms.max(1e-4)))
        .collect();
    let xs = build.iter().map(|p| p.0);
    let ys = build.iter().chain(&prepare).map(|p| p.1);
    let (x0, x1) = decades(
        xs.clone().fold(f64::INFINITY, f64::min),
        xs.fold(0.0, f64::max),
    );
    let (y0, y1) = decades(
        ys.clone().fold(f64::INFINITY, f64::min).min(1.0),
        ys.fold(0.0, f64::max).max(1.0),
    );

    let mut buffer = vec![0u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Geometry stage: milliseconds against caster triangles",
                (FAMILY, 20),
            )
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("caster triangles")
            .y_desc("milliseconds (CPU)")
            .axis_desc_style((FAMILY, 16))
            .label_style((FAMILY, 13))
            .x_label_formatter(&|x| format_count(*x))
            .y_label_formatter(&|y| format_ms(*y))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(plot_err)?;

        let blue = RGBColor(31, 100, 180);
        let orange = RGBColor(220, 120, 30);
        chart
            .draw_series(LineSeries::new(build.clone(), blue.stroke_width(2)))
            .map_err(plot_err)?
            .label("classes + silhouettes + volumes (per light move)")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], blue.stroke_width(2))
            });
        chart
            .draw_series(build.iter().map(|&p| Circle::new(p, 4, blue.filled())))
            .map_err(plot_err)?;
        chart
            .draw_series(LineSeries::new(prepare.clone(), orange.stroke_width(2)))
            .map_err(plot_err)?
            .label("welding + adjacency (once per mesh)")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], orange.stroke_width(2))
            });
        chart
            .draw_series(
                prepare
                    .iter()
                    .map(|&p| TriangleMarker::new(p, 5, orange.filled())),
            )
            .map_err(plot_err)?;
        let red = RGBColor(190, 40, 40);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x0, 1.0), (x1, 1.0)],
                8,
                5,
                red.stroke_width(1),
            ))
            .map_err(plot_err)?
            .label("1 ms")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], red));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FAMILY, 13))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK.mix(0.3))
            .draw()
            .map_err(plot_err)?;
        root.present().map_err(plot_err)?;
    }
    let img = image::RgbImage::from_raw(width, height, buffer)
        .ok_or_else(|| BenchError::Plot("plot buffer has the wrong size".into()))?;
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(plot_err)?;
    Ok(png)
}

/// 1000 → "1k", 1e6 → "1M".
fn format_count(x: f64) -> String {
    if x >= 1e6 {
        format!("{}M", trim(x / 1e6))
    } else if x >= 1e3 {
        format!("{}k", trim(x / 1e3))
    } else {
        trim(x)
    }
}

fn format_ms(y: f64) -> String {
    if y >= 1.0 {
        trim(y)
    } else {
        format!("{y}")
    }
}

fn trim(v: f64) -> String {
    let s = format!("{v:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::Stat;

    #[test]
    fn labels_and_decades() {
        assert_eq!(format_count(1000.0), "1k");
        assert_eq!(format_count(1_048_576.0), "1.05M");
        assert_eq!(format_ms(10.0), "10");
        assert_eq!(decades(1024.0, 262_144.0), (1000.0, 1e6));
        assert_eq!(decades(0.02, 0.5), (0.01, 1.0));
    }

    #[test]
    fn plot_is_a_png_with_ink() {
        let points: Vec<ScalingPoint> = [1024usize, 16384, 262_144]
            .iter()
            .map(|&t| ScalingPoint {
                triangles: t,
                prepare_ms: t as f64 * 3e-4,
                build_ms: Stat {
                    median: t as f64 * 3e-5,
                    min: t as f64 * 2e-5,
                },
                volume_triangles: t / 10,
                cpu_move_ms: None,
                gpu_move_ms: None,
            })
            .collect();
        let png = scaling_png(&points, 640, 420).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (640, 420));
        let blue = img.pixels().filter(|p| p[2] > 150 && p[0] < 80).count();
        let dark = img
            .pixels()
            .filter(|p| p[0] < 100 && p[1] < 100 && p[2] < 100)
            .count();
        assert!(blue > 200, "the series is drawn ({blue} blue pixels)");
        assert!(dark > 500, "axes and labels are drawn ({dark} dark pixels)");
        assert!(scaling_png(&[], 640, 420).is_err());
    }
}
