//! The search for the highest sustainable master rate per axis count: an upward grid scan, the
//! load rates, then a bisection per criterion; the whole sweep runs axis counts in parallel.

use std::path::Path;

use anyhow::Result;
use serde::Serialize;

use super::measure::{prepare, run_point};
use super::point::{point_line, Point};
use super::setup::{settings_lines, Mode};

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
