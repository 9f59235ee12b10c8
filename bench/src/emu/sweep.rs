//! The step-rate sweep: for each axis count, the highest master rate the firmware sustains on
//! the emulated board, and its CPU load at a few fixed rates. For `cargo sim -- --sweep` and
//! `cargo bench --bench sweep`; the numbers go to bench/RESULTS.md.
//!
//! One point = a fresh board (reset), the sweep settings, one `G1` on `axes` axes with the
//! steps in the ratio 10:6:4:8:2:7:5 (X is the master) and F chosen for the target master rate,
//! long enough for `cruise_ms` of measured cruise plus margins. The measured stretch is the
//! whole 1 ms load windows from 2 ms after the ramp's end; every window in it must have X
//! within 1 % of the target (rate from the first and last X edge of the window), else the
//! point reports "no cruise". A point is sustainable when it has no timer overrun in the move,
//! every axis made exactly its steps (rising edges and net count), cruise was reached and no
//! measured window is busier than `max_load`.
//!
//! Step-ISR figures (entries, cycles, BSRR offsets) cover the measured stretch only, so the
//! move's load (refill, 1 000-cycle `Engine::load`) and the ramp walk stay out of them.

use std::path::Path;

use anyhow::{bail, Context, Result};
use serde::Serialize;

use super::board::Board;
use super::clock::HZ;
use super::nvic::IRQ0;
use super::profile::FnCost;
use super::report::{AXES, STEP_PINS};
use super::stats::WINDOW;

/// Steps per axis per 10 master steps: X:Y:Z:A:B:C:U = 10:6:4:8:2:7:5 (the paper's 5:3:2 first).
pub const RATIO: [u64; 7] = [10, 6, 4, 8, 2, 7, 5];
/// Steps/mm the sweep leaves at its default.
pub(crate) const STEPS_PER_MM: f64 = 100.0;
/// `$120..126` for the sweep, mm/s² (10⁸ master steps/s²: 500 kHz in 5 ms).
const ACCEL_MM_S2: f64 = 1_000_000.0;
/// `$110..126` for the sweep, mm/min (1 MHz at 100 steps/mm: never the limit).
const MAX_RATE_MM_MIN: f64 = 600_000.0;
/// `$0` for the sweep, µs. The firmware's cap (`Timing::max_rate_for`, src/motion/timing.rs)
/// combines the pulse rule (2 × pulse + 72 ticks) with the step handler's measured cost; the
/// search runs up to whatever `$I` reports for it.
pub const PULSE_US: f64 = 0.5;

/// How the firmware puts out steps: interrupt mode (the default), dual-edge (`$580=1`), DMA
/// burst (`$581=1`), or both.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Mode {
    /// Every step toggles its pin.
    pub dual_edge: bool,
    /// DMA stores the buffered words at TIM2's events; the step path is the buffer fill.
    pub dma: bool,
}

impl Mode {
    /// The settings that select it (each restarts the MCU).
    fn lines(self) -> Vec<&'static str> {
        let mut v = Vec::new();
        if self.dual_edge {
            v.push("$580=1");
        }
        if self.dma {
            v.push("$581=1");
        }
        v
    }

    /// How tables and logs name it.
    pub fn label(self) -> &'static str {
        match (self.dual_edge, self.dma) {
            (false, false) => "interrupt",
            (true, false) => "dual-edge",
            (false, true) => "DMA",
            (true, true) => "DMA dual-edge",
        }
    }
}

/// What to sweep.
#[derive(Clone, Debug)]
pub struct Options {
    /// Axis counts (1..=7).
    pub axes: Vec<usize>,
    /// Rates at which the load is reported, Hz.
    pub load_rates: Vec<u32>,
    /// Grid step of the upward scan (and its first rate), Hz.
    pub grid_hz: u32,
    /// Stop the refinement when the pass/fail bracket is this narrow, Hz.
    pub resolution_hz: u32,
    /// Measured cruise per point, ms.
    pub cruise_ms: u64,
    /// Highest busy fraction allowed in any measured window.
    pub max_load: f64,
    /// Worker threads (points of one axis count run in sequence).
    pub jobs: usize,
    /// Print each point as it finishes.
    pub verbose: bool,
    /// The step output mode.
    pub mode: Mode,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            axes: (1..=7).collect(),
            load_rates: vec![50_000, 200_000, 400_000],
            grid_hz: 10_000,
            resolution_hz: 1_000,
            cruise_ms: 20,
            max_load: 0.95,
            jobs: 2,
            verbose: true,
            mode: Mode::default(),
        }
    }
}

/// Why a point is not sustainable.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Verdict {
    Ok,
    /// Timer events found their flag still set.
    Overrun(u64),
    /// Busiest measured window, busy fraction.
    Load(f64),
    /// Some axis did not make its exact steps.
    Counts(String),
    /// The measured stretch was not all cruise at the target (slowest window's X rate, Hz).
    NoCruise(f64),
    /// The planner did not accept the move, or the board faulted.
    Error(String),
}

