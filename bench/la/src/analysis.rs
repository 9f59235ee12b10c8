//! The streaming analyzer: level reports in, [`Report`] out. Readers and the virtual bench both
//! feed it; see the module docs of [`crate`] for the rules.
//!
//! Pipeline per report: glitch filter (confirms edges in time order) → batch of one timestamp →
//! dir edges, then step edges, then one deviation sample per axis that stepped. Applying dir
//! before step makes a dir change and a step in the same sample count in the new direction
//! with 0 ns setup; applying all steps before sampling makes simultaneous master and slave
//! steps count together.

use anyhow::{bail, Result};

use super::axis::AxisState;
use super::deviation::DeviationTracker;
use super::glitch::{Edge, GlitchFilter, Observed};
use super::rate::{cruise_bins, BIN_PS, MAX_BINS};
use super::ratio::reduce;
use super::report::{AxisReport, Cruise, Expectation, Report, Series};

/// Cruise: bins whose master rate is at least this fraction of its maximum.
pub const CRUISE_FRACTION: f64 = 0.99;

/// Which channels carry one axis.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AxisChannels {
    pub name: String,
    pub step: usize,
    pub dir: Option<usize>,
}

impl AxisChannels {
    // name an axis and its channel indices
    pub fn new(name: &str, step: usize, dir: Option<usize>) -> Self {
        Self {
            name: name.to_string(),
            step,
            dir,
        }
    }
}

/// What to check.
#[derive(Clone, Debug, Default)]
pub struct Config {
    /// Axes in ratio order.
    pub axes: Vec<AxisChannels>,
    /// Dir low means + instead of high.
    pub dir_invert: bool,
    /// Dual-edge stepping: both edges of a step line are steps (TMC22xx `dedge`, ddastep's
    /// `$580`); the high and low widths are then the spacing between two toggles.
    pub dual_edge: bool,
    /// Pulses narrower than this are glitches (0: only zero-width ones).
    pub min_glitch_ps: u64,
    /// Expected step ratio, in axis order (compared after reducing by the gcd).
    pub expect: Option<Vec<u64>>,
}

impl Config {
    // check these axes with default settings
    pub fn new(axes: Vec<AxisChannels>) -> Self {
        Self {
            axes,
            ..Self::default()
        }
    }
}

/// What a channel is for.
#[derive(Clone, Copy, Debug)]
enum Role {
    Step(usize),
    Dir(usize),
}

/// Streaming step/dir checker.
pub struct Analyzer {
    config: Config,
    roles: Vec<Option<Role>>,
    filter: GlitchFilter,
    axes: Vec<AxisState>,
    deviation: DeviationTracker,
    ready: Vec<Edge>,
    batch: Vec<Edge>,
    counts: Vec<u64>,
    stepped: Vec<bool>,
    origin_ps: Option<u64>,
    now_ps: u64,
    bin_ps: u64,
}

impl Analyzer {
    // build an analyzer; fails when channels are shared or the expectation does not fit
    pub fn new(config: Config) -> Result<Self> {
        if config.axes.is_empty() {
            bail!("no axes to check");
        }
        if let Some(expect) = &config.expect {
            if expect.len() > config.axes.len() {
                let names: Vec<_> = config.axes.iter().map(|a| a.name.as_str()).collect();
                bail!(
                    "--expect has {} terms but only {} axes are mapped ({}); name the step \
                     channel of each axis in ratio order with --map, e.g. --map X=D0,Y=D1,Z=D2",
                    expect.len(),
                    names.len(),
                    names.join(", ")
                );
            }
        }
        let channels = config
            .axes
            .iter()
            .flat_map(|a| [Some(a.step), a.dir])
            .flatten()
            .max()
            .unwrap_or(0)
            + 1;
        let mut roles = vec![None; channels];
        for (i, axis) in config.axes.iter().enumerate() {
            for (channel, role) in [(Some(axis.step), Role::Step(i)), (axis.dir, Role::Dir(i))] {
                let Some(channel) = channel else { continue };
                if roles[channel].is_some() {
                    bail!("channel {channel} is mapped twice (axis {})", axis.name);
                }
                roles[channel] = Some(role);
            }
        }
        let n = config.axes.len();
        Ok(Self {
            filter: GlitchFilter::new(channels, config.min_glitch_ps),
            axes: (0..n).map(|_| AxisState::new(config.dir_invert, config.dual_edge)).collect(),
            deviation: DeviationTracker::new(n),
            config,
            roles,
            ready: Vec::new(),
            batch: Vec::new(),
            counts: vec![0; n],
            stepped: vec![false; n],
            origin_ps: None,
            now_ps: 0,
            bin_ps: BIN_PS,
        })
    }

