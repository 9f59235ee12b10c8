//! Moves changing at speed: back-to-back short moves at the firmware's own rate cap, and the
//! step interrupt's mean and longest run while they run (the goal: a move change costs a tick
//! no more than 1.3× the mean; figures in bench/RESULTS.md, "Moves changing at the rate cap").
//! Every figure is *modeled* (cycles of the emulated Cortex-M3, see bench/README.md).

use anyhow::{ensure, Result};

use super::sweep::setup::{settings_lines, PULSE_US, RATIO, STEPS_PER_MM};
use super::{Board, HZ};

/// A step-interrupt run is at speed when its update event came within this many cycles of
/// the one before (above 35 kHz).
pub const AT_SPEED_CYCLES: u64 = 2048;

/// Short moves after the long first one.
pub const MOVES: usize = 12;

/// What one run measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ChangeResult {
    pub axes: usize,
    /// The master rate asked for (Hz; above the cap the planner runs the moves at the cap).
    pub hz: f64,
    /// Step-interrupt runs at speed (their update event came within [`AT_SPEED_CYCLES`] of the
    /// one before) up to the chain's last step (excluded): count, mean and longest, modeled
    /// cycles.
    pub runs: usize,
    pub mean: f64,
    pub max: u64,
    /// The longest of them that made a move change: the tick of a move's last step (it finds
    /// the next move) and the next move's first (it enters it).
    pub max_change: u64,
    pub max_last: u64,
    pub max_first: u64,
    /// The longest run not at speed (a start from rest, a tick after a direction change's
    /// setup gap), and the run that ends the chain (its last step, then idle: no edge follows).
    pub max_start: u64,
    pub max_end: u64,
    /// Net steps asked for per axis, and rising step edges asked for in all.
    pub want: [i64; 7],
    pub rising: i64,
}

impl ChangeResult {
    /// Longest run at speed over the mean.
    pub fn ratio(&self) -> f64 {
        self.max as f64 / self.mean.max(1.0)
    }
}

/// The `G1` line (relative, the sweep's steps/mm) that moves `steps` per axis with the master,
/// the first axis, at `master_hz`.
pub fn g1_line(steps: &[i64], master_hz: f64) -> String {
    let mm: Vec<f64> = steps.iter().map(|&s| s as f64 / STEPS_PER_MM).collect();
    let path = mm.iter().map(|m| m * m).sum::<f64>().sqrt();
    let feed = path / (steps[0] as f64 / master_hz) * 60.0;
    let words: String = "XYZABCU".chars().zip(&mm).map(|(a, m)| format!(" {a}{m}")).collect();
    format!("G1{words} F{feed:.3}")
}

/// On a booted `board` (the sweep's settings are sent first: 0.5 µs pulses, the shortest
/// leave a long tick the least room): one long move, then [`MOVES`] short ones of 200 master
/// steps, queued while the long one runs so that each starts at speed, at master rate `hz` on
/// `axes` axes (steps in the sweep's ratio; on 2 and more axes Y reverses at every junction:
/// a direction change at speed). Runs until idle.
pub fn back_to_back(b: &mut Board, axes: usize, hz: f64) -> Result<ChangeResult> {
    back_to_back_at(b, axes, hz, PULSE_US)
}

/// [`back_to_back`] with pulses of `pulse_us` (`$0`) instead of the sweep's.
pub fn back_to_back_at(b: &mut Board, axes: usize, hz: f64, pulse_us: f64) -> Result<ChangeResult> {
    for l in settings_lines() {
        let r = b.send_line_wait_ok(&l)?;
        ensure!(r.contains("ok"), "{l}: {r}");
    }
    let r = b.send_line_wait_ok(&format!("$0={pulse_us}"))?;
    ensure!(r.contains("ok"), "$0: {r}");
    ensure!(b.send_line_wait_ok("G91")?.contains("ok"));
    let mut want = [0i64; 7];
    let mut rising = 0i64;
    b.set_isr_log(true);
    for k in 0..=MOVES {
        // A long first move, so the short ones after it are all queued before it ends (each
        // is shorter than its line takes on the serial line).
        let len = if k == 0 { 8000 } else { 200 };
        let mut steps: Vec<i64> = RATIO[..axes].iter().map(|&r| len * r as i64).collect();
        if axes > 1 {
            steps[1] = if k % 2 == 0 { len } else { -len };
        }
        for (w, s) in want.iter_mut().zip(&steps) {
            *w += s;
            rising += s.abs();
        }
        let r = b.send_line_wait_ok(&g1_line(&steps, hz))?;
        ensure!(r.contains("ok"), "{r}");
    }
    b.run_until_quiet(HZ / 10, 5 * HZ)?;
    let log = b.isr_log();
    let has = |r: &super::IsrRun, f: &str| r.blocks.iter().any(|&a| b.symbol(a).is_some_and(|(n, _)| n.ends_with(f)));
    // The chain: every step-interrupt run with an update event up to the one that ends the
    // motion (its last step, then idle: no edge follows it, reported apart).
    let end = log.iter().rposition(|r| r.update.is_some() && has(r, "::end_of_queue")).unwrap_or(log.len());
    let runs: Vec<&super::IsrRun> = log[..end].iter().filter(|r| r.update.is_some()).collect();
    // At speed: the update came within 2048 cycles (above 35 kHz) of the one before (not a
    // start from rest, reported apart).
    let (mut ticks, mut max_start, mut max_last, mut max_first, mut after_last) = (Vec::new(), 0, 0, 0, false);
    for (k, r) in runs.iter().enumerate() {
        // A move change: the tick of a move's last step finds the next one, the tick after it
        // enters it.
        let (last, first) = (has(r, "::finish"), after_last);
        after_last = last;
        let at_speed = k > 0 && r.update.unwrap_or(0) - runs[k - 1].update.unwrap_or(0) < AT_SPEED_CYCLES;
        if !at_speed {
            max_start = max_start.max(r.cycles);
            continue;
        }
        ticks.push(r.cycles);
        if last {
            max_last = max_last.max(r.cycles);
        }
        if first {
            max_first = max_first.max(r.cycles);
        }
    }
    let max_end = log.get(end).map_or(0, |r| r.cycles);
    b.set_isr_log(false);
    ensure!(!ticks.is_empty(), "no step interrupt");
    Ok(ChangeResult {
        axes,
        hz,
        runs: ticks.len(),
        mean: ticks.iter().sum::<u64>() as f64 / ticks.len() as f64,
        max: ticks.iter().copied().max().unwrap_or(0),
        max_start,
        max_end,
        max_change: max_last.max(max_first),
        max_last,
        max_first,
        want,
        rising,
    })
}