/// One measured point.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    pub axes: usize,
    pub target_hz: u32,
    /// Judged with the CPU load (everything not asleep: step ISR, other interrupts, `idle`).
    pub verdict: Verdict,
    /// Judged with the step ISR's share of each window instead of the CPU load.
    pub isr_verdict: Verdict,
    /// X rate over the measured stretch (edges / time), Hz.
    pub cruise_hz: f64,
    pub windows: usize,
    /// CPU load (not asleep) over the measured windows: mean and busiest.
    pub load_mean: f64,
    pub load_max: f64,
    /// Step-ISR share of the measured windows: mean and busiest.
    pub isr_load_mean: f64,
    pub isr_load_max: f64,
    pub overruns: u64,
    /// Step-ISR figures over the measured stretch.
    pub isr_entries: u64,
    pub isr_mean_cycles: f64,
    pub isr_max_cycles: u64,
    /// Step-ISR modeled cycles per master step (all entries of the stretch / X steps).
    pub isr_cycles_per_step: f64,
    pub bsrr_min: Option<u64>,
    pub bsrr_max: Option<u64>,
    /// Shortest X step high time in the move, ns.
    pub min_high_ns: Option<f64>,
    /// Step-ISR profile over the measured stretch (when asked for).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub profile: Vec<FnCost>,
    /// The same by translated block: (address and name, runs, cycles).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub profile_blocks: Vec<(String, u64, u64)>,
    /// Thread mode (`idle`) by function over the measured stretch.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub profile_thread: Vec<FnCost>,
    /// Simulated seconds and wall seconds this point took.
    pub sim_s: f64,
    pub wall_s: f64,
}

impl Point {
    // true when the firmware sustained the rate with the CPU load at most `max_load`
    pub fn ok(&self) -> bool {
        self.verdict == Verdict::Ok
    }

    // true when it sustained the rate with the step ISR's share at most `max_load`
    pub fn isr_ok(&self) -> bool {
        self.isr_verdict == Verdict::Ok
    }

    fn failed(axes: usize, target_hz: u32, verdict: Verdict) -> Self {
        Point {
            axes,
            target_hz,
            isr_verdict: verdict.clone(),
            verdict,
            cruise_hz: 0.0,
            windows: 0,
            load_mean: 0.0,
            load_max: 0.0,
            isr_load_mean: 0.0,
            isr_load_max: 0.0,
            overruns: 0,
            isr_entries: 0,
            isr_mean_cycles: 0.0,
            isr_max_cycles: 0,
            isr_cycles_per_step: 0.0,
            bsrr_min: None,
            bsrr_max: None,
            min_high_ns: None,
            profile: Vec::new(),
            profile_blocks: Vec::new(),
            profile_thread: Vec::new(),
            sim_s: 0.0,
            wall_s: 0.0,
        }
    }
}

/// The highest passing and lowest failing rate of one criterion.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Bracket {
    /// Highest sustainable rate found, Hz (0: none).
    pub max_hz: u32,
    /// Lowest failing rate above it (None: the firmware's cap passed).
    pub fail_hz: Option<u32>,
}

/// The sweep's result for one axis count.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub axes: usize,
    /// With the CPU load criterion (the headline).
    pub cpu: Bracket,
    /// With the step ISR's share instead (what the handler alone sustains).
    pub isr: Bracket,
    /// A grid rate above `cpu.fail_hz` where the CPU criterion passed again, if any.
    pub cpu_passes_again_hz: Option<u32>,
    /// Every point tried, in order.
    pub tried: Vec<Point>,
}

impl Row {
    // the point tried at `hz`
    pub fn at(&self, hz: u32) -> Option<&Point> {
        self.tried.iter().find(|p| p.target_hz == hz)
    }
}

/// Everything the sweep found.
#[derive(Clone, Debug, Serialize)]
pub struct Sweep {
    /// The step output mode.
    pub mode: Mode,
    /// `[MSG:max step rate N Hz]` with the sweep settings.
    pub cap_hz: u32,
    /// Settings lines sent to each board.
    pub settings: Vec<String>,
    pub rows: Vec<Row>,
    pub wall_s: f64,
    pub points: usize,
}

// the settings lines every point sends (after reset)
pub fn settings_lines() -> Vec<String> {
    // All seven axes ($42), at the sweep's steps/mm (the defaults are a 3-axis gantry's).
    let mut v = vec![format!("$0={PULSE_US}"), "$41=0".to_string(), "$40=1000".to_string(), "$42=7".to_string()];
    for i in 0..7 {
        v.push(format!("$10{i}={STEPS_PER_MM}"));
        v.push(format!("$11{i}={MAX_RATE_MM_MIN}"));
        v.push(format!("$12{i}={ACCEL_MM_S2}"));
    }
    v
}

/// A booted board with the sweep settings applied and what `$I` said.
struct Prepared {
    board: Board,
    cap_hz: u32,
    accel_hz_s: u32,
}

/// A booted board in `mode` (each mode setting restarts the MCU: one more banner each).
pub fn boot(elf: &Path, mode: Mode) -> Result<Board> {
    let mut board = Board::load(elf)?;
    board.run_until(HZ / 2, |b| b.serial_output().contains("Grbl"))?;
    for (i, line) in mode.lines().into_iter().enumerate() {
        board.send_line_wait_ok(line)?;
        let up = board.run_until(HZ / 2, |b| b.serial_output().matches("Grbl").count() >= i + 2)?;
        if !up {
            bail!("no banner after {line}");
        }
    }
    board.dual_edge = mode.dual_edge;
    if mode.dma {
        board.step_irq = super::dma::IRQ_CHANNEL1;
    }
    Ok(board)
}

