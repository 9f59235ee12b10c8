//! Measuring one sweep point: boot a fresh board in the mode, send the sweep settings and one
//! `G1` for the target master rate, then judge the measured cruise windows (see `mod.rs`).

use std::path::Path;

use anyhow::{bail, Context, Result};

use super::point::{overruns_text, Point, Verdict};
use super::setup::{settings_lines, Mode, RATIO, STEPS_PER_MM};
use crate::emu::board::Board;
use crate::emu::clock::HZ;
use crate::emu::nvic::IRQ0;
use crate::emu::report::{AXES, STEP_PINS};
use crate::emu::stats::WINDOW;

/// A booted board with the sweep settings applied and what `$I` said.
pub(super) struct Prepared {
    board: Board,
    pub(super) cap_hz: u32,
    accel_hz_s: u32,
}

/// A booted board in `mode` (each mode setting applies in place: its `ok` only).
pub fn boot(elf: &Path, mode: Mode) -> Result<Board> {
    let mut board = Board::load(elf)?;
    board.run_until(HZ / 2, |b| b.serial_output().ends_with("help]\r\n"))?;
    for line in mode.lines() {
        let r = board.send_line_wait_ok(line)?;
        if r.trim_end() != "ok" {
            bail!("{line}: {r:?}");
        }
    }
    board.dual_edge = mode.dual_edge;
    if mode.dma {
        board.step_irq = crate::emu::dma::IRQ_CHANNEL1;
    }
    Ok(board)
}

// reset a board from `elf`, boot it, send the settings and `$I`
pub(super) fn prepare(elf: &Path, mode: Mode) -> Result<Prepared> {
    let mut board = boot(elf, mode)?;
    for line in settings_lines() {
        board.send_line_wait_ok(&line)?;
    }
    let info = board.send_line_wait_ok("$I")?;
    let cap_hz = number_after(&info, "max step rate ").context("no max step rate in $I")?;
    let accel_hz_s = info
        .split("[MSG:ramp ")
        .nth(1)
        .and_then(|r| r.split(" Hz ").nth(1))
        .and_then(|r| r.split(' ').next()?.parse().ok())
        .context("no ramp acceleration in $I")?;
    board.send_line_wait_ok("G91")?;
    Ok(Prepared { board, cap_hz, accel_hz_s })
}

fn number_after(text: &str, key: &str) -> Option<u32> {
    let rest = &text[text.find(key)? + key.len()..];
    rest[..rest.find(|c: char| !c.is_ascii_digit())?].parse().ok()
}

/// The move for a point: steps per axis and the `G1` line.
fn move_line(axes: usize, target_hz: u32, master_steps: u64) -> (Vec<u64>, String) {
    let steps: Vec<u64> = RATIO[..axes].iter().map(|r| master_steps * r / 10).collect();
    let mm: Vec<f64> = steps.iter().map(|&s| s as f64 / STEPS_PER_MM).collect();
    let path = mm.iter().map(|m| m * m).sum::<f64>().sqrt();
    let seconds = master_steps as f64 / target_hz as f64;
    let feed = path / seconds * 60.0;
    let mut line = "G1".to_string();
    for (name, m) in AXES.iter().zip(&mm) {
        line += &format!(" {name}{m}");
    }
    line += &format!(" F{feed:.4}");
    (steps, line)
}

// run one point: reset, settings, the move, measurements
pub fn run_point(elf: &Path, axes: usize, target_hz: u32, cruise_ms: u64, max_load: f64, profile: bool, mode: Mode) -> Point {
    let wall = std::time::Instant::now();
    let mut p = match measure(elf, axes, target_hz, cruise_ms, max_load, profile, mode) {
        Ok(p) => p,
        Err(e) => Point::failed(axes, target_hz, Verdict::Error(format!("{e:#}"))),
    };
    p.wall_s = wall.elapsed().as_secs_f64();
    p
}

