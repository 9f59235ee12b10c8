//! PNG of the step lines as a logic analyzer shows them, over a short window: the axes that
//! step, one trace each, with the rising edges counted in the title (the 5:3:2 pattern of the
//! seed paper's move shows as 5, 3 and 2 pulses per five master periods).

use std::path::Path;

use anyhow::{anyhow, Result};
use plotters::prelude::*;

use crate::plot::{register, PALETTE};
use crate::trace::Trace;

/// Draws the step lines of the axes that step from `from_ps` for `len_ps` into `path`.
pub fn write_png(trace: &Trace, from_ps: u64, len_ps: u64, title: &str, path: &Path) -> Result<()> {
    register();
    let root = BitMapBackend::new(path, (1200, 420)).into_drawing_area();
    draw(trace, from_ps, len_ps, title, &root).map_err(|e| anyhow!("cannot draw {}: {e}", path.display()))?;
    root.present().map_err(|e| anyhow!("cannot write {}: {e}", path.display()))?;
    Ok(())
}

/// The level of a line at `t` from its level changes.
fn level_at(levels: &[(u64, bool)], t: u64) -> bool {
    match levels.partition_point(|&(at, _)| at <= t) {
        0 => levels.first().is_some_and(|l| l.1),
        i => levels[i - 1].1,
    }
}

/// Rising edges of an axis in `[from, to)`.
pub fn rising_in(trace: &Trace, axis: usize, from_ps: u64, to_ps: u64) -> usize {
    trace.axes[axis].steps.iter().filter(|s| (from_ps..to_ps).contains(&s.0)).count()
}

// one square wave per stepping axis, top to bottom in ratio order
fn draw<DB: DrawingBackend>(
    trace: &Trace,
    from_ps: u64,
    len_ps: u64,
    title: &str,
    root: &DrawingArea<DB, plotters::coord::Shift>,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let to_ps = from_ps + len_ps;
    let shown: Vec<usize> = (0..trace.axes.len()).filter(|&i| !trace.axes[i].steps.is_empty()).collect();
    let counts: Vec<String> =
        shown.iter().map(|&i| format!("{} {}", trace.axes[i].name, rising_in(trace, i, from_ps, to_ps))).collect();
    root.fill(&WHITE)?;
    let root = root.titled(&format!("{title}: rising edges {}", counts.join(", ")), ("sans-serif", 18))?;
    let us = |t: u64| (t as f64 - from_ps as f64) / 1e6;
    let rows = shown.len().max(1) as f64;
    let mut chart = ChartBuilder::on(&root)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..us(to_ps), -0.3..rows)?;
    let names: Vec<String> = shown.iter().map(|&i| format!("{}_STEP", trace.axes[i].name)).collect();
    chart
        .configure_mesh()
        .disable_y_mesh()
        .x_desc("time (µs)".replace('µ', "u"))
        .y_labels(shown.len() * 2 + 1)
        .y_label_formatter(&|v| {
            let row = (rows - 1.0 - v.floor()) as usize;
            if (v - v.floor() - 0.4).abs() < 0.26 && v.floor() >= 0.0 {
                names.get(row).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .label_style(("sans-serif", 14))
        .draw()?;
    for (row, &i) in shown.iter().enumerate() {
        let base = rows - 1.0 - row as f64;
        let levels = &trace.axes[i].step_levels;
        let y = |l: bool| base + if l { 0.7 } else { 0.0 };
        let mut points = vec![(0.0, y(level_at(levels, from_ps)))];
        for &(t, l) in levels.iter().filter(|(t, _)| (from_ps..to_ps).contains(t)) {
            let last = points.last().map_or(0.0, |p| p.1);
            points.push((us(t), last));
            points.push((us(t), y(l)));
        }
        let last = points.last().map_or(0.0, |p| p.1);
        points.push((us(to_ps), last));
        chart.draw_series(LineSeries::new(points, PALETTE[i % PALETTE.len()].stroke_width(2)))?;
    }
    Ok(())
}