// reset a board from `elf`, boot it, send the settings and `$I`
fn prepare(elf: &Path, mode: Mode) -> Result<Prepared> {
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

// the search for one axis count: a grid upward from `grid_hz` until the step ISR fails, the
// load rates, then per criterion a bisection between its last passing and first failing grid
// point ("sustainable at every rate up to max_hz")
fn sweep_axes(elf: &Path, axes: usize, cap_hz: u32, opts: &Options) -> Row {
    let mut tried: Vec<Point> = Vec::new();
    let mut run = |hz: u32| -> Point {
        if let Some(p) = tried.iter().find(|p| p.target_hz == hz) {
            return p.clone();
        }
        let p = run_point(elf, axes, hz, opts.cruise_ms, opts.max_load, false, opts.mode);
        if opts.verbose {
            eprintln!("{}", point_line(&p));
        }
        tried.push(p.clone());
        p
    };
    let mut grid: Vec<(u32, bool, bool)> = Vec::new();
    let mut hz = opts.grid_hz;
    loop {
        let hz_now = hz.min(cap_hz);
        let p = run(hz_now);
        grid.push((hz_now, p.ok(), p.isr_ok()));
        if !p.isr_ok() || hz_now == cap_hz {
            break;
        }
        hz += opts.grid_hz;
    }
    for &hz in &opts.load_rates {
        if hz <= cap_hz {
            run(hz);
        }
    }
    let cpu = refine(&mut run, &grid, opts, |g| g.1, Point::ok);
    let isr = refine(&mut run, &grid, opts, |g| g.2, Point::isr_ok);
    // The CPU load is not monotone in the rate (how `idle`'s loop meets the steps): say so.
    let cpu_again = cpu.fail_hz.and_then(|f| grid.iter().find(|g| g.0 > f && g.1).map(|g| g.0));
    tried.sort_by_key(|p| p.target_hz);
    Row { axes, cpu, isr, cpu_passes_again_hz: cpu_again, tried }
}

// bisection between the last grid point where `grid_pass` holds before its first failure and
// that failure, on a 1 kHz grid down to the resolution
fn refine(run: &mut impl FnMut(u32) -> Point, grid: &[(u32, bool, bool)], opts: &Options, grid_pass: fn(&(u32, bool, bool)) -> bool, pass: fn(&Point) -> bool) -> Bracket {
    let Some(first_fail) = grid.iter().position(|g| !grid_pass(g)) else {
        return Bracket { max_hz: grid.last().map_or(0, |g| g.0), fail_hz: None };
    };
    let mut lo = if first_fail == 0 { 0 } else { grid[first_fail - 1].0 };
    let mut hi = grid[first_fail].0;
    loop {
        let mid = (lo + (hi - lo) / 2) / 1000 * 1000;
        if hi - lo <= opts.resolution_hz || mid <= lo || mid >= hi {
            break;
        }
        if pass(&run(mid)) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Bracket { max_hz: lo, fail_hz: Some(hi) }
}

// the whole sweep, `opts.jobs` axis counts at a time
pub fn sweep(elf: &Path, opts: &Options) -> Result<Sweep> {
    let wall = std::time::Instant::now();
    let cap_hz = prepare(elf, opts.mode)?.cap_hz;
    let queue = std::sync::Mutex::new(opts.axes.clone());
    let rows = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..opts.jobs.max(1) {
            s.spawn(|| loop {
                let Some(axes) = queue.lock().unwrap().pop() else { break };
                let row = sweep_axes(elf, axes, cap_hz, opts);
                rows.lock().unwrap().push(row);
            });
        }
    });
    let mut rows = rows.into_inner().unwrap();
    rows.sort_by_key(|r| r.axes);
    let points = rows.iter().map(|r| r.tried.len()).sum();
    Ok(Sweep { mode: opts.mode, cap_hz, settings: settings_lines(), rows, wall_s: wall.elapsed().as_secs_f64(), points })
}

// one line per point for progress output (with the simulated and wall time)
pub fn point_line(p: &Point) -> String {
    format!("{}, {:.2} s sim in {:.1} s", point_text(p), p.sim_s, p.wall_s)
}

// one line per point, deterministic (for RESULTS.md)
pub fn point_text(p: &Point) -> String {
    format!(
        "{} axes @ {:>6.1} kHz: {:<22} (ISR only: {:<16}) CPU {:>5.1}/{:>5.1} %, ISR {:>5.1}/{:>5.1} % (mean/max), ISR {:>6.1} cyc/step ({:>5.1} mean / {:>4} max per entry), BSRR {}..{}, X high ≥ {} ns",
        p.axes,
        p.target_hz as f64 / 1000.0,
        verdict_text(&p.verdict),
        verdict_text(&p.isr_verdict),
        p.load_mean * 100.0,
        p.load_max * 100.0,
        p.isr_load_mean * 100.0,
        p.isr_load_max * 100.0,
        p.isr_cycles_per_step,
        p.isr_mean_cycles,
        p.isr_max_cycles,
        p.bsrr_min.map_or("-".into(), |v| v.to_string()),
        p.bsrr_max.map_or("-".into(), |v| v.to_string()),
        p.min_high_ns.map_or("-".into(), |v| format!("{v:.0}")),
    )
}

// a verdict for a table cell
fn short_verdict(v: &Verdict) -> String {
    match v {
        Verdict::Counts(s) => match s.split_once(" (") {
            Some((_, over)) => format!("steps lost ({}", over),
            None => "steps lost".into(),
        },
        Verdict::NoCruise(_) => "no cruise".into(),
        Verdict::Error(_) => "error".into(),
        v => verdict_text(v),
    }
}

