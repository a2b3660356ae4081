//! The convergence plot: RMSE against seconds, log-log, one line per series, as SVG and PNG.

use crate::converge::Report;
use crate::film::output::write_atomically;
use anyhow::{Context, anyhow};
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// Fonts tried for labels, in order (Debian/Ubuntu's fonts-dejavu-core provides the first).
const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/Library/Fonts/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

fn register_font() -> anyhow::Result<()> {
    static FONT: OnceLock<Result<(), String>> = OnceLock::new();
    FONT.get_or_init(|| {
        let bytes = FONT_PATHS
            .iter()
            .find_map(|p| std::fs::read(p).ok())
            .ok_or("no font for plot labels found: install fonts-dejavu-core")?;
        plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            Box::leak(bytes.into_boxed_slice()),
        )
        .map_err(|_| "the plot font is not a valid TrueType font".to_string())
    })
    .clone()
    .map_err(|e| anyhow!(e))
}

const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
];

fn draw<DB: DrawingBackend>(
    report: &Report,
    title: &str,
    root: DrawingArea<DB, plotters::coord::Shift>,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("cannot draw the plot: {e:?}");
    root.fill(&WHITE).map_err(err)?;
    let xs = report.rungs.iter().map(|r| r.seconds);
    let ys = report
        .rungs
        .iter()
        .map(|r| r.errors.rmse)
        .chain(report.reference.noise_rmse);
    // A log axis needs positive, finite ends (plotters' never ends its ticks on a degenerate
    // range): errors of 0 (a black scene, or renders equal to their reference) have no place.
    let (x0, x1) = log_range(xs).ok_or_else(|| anyhow!("no render took a measurable time"))?;
    let (y0, y1) = log_range(ys).ok_or_else(|| {
        anyhow!(
            "every render's error is 0 (the scene renders exactly as its reference, black say): nothing to draw on a log scale"
        )
    })?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x0 * 0.8..x1 * 1.25).log_scale(),
            (y0 * 0.8..y1 * 1.25).log_scale(),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("seconds")
        .y_desc("RMSE against the reference")
        .x_label_formatter(&|v| compact(*v))
        .y_label_formatter(&|v| compact(*v))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    for (i, (series, fit)) in report.fits.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let points: Vec<(f64, f64)> = report
            .rungs
            .iter()
            .filter(|r| &r.series == series)
            .map(|r| (r.seconds, r.errors.rmse))
            .filter(|&(x, y)| x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite())
            .collect();
        let label = match fit {
            Some(f) => format!("{series} (exponent {:+.2})", f.exponent),
            None => series.clone(),
        };
        chart
            .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
            .map_err(err)?;
    }
    if let Some(floor) = report.reference.noise_rmse {
        chart
            .draw_series(LineSeries::new(
                vec![(x0 * 0.8, floor), (x1 * 1.25, floor)],
                BLACK.mix(0.4),
            ))
            .map_err(err)?
            .label("reference noise")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.4)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// The smallest and largest positive, finite values of `values`, apart by a factor of 2 at
/// least (a log axis of any length); `None` if none is positive and finite.
fn log_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    if lo > hi {
        return None;
    }
    let middle = (lo * hi).sqrt();
    Some((lo.min(middle / 2.0), hi.max(middle * 2.0)))
}

/// A short axis label: 0.25, 3, 1e-4.
fn compact(v: f64) -> String {
    if (0.01..10_000.0).contains(&v.abs()) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.0e}")
    }
}

/// Writes `stem.svg` and `stem.png` (atomically).
pub fn write_plot(report: &Report, title: &str, stem: &Path) -> anyhow::Result<()> {
    register_font()?;
    if report.rungs.is_empty() {
        return Err(anyhow!("nothing to plot"));
    }
    let (w, h) = (900u32, 600u32);
    let mut svg = String::new();
    draw(
        report,
        title,
        SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area(),
    )?;
    write_atomically(&stem.with_extension("svg"), |out| {
        use std::io::Write;
        Ok(out.write_all(svg.as_bytes())?)
    })?;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    draw(
        report,
        title,
        BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area(),
    )?;
    let img = image::RgbImage::from_raw(w, h, rgb).context("plot buffer size")?;
    write_atomically(&stem.with_extension("png"), |out| {
        Ok(img.write_to(out, image::ImageFormat::Png)?)
    })
}