fn measure(elf: &Path, axes: usize, target_hz: u32, cruise_ms: u64, max_load: f64, profile: bool, mode: Mode) -> Result<Point> {
    let dual_edge = mode.dual_edge;
    let Prepared { mut board, accel_hz_s, .. } = prepare(elf, mode)?;
    // Ramp: whole table entries of 1 ms, from the 1 kHz start, at the move's acceleration:
    // `$I` gives the table's, which is twice the largest axis's (a move walks it at its own
    // axes' share; with the sweep's equal `$120`s exactly half).
    let ramp_ms = ((target_hz as u64).saturating_sub(1000) * 1000).div_ceil((accel_hz_s / 2).max(1) as u64) + 1;
    let cruise_total_ms = cruise_ms + ramp_ms + 6;
    let master = (target_hz as u64 * cruise_total_ms / 1000).div_ceil(10) * 10;
    let (steps, line) = move_line(axes, target_hz, master);
    let overruns0 = board.overruns();
    let edges0 = board.edges().len();
    board.send_line_wait_ok(&line)?;
    // The first X step starts the clock.
    let x_pin = STEP_PINS[0];
    let started = board.run_until(HZ / 20, |b| b.edges()[edges0..].iter().any(|e| e.port == 1 && e.pin == x_pin && (e.level || dual_edge)))?;
    if !started {
        bail!("no X step within 50 ms of {line:?}");
    }
    let x0 = board.edges()[edges0..].iter().find(|e| e.port == 1 && e.pin == x_pin && (e.level || dual_edge)).unwrap().cycle;
    let w0 = (x0 + (ramp_ms + 2) * WINDOW).div_ceil(WINDOW);
    let w1 = w0 + cruise_ms;
    board.run_until_cycle(w0 * WINDOW)?;
    board.reset_step_isr_stats();
    board.set_profile(profile);
    board.run_until_cycle(w1 * WINDOW)?;
    let isr = board.step_isr();
    let prof = if profile { board.profile(IRQ0 + board.step_irq) } else { Vec::new() };
    let blocks = if profile { board.profile_blocks(IRQ0 + board.step_irq) } else { Vec::new() };
    let thread = if profile { board.profile(0) } else { Vec::new() };
    board.set_profile(false);
    // Run until the move is over: no step edge for 2 ms.
    let expected_end = x0 + (master as f64 / target_hz as f64 * HZ as f64) as u64 + HZ / 100;
    while board.cycles() < expected_end + HZ / 2 {
        let last = board.edges().last().map_or(0, |e| e.cycle);
        if board.cycles() > expected_end && board.cycles() > last + HZ / 500 {
            break;
        }
        board.run_for(HZ / 1000)?;
    }
    // X edges per measured window.
    let mut per_window: Vec<Vec<u64>> = vec![Vec::new(); cruise_ms as usize];
    let mut x_steps = 0u64;
    for e in &board.edges()[edges0..] {
        if e.port == 1 && e.pin == x_pin && (e.level || dual_edge) && e.cycle >= w0 * WINDOW && e.cycle < w1 * WINDOW {
            per_window[(e.cycle / WINDOW - w0) as usize].push(e.cycle);
            x_steps += 1;
        }
    }
    let rate = |t: &[u64]| if t.len() < 2 { 0.0 } else { (t.len() - 1) as f64 * HZ as f64 / (t[t.len() - 1] - t[0]) as f64 };
    let slowest = per_window.iter().map(|t| rate(t)).fold(f64::INFINITY, f64::min);
    let fastest = per_window.iter().map(|t| rate(t)).fold(0.0, f64::max);
    let in_cruise = |r: f64| (r - target_hz as f64).abs() <= 0.01 * target_hz as f64;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let loads = board.window_loads(w0..w1);
    let isr_loads = board.window_isr_loads(w0..w1);
    let report = board.report();
    let overruns = board.overruns() - overruns0;
    let mut wrong = Vec::new();
    for (i, &want) in steps.iter().enumerate() {
        let a = &report.axes.0[i].1;
        if a.rising_edges != want || a.net_steps != want as i64 {
            wrong.push(format!("{} {}/{} net {}", AXES[i], a.rising_edges, want, a.net_steps));
        }
    }
    for (name, a) in &report.axes.0[axes..] {
        if a.rising_edges != 0 {
            wrong.push(format!("{name} moved {}", a.rising_edges));
        }
    }
    let verdict = |load_max: f64| {
        if !wrong.is_empty() {
            let also = if overruns > 0 { format!(" ({})", overruns_text(overruns)) } else { String::new() };
            Verdict::Counts(wrong.join(", ") + &also)
        } else if overruns > 0 {
            Verdict::Overrun(overruns)
        } else if !in_cruise(slowest) || !in_cruise(fastest) {
            Verdict::NoCruise(if in_cruise(slowest) { fastest } else { slowest })
        } else if load_max > max_load {
            Verdict::Load(load_max)
        } else {
            Verdict::Ok
        }
    };
    let span = (w1 - w0) * WINDOW;
    Ok(Point {
        axes,
        target_hz,
        verdict: verdict(max(&loads)),
        isr_verdict: verdict(max(&isr_loads)),
        cruise_hz: x_steps as f64 * HZ as f64 / span as f64,
        windows: cruise_ms as usize,
        load_mean: mean(&loads),
        load_max: max(&loads),
        isr_load_mean: mean(&isr_loads),
        isr_load_max: max(&isr_loads),
        overruns,
        isr_entries: isr.entries,
        isr_mean_cycles: isr.mean_cycles,
        isr_max_cycles: isr.max_cycles,
        isr_cycles_per_step: isr.total_cycles as f64 / x_steps.max(1) as f64,
        bsrr_min: isr.bsrr_offset_min_cycles,
        bsrr_max: isr.bsrr_offset_max_cycles,
        min_high_ns: report.axes.0[0].1.min_high_ns,
        profile: prof,
        profile_blocks: blocks.into_iter().map(|(n, c)| (n, c.runs, c.cycles)).collect(),
        profile_thread: thread,
        sim_s: board.seconds(),
        wall_s: 0.0,
    })
}