fn overruns_text(n: u64) -> String {
    format!("{n} overrun{}", if n == 1 { "" } else { "s" })
}

// a short verdict
pub fn verdict_text(v: &Verdict) -> String {
    match v {
        Verdict::Ok => "ok".into(),
        Verdict::Overrun(n) => overruns_text(*n),
        Verdict::Load(l) => format!("load {:.1} %", l * 100.0),
        Verdict::Counts(s) => format!("counts: {s}"),
        Verdict::NoCruise(r) => format!("no cruise ({:.1} kHz)", r / 1000.0),
        Verdict::Error(e) => format!("error: {e}"),
    }
}

impl Sweep {
    // the results table (Markdown)
    pub fn table(&self) -> String {
        let mut s = String::new();
        s += "| axes | max kHz (CPU ≤ 95 %) | max kHz (step ISR ≤ 95 %) | CPU / ISR load @ 50 kHz | @ 200 kHz | @ 400 kHz | ISR cycles per step @ 50 kHz | ISR mean / max cycles per entry @ 50 kHz | BSRR offset min / max cycles |\n";
        s += "|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
        for r in &self.rows {
            let load = |hz: u32| match r.at(hz) {
                Some(p) if matches!(p.isr_verdict, Verdict::Ok | Verdict::Load(_)) => {
                    let mark = if p.ok() { "" } else if p.isr_ok() { " ¹" } else { " ²" };
                    format!("{:.0} / {:.0} %{mark}", p.load_max * 100.0, p.isr_load_max * 100.0)
                }
                Some(p) => short_verdict(&p.verdict),
                None => "-".into(),
            };
            let (cps, isr) = match r.at(50_000) {
                Some(p) if p.isr_entries > 0 => (format!("{:.0}", p.isr_cycles_per_step), format!("{:.0} / {}", p.isr_mean_cycles, p.isr_max_cycles)),
                _ => ("-".into(), "-".into()),
            };
            let bsrr_min = r.tried.iter().filter_map(|p| p.bsrr_min).min();
            let bsrr_max = r.tried.iter().filter(|p| p.isr_ok()).filter_map(|p| p.bsrr_max).max();
            let bsrr = format!("{} / {}", bsrr_min.map_or("-".into(), |v| v.to_string()), bsrr_max.map_or("-".into(), |v| v.to_string()));
            let again = r.cpu_passes_again_hz.map_or(String::new(), |hz| format!(" ³ {:.0}", hz as f64 / 1000.0));
            s += &format!(
                "| {} | {}{again} | {} | {} | {} | {} | {cps} | {isr} | {bsrr} |\n",
                r.axes,
                bracket_text(&r.cpu),
                bracket_text(&r.isr),
                load(50_000),
                load(200_000),
                load(400_000)
            );
        }
        s
    }
}

fn bracket_text(b: &Bracket) -> String {
    match (b.max_hz, b.fail_hz) {
        (0, Some(f)) => format!("< {:.0}", f as f64 / 1000.0),
        (m, None) => format!("≥ {:.0} (cap)", m as f64 / 1000.0),
        (m, Some(f)) => format!("{:.0} (fails {:.0})", m as f64 / 1000.0, f as f64 / 1000.0),
    }
}

// the master rates the move-change benchmark runs at: 0.5 % under the cap for 1, 3 and 7 axes
// (the firmware's `Timing::max_rate_for`: `$I`'s one-axis cap, and for more axes the handler's
// cost per slave, 17 ticks, on the sweep's short pulse)
fn change_rates(s: &Sweep) -> Vec<(usize, f64)> {
    let base = (72_000_000.0 / s.cap_hz as f64).round();
    [1usize, 3, 7].iter().map(|&a| (a, (72_000_000.0 / (base + 17.0 * (a - 1) as f64)).floor() * 0.995)).collect()
}

