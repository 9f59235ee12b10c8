//! Streaming short segments to the firmware like a sender (line, wait for `ok`): the planner's
//! throughput per G-code line and the step interrupt during back-to-back moves at speed.
//!
//! Every figure is *modeled* (cycles of the emulated Cortex-M3, see bench/README.md).

use anyhow::{ensure, Result};

use super::profile::FnCost;
use super::{Board, StepIsr, HZ};

/// What one stream measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StreamResult {
    /// Segments streamed.
    pub lines: usize,
    /// Thread-mode cycles (everything but interrupts: line parsing, planning, look-ahead,
    /// feeder, polls, replies) per streamed line.
    pub thread_cycles_per_line: f64,
    /// Parsing and planning alone, with the look-ahead full (lines after the 40th): inclusive
    /// thread-mode cycles of `Controller::gcode` (parse, interpret, plan) and `Controller::push`
    /// (into the look-ahead, its re-plan and the feeder) per line, interrupts not counted.
    pub plan: PlanCost,
    /// The step interrupt while the segments ran at speed (after the first 40 lines, until
    /// the last was sent).
    pub isr: StepIsr,
    /// 10 ms windows without a step between the first step and the last line's `ok`.
    pub starved_windows: usize,
    /// Motion time of the segments, s.
    pub seconds: f64,
}

/// Modeled cost of parsing and planning a line (see [`StreamResult::plan`]).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct PlanCost {
    /// Lines measured.
    pub lines: usize,
    /// Mean cycles per line: its `gcode` call plus its pushes.
    pub mean: f64,
    /// Longest single `gcode` call and longest single push, cycles.
    pub max_parse: u64,
    pub max_push: u64,
}

/// `n` segments of 0.1–0.5 mm at `feed` mm/min, turning by up to ±30° each (xorshift from
/// `seed`), on default settings.
pub fn segments(n: usize, feed: f64, seed: u64) -> Vec<String> {
    let mut r = seed | 1;
    let mut next = || {
        r ^= r << 13;
        r ^= r >> 7;
        r ^= r << 17;
        (r >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut x, mut y, mut a) = (0.0f64, 0.0f64, 0.0f64);
    let mut out = vec![format!("G90 G1 F{feed}")];
    for _ in 0..n {
        a += (next() - 0.5) * std::f64::consts::PI / 3.0;
        let len = 0.1 + 0.4 * next();
        x += len * a.cos();
        y += len * a.sin();
        out.push(format!("X{x:.3} Y{y:.3}"));
    }
    out
}

/// Where the parse + plan cycles of [`StreamResult::plan`] go.
#[derive(Clone, Debug, Default)]
pub struct PlanBreakdown {
    /// Exclusive cycles per function inside the timed `gcode` and `push` calls, most first.
    pub functions: Vec<FnCost>,
    /// Per extra function asked for: (name, calls, inclusive cycles of all calls).
    pub inclusive: Vec<(String, usize, u64)>,
    /// The extra functions' calls by call site: (index into `inclusive`, `caller+offset`,
    /// calls, inclusive cycles), most cycles first.
    pub callers: Vec<(usize, String, u64, u64)>,
}

// a step pulse's rising edge (GPIOB's step pins; not EN, PB8, which boot raises)
fn is_step(e: &super::gpio::PinEdge) -> bool {
    e.port == 1 && e.level && super::STEP_PINS.contains(&e.pin)
}

/// Streams `segments(n, 3000, seed)` into a booted `board` and measures.
pub fn stream_segments(board: &mut Board, n: usize, seed: u64) -> Result<StreamResult> {
    Ok(stream_segments_profiled(board, n, seed, &[])?.0)
}

/// [`stream_segments`], with where the parse + plan cycles go: exclusive per function, and
/// inclusive for the functions named in `extra` (demangled, generics as `<_>`; calls within
/// the measured lines).
pub fn stream_segments_profiled(board: &mut Board, n: usize, seed: u64, extra: &[&str]) -> Result<(StreamResult, PlanBreakdown)> {
    let lines = segments(n, 3000.0, seed);
    board.set_profile(true);
    let mut first_step = None;
    let mut last_ok = 0;
    for (i, l) in lines.iter().enumerate() {
        if i == 40 {
            board.reset_step_isr_stats();
            let mut names = vec![
                "ddastep::grbl::controller::lines::<impl ddastep::grbl::controller::Controller<_>>::gcode",
                "ddastep::grbl::controller::poll::<impl ddastep::grbl::controller::Controller<_>>::push",
            ];
            names.extend_from_slice(extra);
            board.time_functions(&names)?;
        }
        let r = board.send_line_wait_ok(l)?;
        ensure!(r.contains("ok"), "{l}: {r}");
        if first_step.is_none() {
            first_step = board.edges().iter().find(|e| is_step(e)).map(|e| e.cycle);
        }
        last_ok = board.cycles();
    }
    let isr = board.step_isr();
    let functions = board.timed_profile();
    let callers = board.timed_callers().into_iter().filter(|c| c.0 >= 2).map(|(k, f, n, c)| (k - 2, f, n, c)).collect();
    let calls = board.timed_calls();
    let inclusive = extra
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let c: Vec<u64> = calls.iter().filter(|c| c.0 == i + 2).map(|c| c.1).collect();
            (n.to_string(), c.len(), c.iter().sum())
        })
        .collect();
    let measured = lines.len() - 40;
    let max_of = |k: usize| calls.iter().filter(|c| c.0 == k).map(|c| c.1).max().unwrap_or(0);
    let plan = PlanCost {
        lines: measured,
        mean: calls.iter().filter(|c| c.0 < 2).map(|c| c.1).sum::<u64>() as f64 / measured as f64,
        max_parse: max_of(0),
        max_push: max_of(1),
    };
    let prof = board.profile(0);
    if std::env::var_os("STREAM_PROFILE").is_some() {
        for f in prof.iter().take(25) {
            eprintln!("{:>10} {:>5.1}% {}", f.cycles, f.share * 100.0, f.function);
        }
    }
    let thread: u64 = prof.iter().map(|f| f.cycles).sum();
    if std::env::var_os("STREAM_PROFILE").is_some() {
        for f in board.profile(16 + super::TIM2_IRQ).iter().take(12) {
            eprintln!("TIM2 {:>10} {:>8} runs {:>5.1}% {}", f.cycles, f.block_runs, f.share * 100.0, f.function);
        }
    }
    board.set_profile(false);
    board.run_until_quiet(HZ / 10, 30 * HZ)?;
    let first = first_step.unwrap_or(last_ok);
    let last_step = board.edges().iter().rev().find(|e| is_step(e)).map_or(first, |e| e.cycle);
    let w = HZ / 100;
    let mut busy = vec![false; ((last_ok.saturating_sub(first)) / w) as usize + 1];
    for e in board.edges().iter().filter(|e| is_step(e) && e.cycle >= first && e.cycle < last_ok) {
        busy[((e.cycle - first) / w) as usize] = true;
    }
    let starved = busy.iter().take(busy.len().saturating_sub(1)).filter(|b| !**b).count();
    let r = StreamResult {
        lines: n,
        thread_cycles_per_line: thread as f64 / lines.len() as f64,
        plan,
        isr,
        starved_windows: starved,
        seconds: (last_step - first) as f64 / HZ as f64,
    };
    Ok((r, PlanBreakdown { functions, inclusive, callers }))
}