    // report `channel`'s level at `time_ps`; earlier times than already seen count as now
    pub fn edge(&mut self, time_ps: u64, channel: usize, level: bool) {
        self.advance(time_ps);
        let Some(Some(role)) = self.roles.get(channel).copied() else {
            return;
        };
        if self.filter.observe(self.now_ps, channel, level) == Observed::Initial {
            match role {
                Role::Dir(axis) => self.axes[axis].initial_dir(level),
                // A step line's start level needs nothing: widths start at its first edge.
                Role::Step(_) => {}
            }
        }
    }

    // tell the analyzer that time has reached `time_ps` (capture end, idle stretches)
    pub fn advance(&mut self, time_ps: u64) {
        self.origin_ps.get_or_insert(time_ps);
        self.now_ps = self.now_ps.max(time_ps);
        self.filter.confirm(self.now_ps, &mut self.ready);
        self.commit_ready();
    }

    // finish the capture and compute the report
    pub fn finish(mut self) -> Report {
        self.filter.confirm_all(&mut self.ready);
        self.commit_ready();
        self.flush_batch();
        self.report()
    }

    // group confirmed edges by timestamp
    fn commit_ready(&mut self) {
        let ready = std::mem::take(&mut self.ready);
        for edge in &ready {
            if self
                .batch
                .first()
                .is_some_and(|b| b.time_ps != edge.time_ps)
            {
                self.flush_batch();
            }
            self.batch.push(*edge);
        }
        self.ready = ready;
        self.ready.clear();
    }

    // apply one timestamp's edges: dir first, then steps, then deviation samples
    fn flush_batch(&mut self) {
        let Some(time_ps) = self.batch.first().map(|e| e.time_ps) else {
            return;
        };
        let bin = self.bin_index(time_ps);
        for edge in &self.batch {
            if let Some(Role::Dir(axis)) = self.roles[edge.channel] {
                self.axes[axis].dir_edge(time_ps, edge.level);
            }
        }
        for edge in &self.batch {
            if let Some(Role::Step(axis)) = self.roles[edge.channel] {
                if self.axes[axis].step_edge(time_ps, edge.level, bin) {
                    self.counts[axis] += 1;
                    self.stepped[axis] = true;
                }
            }
        }
        for master in 0..self.axes.len() {
            if std::mem::take(&mut self.stepped[master]) {
                self.deviation.master_step(master, &self.counts);
            }
        }
        self.batch.clear();
    }

    // rate bin of a time, widening all bins when the capture outgrows them
    fn bin_index(&mut self, time_ps: u64) -> usize {
        let since = time_ps - self.origin_ps.unwrap_or(0);
        while since / self.bin_ps >= MAX_BINS as u64 {
            self.bin_ps *= 2;
            self.axes.iter_mut().for_each(|a| a.bins.coarsen());
        }
        (since / self.bin_ps) as usize
    }