// bench/RESULTS.md: command, date, model, table, ISR cost and profile, notes, every point
pub fn results_markdown(s: &Sweep, others: &[Sweep], command: &str, firmware: &str, elf: &Path) -> Result<String> {
    let dual = others.iter().find(|o| o.mode == Mode { dual_edge: true, dma: false });
    let dma = others.iter().find(|o| o.mode == Mode { dual_edge: false, dma: true });
    let dma_dual = others.iter().find(|o| o.mode == Mode { dual_edge: true, dma: true });
    use std::fmt::Write as _;
    let mut m = String::new();
    let (date, commit, flash) = (utc_date(), firmware, flash_bytes(elf));
    let cruise_ms = Options::default().cruise_ms;
    writeln!(m, "# Step-rate sweep on the virtual bench\n")?;
    writeln!(m, "Made by `{command}` on {date} (UTC), firmware {commit}, flash image {flash} bytes;")?;
    writeln!(m, "{} points (about a minute on two cores). Regenerate with the same command after a firmware", s.points)?;
    writeln!(m, "change: on the same firmware only the date changes.\n")?;
    writeln!(m, "## What the numbers are\n")?;
    writeln!(m, "Every cycle and load figure is **modeled**: the release ELF runs on unicorn and the bench charges")?;
    writeln!(m, "Cortex-M3 TRM cycle costs per instruction plus the STM32F103's memory timing: flash lines with")?;
    writeln!(m, "FLASH_ACR's 2 wait states and the prefetch buffer, refills after taken branches, AHB-to-APB")?;
    writeln!(m, "bridge stalls (TIM2 reads 5 cycles, GPIO 3), exception entry 14 / return 12 / tail-chain 8")?;
    writeln!(m, "(bench/README.md, \"Model\"). The memory model is checked against two published silicon")?;
    writeln!(m, "measurements within ±5 % (`bench/tests/emu_silicon.rs`); expect a handler within roughly ±10 %,")?;
    writeln!(m, "and before/after comparisons on the bench much tighter than that. On a board, `$I` reports the")?;
    writeln!(m, "firmware's own DWT measurement of the step interrupt.\n")?;
    writeln!(m, "Per point: reset, then `{}`, `G91` and one `G1` on N axes", s.settings.join("`, `"))?;
    writeln!(m, "(steps X:Y:Z:A:B:C:U = 10:6:4:8:2:7:5, all positive, F for the target master rate, trapezoid")?;
    writeln!(m, "ramp at 10⁸ steps/s²). The firmware's cap (`Timing::max_rate_for`) combines the pulse rule")?;
    writeln!(m, "(2·pulse + 72 ticks) with the step handler's measured cost. `$I` reports {} Hz with these", s.cap_hz)?;
    writeln!(m, "settings: the cap of the search.\n")?;
    writeln!(m, "Measured: {cruise_ms} whole 1 ms windows starting 2 ms after the ramp; each must have X within 1 % of")?;
    writeln!(m, "the target (first-to-last X edge of the window). A rate is **sustainable** when, for the move,")?;
    writeln!(m, "there is no timer overrun, every axis made exactly its steps (rising edges and net count),")?;
    writeln!(m, "cruise held, and no measured window is over 95 % busy. \"CPU\" is everything not asleep in")?;
    writeln!(m, "WFI (step ISR, other interrupts, `idle`); \"ISR\" is the step interrupt's share alone (entry to")?;
    let o = Options::default();
    writeln!(m, "end of return). Per axis count the search scans up from {0} kHz in {0} kHz steps until the step", o.grid_hz / 1000)?;
    writeln!(m, "ISR fails, then bisects each criterion between its last pass and first failure of the scan to")?;
    writeln!(m, "{} kHz: \"max\" is sustainable at every scanned rate up to it.\n", o.resolution_hz / 1000)?;
    writeln!(m, "## Continuous motion (look-ahead)\n")?;
    {
        let mut b = super::Board::load(elf)?;
        b.run_until(super::HZ / 2, |b| b.serial_output().contains("Grbl"))?;
        let r = super::stream::stream_segments(&mut b, 300, 0x2545_F491_4F6C_DD1D)?;
        writeln!(m, "300 G1 segments of 0.1–0.5 mm at F3000 (turning up to ±30° each, default settings), sent")?;
        writeln!(m, "like a sender (line, wait for `ok`) at 115200 baud; `cargo bench -p ddastep-bench --target")?;
        writeln!(m, "host-tuple --bench plan_line` prints the same.\n")?;
        writeln!(m, "| what | figure (modeled) |")?;
        writeln!(m, "|---|---|")?;
        writeln!(m, "| thread-mode cycles per streamed line (parse, plan, look-ahead, feeder, polls, replies) | {:.0} ({:.3} ms) |", r.thread_cycles_per_line, r.thread_cycles_per_line / 72_000.0)?;
        let p = &r.plan;
        writeln!(
            m,
            "| parse + plan per line with the look-ahead full (`Controller::gcode` + `Controller::push`, inclusive, interrupts excluded; {} lines): mean / longest parse / longest push | {:.0} ({:.3} ms) / {} / {} |",
            p.lines,
            p.mean,
            p.mean / 72_000.0,
            p.max_parse,
            p.max_push
        )?;
        writeln!(m, "| step ISR during the back-to-back moves: mean / max cycles | {:.1} / {} (max/mean {:.2}) |", r.isr.mean_cycles, r.isr.max_cycles, r.isr.max_cycles as f64 / r.isr.mean_cycles.max(1.0))?;
        writeln!(m, "| 10 ms windows without a step while streaming | {} |", r.starved_windows)?;
        writeln!(m, "| motion time | {:.3} s |\n", r.seconds)?;
        writeln!(m, "At this feed (5 kHz master) most step ticks are far apart; the max is a start from rest or")?;
        writeln!(m, "the end of a chain. Moves changing at the rate cap are measured below.\n")?;
    }
    writeln!(m, "### Moves changing at the rate cap\n")?;
    writeln!(m, "`ddastep_bench::emu::changes::back_to_back`, as `bench/tests/firmware_lookahead.rs` runs it: the")?;
    writeln!(m, "sweep's settings, one long move, then {} short ones (200 master steps each) queued behind it,", super::changes::MOVES)?;
    writeln!(m, "at 0.5 % under `Timing::max_rate_for` for the axis count (steps in the sweep's ratio; on 3 and")?;
    writeln!(m, "7 axes Y reverses at every junction: a direction change at speed). The step ISR's runs at")?;
    writeln!(m, "speed (update within {} cycles of the one before) up to the chain's last step; a move", super::changes::AT_SPEED_CYCLES)?;
    writeln!(m, "change is the tick of a move's last step (it finds the primed successor) and the next one's")?;
    writeln!(m, "first (it enters it); the ramp work runs in its own interrupt.\n")?;
    writeln!(m, "| axes | master rate | mean / max cycles (max/mean) | move change: last step / first step | not at speed (start from rest) / the chain's end |")?;
    writeln!(m, "|---:|---:|---:|---:|---:|")?;
    for (axes, hz) in change_rates(s) {
        let mut b = super::Board::load(elf)?;
        b.run_until(super::HZ / 2, |b| b.serial_output().contains("Grbl"))?;
        let r = super::changes::back_to_back(&mut b, axes, hz)?;
        writeln!(m, "| {axes} | {:.1} kHz | {:.1} / {} ({:.2}) | {} / {} | {} / {} |", hz / 1000.0, r.mean, r.max, r.ratio(), r.max_last, r.max_first, r.max_start, r.max_end)?;
    }
    writeln!(m)?;
    writeln!(m, "## Results\n")?;
    m += &s.table();
    writeln!(m, "\nLoad cells: busiest measured window, CPU / step ISR; ¹ sustained except the CPU load (over 95 %),")?;
    writeln!(m, "² the step ISR alone is over 95 % too. A failure is named when the rate was not sustained at all")?;
    writeln!(m, "(\"steps lost\": fewer rising edges on the pins than the move's steps).")?;
    if s.rows.iter().any(|r| r.cpu_passes_again_hz.is_some()) {
        writeln!(m, "³ a scanned rate above the failure where the CPU criterion passes again: the CPU load is not")?;
        writeln!(m, "monotone in the rate (how often `idle` completes its loop and reaches WFI between steps).")?;
    }
    writeln!(m, "BSRR offset: update event to the handler's first GPIOB store, over the points the ISR sustained.\n")?;
    if let Some(d) = dual {
        writeln!(m, "## Dual-edge mode (`$580=1`)\n")?;
        writeln!(m, "The same sweep with `$580=1` first (the MCU restarts): every step toggles its pin, one update")?;
        writeln!(m, "event per step and no compare event. Steps are counted on both edges; the X high time column")?;
        writeln!(m, "is then the shortest time between two toggles of X. `$I` reports {} Hz with these settings", d.cap_hz)?;
        writeln!(m, "(`Timing::min_period_for`, dual-edge rule: the handler's measured cost per step, two toggles a")?;
        writeln!(m, "long tick brings closer still a pulse apart, the pulse plus the store jitter). A \"fails\" just above a row's cap is the")?;
        writeln!(m, "planner's clamp (the move cruises at the cap, not at the target: \"no cruise\" in the point list).\n")?;
        m += &d.table();
        writeln!(m, "\nSide by side (CPU ≤ 95 %; `$I`, one axis: {:.1} kHz single-edge, {:.1} kHz dual-edge):\n", s.cap_hz as f64 / 1000.0, d.cap_hz as f64 / 1000.0)?;
        writeln!(m, "| axes | max kHz, single-edge | max kHz, dual-edge | dual / single |\n|---:|---:|---:|---:|")?;
        for (a, b) in s.rows.iter().zip(&d.rows) {
            let gain = if a.cpu.max_hz > 0 { format!("{:.2}", b.cpu.max_hz as f64 / a.cpu.max_hz as f64) } else { "-".into() };
            writeln!(m, "| {} | {} | {} | {gain} |", a.axes, bracket_text(&a.cpu), bracket_text(&b.cpu))?;
        }
    }
    if let Some(d) = dma {
        writeln!(m, "## DMA burst mode (`$581=1`)\n")?;
        writeln!(m, "The same sweep with `$581=1` first (the MCU restarts): TIM2 paces every edge, DMA1 stores the")?;
        writeln!(m, "words the engine buffered (update event: the step word into GPIOB's BSRR; compare 3: the next")?;
        writeln!(m, "period into ARR; compare 1: the falling-edge word), and the step path is the buffer fill in")?;
        writeln!(m, "DMA1 channel 1's half/complete interrupt (`src/firmware/burst.rs`, `ddastep::motion::burst`). The")?;
        writeln!(m, "\"ISR\" columns are that interrupt; DMA's own bus cycles are charged to the CPU while it runs")?;
        writeln!(m, "(the bench's DMA model, bench/src/emu/dma.rs: 7 cycles per store to GPIO, 9 to TIM2, the")?;
        writeln!(m, "bus-matrix share stolen from a running core). `$I` reports {} Hz with these settings", d.cap_hz)?;
        writeln!(m, "(`Timing::min_period_for`, DMA rule: the fill's measured cost per step, above the pulse and low")?;
        writeln!(m, "time plus the stores' latency margin). A \"fails\" just above a row's cap is the planner's clamp.\n")?;
        m += &d.table();
        writeln!(m)?;
    }
    if let Some(d) = dma_dual {
        writeln!(m, "### DMA burst mode, dual-edge (`$581=1`, `$580=1`)\n")?;
        writeln!(m, "The same with every step toggling its pin: no compare event, no falling-edge store (two DMA")?;
        writeln!(m, "stores per entry). Steps are counted on both edges; the X high time column is the shortest time")?;
        writeln!(m, "between two toggles of X. `$I` reports {} Hz with these settings.\n", d.cap_hz)?;
        m += &d.table();
        writeln!(m)?;
    }
    if !others.is_empty() {
        writeln!(m, "## The modes side by side\n")?;
        writeln!(m, "Highest sustainable master rate per axis count (CPU ≤ 95 %, kHz):\n")?;
        let all: Vec<&Sweep> = std::iter::once(s).chain(others.iter()).collect();
        let head: Vec<String> = all.iter().map(|w| format!("{} (`$I` {:.1})", w.mode.label(), w.cap_hz as f64 / 1000.0)).collect();
        writeln!(m, "| axes | {} |\n|---:|{}", head.join(" | "), "---:|".repeat(all.len()))?;
        for (i, r) in s.rows.iter().enumerate() {
            let cells: Vec<String> = all.iter().map(|w| w.rows.get(i).map_or("-".into(), |r| bracket_text(&r.cpu))).collect();
            writeln!(m, "| {} | {} |", r.axes, cells.join(" | "))?;
        }
        writeln!(m, "| reference: Klipper on an STM32F103 (silicon, 1 stepper, full pulses) | 590 |{}", " |".repeat(all.len() - 1))?;
        writeln!(m, "| reference: grbl32 (silicon, 1 axis) | 222 |{}", " |".repeat(all.len() - 1))?;
        writeln!(m, "\nReference lines from issue 15: Klipper 1.18 M toggles/s (590 kHz with full pulses, one")?;
        writeln!(m, "stepper), grbl32 222 kHz (one axis), both measured on silicon; ours are modeled.\n")?;
    }
    if let Some((a, b)) = isr_cost_fit(s) {
        writeln!(m, "## Step ISR cost\n")?;
        writeln!(m, "Modeled step-ISR cycles per master step at 50 kHz cruise: ≈ {a:.0} + {b:.1} × slaves")?;
        let entries: Vec<f64> = s.rows.iter().filter_map(|r| r.at(50_000).map(|p| p.isr_entries as f64 / (p.target_hz as f64 * cruise_ms as f64 / 1000.0))).collect();
        writeln!(m, "(least squares over the axis counts; entry, body and return included; {:.2}–{:.2} handler entries", entries.iter().copied().fold(f64::INFINITY, f64::min), entries.iter().copied().fold(0.0, f64::max))?;
        writeln!(m, "per step: with a short pulse the compare event is already pending when the update handler")?;
        writeln!(m, "checks it, so the falling edge costs no entry of its own). The step ISR alone saturates the core")?;
        writeln!(m, "at 72 MHz / cycles: ≈ {:.0} kHz for 1 axis, ≈ {:.0} kHz for 7. 500 kHz needs", 72e3 / a, 72e3 / (a + 6.0 * b))?;
        writeln!(m, "≤ 144 cycles per step including entry and return (26). The step interrupt's code (the TIM2")?;
        writeln!(m, "handler, `Stepper::tick`, the plain step of `Stepper::tick_quick`) runs from SRAM, where the")?;
        writeln!(m, "bench charges its fetches sharing the System bus with data (bench/README.md, \"Model\").\n")?;
        let floor = super::floor::measure()?;
        writeln!(m, "### The step handler's floor\n")?;
        writeln!(m, "A hand-scheduled Thumb handler that does only what interrupt mode's plain step must (the")?;
        writeln!(m, "checks of `Stepper::tick_quick`, the step's state, the rising store first, the compare")?;
        writeln!(m, "event's falling edge, the DWT self-timing `$I` reports), one axis, TIM2 at 250 kHz")?;
        writeln!(m, "(`cargo sim -- --floor`, bench/src/emu/floor.rs; entry and return included):\n")?;
        m += &super::floor::markdown(&floor);
        writeln!(m, "\nNo compiled handler of the same work goes below the first row ({:.0} cycles; ours: {a:.0}).", floor[0].1)?;
        writeln!(m, "500 kHz in interrupt mode needs ≤ 137 cycles per step at 95 % CPU, so it is out of reach")?;
        writeln!(m, "while every step times itself; without the self-timing the floor would allow it, with")?;
        writeln!(m, "nothing left for the long ticks (a move change, a ramp millisecond) that must also fit.\n")?;
    }
    let mut thread_per_entry = 0.0f64;
    for (axes, hz) in [(7usize, 50_000u32), (1, 50_000)] {
        let p = run_point(elf, axes, hz, cruise_ms, 0.95, true, Mode::default());
        let e = p.isr_entries.max(1) as f64;
        writeln!(m, "### Where the cycles go: {axes} {} at {} kHz ({:.0} cycles per step)\n", if axes == 1 { "axis" } else { "axes" }, hz / 1000, p.isr_cycles_per_step)?;
        writeln!(m, "| step ISR, by function | cycles per entry | share |\n|---|---:|---:|")?;
        for f in &p.profile {
            writeln!(m, "| `{}` | {:.1} | {:.1} % |", f.function, f.cycles as f64 / e, f.share * 100.0)?;
        }
        writeln!(m, "\n| hottest blocks (start, function+offset) | cycles per entry | cycles per run |\n|---|---:|---:|")?;
        for (name, runs, cycles) in p.profile_blocks.iter().take(10) {
            writeln!(m, "| `{name}` | {:.1} | {:.1} |", *cycles as f64 / e, *cycles as f64 / (*runs).max(1) as f64)?;
        }
        let thread: u64 = p.profile_thread.iter().map(|f| f.cycles).sum();
        thread_per_entry = thread_per_entry.max(thread as f64 / e);
        writeln!(m, "\nThread mode in the same windows: {:.0} cycles per step-ISR entry ({}).\n", thread as f64 / e, p.profile_thread.iter().take(4).map(|f| format!("`{}` {:.0}", f.function, f.cycles as f64 / e)).collect::<Vec<_>>().join(", "))?;
    }
    writeln!(m, "## Notes\n")?;
    if thread_per_entry > 50.0 {
        m += IDLE_NOTE;
    }
    m += NOTES;
    writeln!(m, "\n<details><summary>Every point tried</summary>\n\n```")?;
    for r in &s.rows {
        for p in &r.tried {
            writeln!(m, "{}", point_text(p))?;
        }
    }
    for o in others {
        for r in &o.rows {
            for p in &r.tried {
                writeln!(m, "{} {}", o.mode.label(), point_text(p))?;
            }
        }
    }
    writeln!(m, "```\n</details>")?;
    Ok(m)
}

