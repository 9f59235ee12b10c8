//! PNG of the XY path a capture's steps trace (the first two mapped axes that step), each
//! 5 ms piece coloured by the path speed over it: a CAM job's shape and where it slows down.
//! (A piece's speed is its whole steps over 5 ms, so it reads within one step per 5 ms.)

use std::path::Path;

use anyhow::{anyhow, Result};
use plotters::prelude::*;

use crate::plot::register;
use crate::trace::Trace;

/// One piece ([`PIECE_PS`]): start and end position (units) and its speed (units/min).
pub type Piece = ((f64, f64), (f64, f64), f64);

/// Length of a piece: 5 ms, in ps.
pub const PIECE_PS: u64 = 5_000_000_000;

/// The path of axes `x` and `y` in [`PIECE_PS`] pieces, positions in steps / `per_unit`.
pub fn pieces(trace: &Trace, x: usize, y: usize, per_unit: f64) -> Vec<Piece> {
    const MS: u64 = PIECE_PS;
    let (Some(start), ends) = (trace.first_step_ps(), trace.end_ps) else { return Vec::new() };
    let mut pos = [0i64; 2];
    let mut next = [0usize; 2];
    let mut out = Vec::new();
    let mut t = start - start % MS;
    let unit = |p: [i64; 2]| (p[0] as f64 / per_unit, p[1] as f64 / per_unit);
    while t <= ends {
        let from = unit(pos);
        let start = t;
        t += MS;
        for (k, axis) in [x, y].into_iter().enumerate() {
            let steps = &trace.axes[axis].steps;
            while next[k] < steps.len() && steps[next[k]].0 < t {
                pos[k] += steps[next[k]].1 as i64;
                next[k] += 1;
            }
        }
        let to = unit(pos);
        // the capture's last piece may be shorter
        let span = (t.min(ends.max(start + 1)) - start) as f64;
        let speed = ((to.0 - from.0).powi(2) + (to.1 - from.1).powi(2)).sqrt() * 60.0e12 / span;
        out.push((from, to, speed));
        if next[0] == trace.axes[x].steps.len() && next[1] == trace.axes[y].steps.len() {
            break;
        }
    }
    out
}

// blue (slow) through cyan, green and yellow to red (fast)
fn colour(speed: f64, max: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [(0.0, 0.0, 255.0), (0.0, 200.0, 255.0), (0.0, 190.0, 0.0), (240.0, 200.0, 0.0), (230.0, 0.0, 0.0)];
    let f = if max > 0.0 { (speed / max).clamp(0.0, 1.0) * 4.0 } else { 0.0 };
    let i = (f as usize).min(3);
    let (a, b, w) = (STOPS[i], STOPS[i + 1], f - i as f64);
    let mix = |p: f64, q: f64| (p + (q - p) * w).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Draws the XY path of the first two stepping axes into `path`; `unit` names the position unit.
/// Returns the top speed (units/min).
pub fn write_png(trace: &Trace, per_unit: f64, unit: &str, title: &str, path: &Path) -> Result<f64> {
    let stepping: Vec<usize> = (0..trace.axes.len()).filter(|&i| !trace.axes[i].steps.is_empty()).collect();
    let [x, y] = match stepping[..] {
        [x, y, ..] => [x, y],
        _ => return Err(anyhow!("a path needs two axes that step")),
    };
    let pieces = pieces(trace, x, y, per_unit);
    register();
    let root = BitMapBackend::new(path, (900, 800)).into_drawing_area();
    draw(trace, &pieces, [x, y], unit, title, &root).map_err(|e| anyhow!("cannot draw {}: {e}", path.display()))?;
    root.present().map_err(|e| anyhow!("cannot write {}: {e}", path.display()))?;
    Ok(pieces.iter().map(|p| p.2).fold(0.0, f64::max))
}

// the path, equal scales on both axes, and a speed scale
fn draw<DB: DrawingBackend>(
    trace: &Trace,
    pieces: &[Piece],
    [x, y]: [usize; 2],
    unit: &str,
    title: &str,
    root: &DrawingArea<DB, plotters::coord::Shift>,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let max = pieces.iter().map(|p| p.2).fold(0.0, f64::max);
    let pts = pieces.iter().flat_map(|p| [p.0, p.1]);
    let (mut x0, mut x1, mut y0, mut y1) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (px, py) in pts {
        (x0, x1, y0, y1) = (x0.min(px), x1.max(px), y0.min(py), y1.max(py));
    }
    // equal scales: the larger span on both, with a margin
    let span = (x1 - x0).max(y1 - y0).max(1e-9) * 1.1;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    root.fill(&WHITE)?;
    let root = root.titled(&format!("{title}: XY path speed 0 (blue) to {max:.0} {unit}/min (red)"), ("sans-serif", 18))?;
    let mut chart = ChartBuilder::on(&root)
        .margin(16)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(cx - span / 2.0..cx + span / 2.0, cy - span / 2.0..cy + span / 2.0)?;
    chart
        .configure_mesh()
        .x_desc(format!("{} ({unit})", trace.axes[x].name))
        .y_desc(format!("{} ({unit})", trace.axes[y].name))
        .label_style(("sans-serif", 14))
        .draw()?;
    for &(from, to, speed) in pieces {
        chart.draw_series(LineSeries::new([from, to], colour(speed, max).stroke_width(3)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::AxisChannels;
    use crate::levels::Sink;

    #[test]
    fn pieces_follow_the_steps_and_their_speed() {
        // X steps + every 0.5 ms for 10 ms (2 kHz), Y none: 10 steps a piece of 5 ms.
        let mut t = Trace::new(&[AxisChannels::new("X", 0, None), AxisChannels::new("Y", 1, None)], false);
        t.level(0, 0, false);
        t.level(0, 1, false);
        for k in 0..20u64 {
            let at = 1_000_000 + k * 500_000_000;
            t.level(at, 0, true);
            t.level(at + 10_000_000, 0, false);
        }
        t.advance(10_100_000_000);
        let p = pieces(&t, 0, 1, 10.0);
        assert_eq!(p.len(), 2);
        assert_eq!(p[0], ((0.0, 0.0), (1.0, 0.0), 12_000.0)); // 1 unit in 5 ms
        assert_eq!(p[1].1, (2.0, 0.0));
    }
}