    // turn the final state into a report
    fn report(&self) -> Report {
        let duration_ps = self.now_ps - self.origin_ps.unwrap_or(self.now_ps);
        let used = self.axes.iter().map(|a| a.bins.len()).max().unwrap_or(0);
        let bins = used.max(duration_ps.div_ceil(self.bin_ps) as usize);
        let rates: Vec<Vec<f64>> = self.axes.iter().map(|a| a.bins.rates_hz(bins)).collect();
        let master = (0..self.axes.len())
            .filter(|&i| self.counts[i] > 0)
            .max_by(|&a, &b| self.counts[a].cmp(&self.counts[b]).then(b.cmp(&a)));
        let window = master.and_then(|m| cruise_bins(&rates[m], CRUISE_FRACTION));
        let ms_per_bin = self.bin_ps as f64 / 1e9;

        let axes = self.axes.iter().enumerate().map(|(i, axis)| {
            let cruise = window.clone().map(|w| axis.bins.stats(w));
            let cruise = cruise.filter(|s| s.n > 0);
            let channel_glitches = |c: Option<usize>| c.map_or(0, |c| self.filter.glitches(c));
            let spec = &self.config.axes[i];
            AxisReport {
                name: spec.name.clone(),
                steps: axis.rises,
                net_steps: axis.net,
                dir_changes: axis.dir_changes,
                max_rate_hz: rates[i].iter().copied().fold(0.0, f64::max),
                cruise_rate_hz: cruise.and_then(|s| s.mean_ps()).map(|p| 1e12 / p),
                jitter_std_ns: cruise.and_then(|s| s.std_dev_ps()).map(|p| p / 1e3),
                jitter_pp_ns: cruise.and_then(|s| s.spread_ps()).map(|p| p as f64 / 1e3),
                min_high_ns: axis.timing.min_high_ps.map(ps_to_ns),
                min_low_ns: axis.timing.min_low_ps.map(ps_to_ns),
                min_dir_setup_ns: axis.timing.min_dir_setup_ps.map(ps_to_ns),
                min_dir_hold_ns: axis.timing.min_dir_hold_ps.map(ps_to_ns),
                max_deviation_steps: master
                    .filter(|&m| m != i)
                    .map(|m| self.deviation.max_deviation(m, i, &self.counts)),
                glitches: channel_glitches(Some(spec.step)) + channel_glitches(spec.dir),
            }
        });
        let axes: Vec<AxisReport> = axes.collect();
        let cruise = master.zip(window).and_then(|(m, w)| {
            Some(Cruise {
                start_ms: w.start as f64 * ms_per_bin,
                end_ms: w.end as f64 * ms_per_bin,
                rate_hz: axes[m].cruise_rate_hz?,
            })
        });
        let ratio = reduce(&self.counts);
        let expect = self
            .config
            .expect
            .as_ref()
            .map(|expected| self.expectation(expected));
        Report {
            duration_ns: ps_to_ns(duration_ps),
            bin_ms: ms_per_bin,
            glitches: axes.iter().map(|a| a.glitches).sum(),
            master,
            ratio,
            expect,
            cruise,
            series: self.series(master, bins, rates),
            axes,
        }
    }

    // the --expect check: every mapped axis when the terms cover them all, else the axes
    // that stepped (axes with no steps do not count against a shorter ratio)
    fn expectation(&self, expected: &[u64]) -> Expectation {
        let names = |idx: &[usize]| -> Vec<String> {
            idx.iter().map(|&i| self.config.axes[i].name.clone()).collect()
        };
        let compared: Vec<usize> = if expected.len() == self.counts.len() {
            (0..self.counts.len()).collect()
        } else {
            (0..self.counts.len())
                .filter(|&i| self.counts[i] > 0)
                .collect()
        };
        let mapping = (compared.len() != expected.len()).then(|| {
            let stepped = names(&compared);
            format!(
                "--expect {} has {} terms but {} of the {} mapped axes stepped ({}); give one \
                 term per stepping axis, or pick the axes in ratio order with --map, e.g. --map {}",
                expected.iter().map(u64::to_string).collect::<Vec<_>>().join(":"),
                expected.len(),
                stepped.len(),
                self.counts.len(),
                if stepped.is_empty() { "none".to_string() } else { stepped.join(", ") },
                self.config.axes[..expected.len()]
                    .iter()
                    .map(|a| format!("{0}={0}_STEP", a.name))
                    .collect::<Vec<_>>()
                    .join(",")
            )
        });
        let counts: Vec<u64> = compared.iter().map(|&i| self.counts[i]).collect();
        Expectation {
            pass: mapping.is_none()
                && counts.iter().any(|&c| c > 0)
                && reduce(expected) == reduce(&counts),
            expected: expected.to_vec(),
            axes: names(&compared),
            mapping_error: mapping,
        }
    }

    // rate and deviation curves for plotting
    fn series(&self, master: Option<usize>, bins: usize, rate_hz: Vec<Vec<f64>>) -> Series {
        let deviation_steps = (0..self.axes.len())
            .map(|i| match master {
                Some(m) if m != i => {
                    let (mc, sc) = (
                        self.axes[m].bins.cumulative_rises(bins),
                        self.axes[i].bins.cumulative_rises(bins),
                    );
                    let slope = self.counts[i] as f64 / self.counts[m] as f64;
                    mc.iter()
                        .zip(&sc)
                        .map(|(&k, &s)| s as f64 - k as f64 * slope)
                        .collect()
                }
                _ => Vec::new(),
            })
            .collect();
        Series {
            rate_hz,
            deviation_steps,
        }
    }
}

// picoseconds to nanoseconds
fn ps_to_ns(ps: u64) -> f64 {
    ps as f64 / 1e3
}