/// Step-ISR cycles per master step at 50 kHz against the slave count, least squares: (base,
/// per slave), `None` with fewer than two axis counts.
pub fn isr_cost_fit(s: &Sweep) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = s.rows.iter().filter_map(|r| r.at(50_000).filter(|p| p.isr_entries > 0).map(|p| ((r.axes - 1) as f64, p.isr_cycles_per_step))).collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (sx, sy) = (pts.iter().map(|p| p.0).sum::<f64>(), pts.iter().map(|p| p.1).sum::<f64>());
    let sxx = pts.iter().map(|p| p.0 * p.0).sum::<f64>();
    let sxy = pts.iter().map(|p| p.0 * p.1).sum::<f64>();
    let b = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    Some(((sy - b * sx) / n, b))
}

/// Printed when thread mode runs more than 50 cycles per step interrupt.
const IDLE_NOTE: &str = "\
- Thread mode runs about as often as the step interrupt (the \"Thread mode\" figures above): `idle`
  goes round its loop after every wake-up from WFI. Its cycles are preemptible (they never delay
  a step), but they are CPU load: that is why the CPU column stops below the ISR column.
";

/// Notes that hold for the method (findings specific to a firmware version go in the report
/// that accompanies a regeneration).
const NOTES: &str = "\
- Above the ISR limit the firmware does not slow down: the timer keeps its period, handlers run
  back to back, updates are missed (overruns) and a rising edge can merge with the previous pulse
  (a step lost on the pins while the position counter counts it).
