//! One measured point, its verdict and its one-line text (progress output and RESULTS.md's
//! point list). Produced by `measure.rs`, collected by `search.rs`.

use serde::Serialize;

use crate::emu::profile::FnCost;

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

    pub(super) fn failed(axes: usize, target_hz: u32, verdict: Verdict) -> Self {
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

pub(super) fn overruns_text(n: u64) -> String {
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
