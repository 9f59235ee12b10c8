//! PNG plot of a [`Report`]: step rate of every axis over time, and each slave's deviation from
//! the ideal line of the master. Draws with plotters' bitmap backend and an embedded font
//! (DejaVu Sans, ASCII subset, under `bench/la/fixtures/font/`), so it needs no system fonts.

use std::path::Path;
use std::sync::Once;

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use super::Report;

static FONT: &[u8] = include_bytes!("../fixtures/font/DejaVuSans-ascii.ttf");
pub(crate) const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

// make the embedded font plotters' "sans-serif"
pub(crate) fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in and known good; a failure would only lose the labels.
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

// draw the rate and deviation charts of `report` into a PNG file
pub fn write_png(report: &Report, title: &str, path: &Path) -> Result<()> {
    register();
    let root = BitMapBackend::new(path, (1200, 800)).into_drawing_area();
    draw(report, title, &root).map_err(|e| anyhow!("cannot draw {}: {e}", path.display()))?;
    root.present()
        .map_err(|e| anyhow!("cannot write {}: {e}", path.display()))?;
    Ok(())
}

// the two charts, top rate and bottom deviation
fn draw<DB: DrawingBackend>(
    report: &Report,
    title: &str,
    root: &DrawingArea<DB, plotters::coord::Shift>,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    // Long titles (big counts, a mismatch) get a smaller font to fit 1200 px.
    let size = if title.chars().count() > 90 { 15 } else { 20 };
    let root = root.titled(title, ("sans-serif", size))?;
    let (top, bottom) = root.split_vertically(460);
    let bins = report.series.rate_hz.first().map_or(0, Vec::len);
    let x_end = (bins.max(1) as f64) * report.bin_ms;

    let max_khz = report
        .axes
        .iter()
        .map(|a| a.max_rate_hz / 1e3)
        .fold(0.0, f64::max);
    let mut rate = ChartBuilder::on(&top)
        .caption("step rate per axis", ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..x_end, 0.0..(max_khz * 1.1).max(1.0))?;
    rate.configure_mesh()
        .x_desc("time (ms)")
        .y_desc("rate (kHz)")
        .label_style(("sans-serif", 14))
        .draw()?;
    for (i, axis) in report.axes.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        // A bin's rate is drawn at its middle.
        let points = report.series.rate_hz[i]
            .iter()
            .enumerate()
            .map(|(b, &r)| ((b as f64 + 0.5) * report.bin_ms, r / 1e3));
        rate.draw_series(LineSeries::new(points, color.stroke_width(2)))?
            .label(format!("{} ({} steps)", axis.name, axis.steps))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
            });
    }
    rate.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;

    let deviations = &report.series.deviation_steps;
    let extent = deviations
        .iter()
        .flatten()
        .fold(0.5f64, |m, d| m.max(d.abs()))
        * 1.2;
    let master = report
        .master
        .map_or("none".to_string(), |m| report.axes[m].name.clone());
    let mut dev = ChartBuilder::on(&bottom)
        .caption(
            format!("slave - ideal (steps), master {master}"),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..x_end, -extent..extent)?;
    dev.configure_mesh()
        .x_desc("time (ms)")
        .y_desc("deviation (steps)")
        .y_label_formatter(&|v| format!("{:.2}", if v.abs() < 1e-9 { 0.0 } else { *v }))
        .label_style(("sans-serif", 14))
        .draw()?;
    for (i, axis) in report.axes.iter().enumerate() {
        if deviations[i].is_empty() {
            continue;
        }
        let color = PALETTE[i % PALETTE.len()];
        // A bin's deviation is the one at its end.
        let points = deviations[i]
            .iter()
            .enumerate()
            .map(|(b, &d)| ((b as f64 + 1.0) * report.bin_ms, d));
        dev.draw_series(LineSeries::new(points, color.stroke_width(2)))?
            .label(format!(
                "{} max {:.2}",
                axis.name,
                axis.max_deviation_steps.unwrap_or(0.0)
            ))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
            });
    }
    if deviations.iter().any(|d| !d.is_empty()) {
        dev.configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()?;
    }
    Ok(())
}