- The BSRR offset grows when an update arrives while the previous handler is still running. The
  falling edge comes at the compare event (`$0` + 72 ticks, `STORE_LATENCY_TICKS`, after the
  update) or at the end of the update handler, whichever is later: with the sweep's short pulse
  it is the handler's end (the X high times in the point list); with a pulse longer
  than the handler the high time is `$0` + 48 ticks + the falling store's latency − the rising
  store's, at least `$0` while the BSRR offsets spread by less than 48 ticks.
- Peripheral bridge stalls are modeled (TIM2 reads on APB1 5 cycles, GPIO on APB2 3, writes
  buffered); the APB2 figure is fitted to a silicon measurement, the APB1 one extrapolated.
- The step interrupt includes its own DWT self-measurement (about 25 cycles per entry; `$I`).
- The sweep measures one straight move per point. Back-to-back moves at the `$I` cap (moves
  changing at speed, a direction reversing at every junction) are the \"Moves changing at the
  rate cap\" table above, also checked by `bench/tests/firmware_lookahead.rs`
  (`back_to_back_moves_at_the_rate_cap_keep_every_step`: every step, no overrun); the cap's
  long-tick and low-time terms come from there.
- \"CPU\" includes the ramp interrupt (the engine's ramp half, pended by the step interrupt at
  each ramp millisecond, trigger and move start): a few hundred cycles per millisecond.
";

// today's date (UTC) as YYYY-MM-DD
fn utc_date() -> String {
    let days = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs() / 86_400) as i64;
    // Civil from days (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let mo = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + (mo <= 2) as i64;
    format!("{y:04}-{mo:02}-{d:02}")
}

// the last commit of the firmware sources, marked when they have uncommitted changes
pub fn firmware_commit() -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git").current_dir(super::repo_root()).args(args).output().ok().map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    // The last commit that touched the firmware, not HEAD (bench-only commits change nothing).
    let head = git(&["log", "-1", "--format=%h", "--", "src", "Cargo.toml", "Cargo.lock", "memory.x", "build.rs"]).unwrap_or_else(|| "?".into());
    let dirty = git(&["status", "--porcelain", "--", "src", "Cargo.toml", "Cargo.lock", "memory.x", "build.rs"]).is_some_and(|s| !s.is_empty());
    if dirty {
        format!("`{head}` + uncommitted changes in src/")
    } else {
        format!("`{head}`")
    }
}

// bytes the ELF puts in flash
fn flash_bytes(elf: &Path) -> u64 {
    use object::read::elf::{FileHeader, ProgramHeader};
    let Ok(bytes) = std::fs::read(elf) else { return 0 };
    let Ok(h) = object::elf::FileHeader32::<object::Endianness>::parse(&*bytes) else { return 0 };
    let Ok(endian) = h.endian() else { return 0 };
    h.program_headers(endian, &*bytes).map_or(0, |phs| {
        phs.iter()
            .filter(|ph| ph.p_type(endian) == object::elf::PT_LOAD && (0x0800_0000..0x0801_0000).contains(&ph.p_paddr(endian)))
            .map(|ph| ph.p_filesz(endian) as u64)
            .sum()
    })
}
