//! What the engine and the planner derive from the settings: the step [`Timing`], the ramp
//! table (built into a [`Profile`]) with its [`Ramped`] report, and the planner's [`Limits`].
//!
//! Who uses it: the controller (at start-up and after a `$N=` that changes the profile), `$I`.

use super::values::Settings;
use crate::board::PinMap;
use crate::motion::ramp::{peak_slope, Profile, RampConfig, RampError, RampTable, SCurve, Shape, IDX_ONE, MAX_RATE_HZ};
use crate::motion::timing::{ns_to_ticks, Timing};
use crate::num::{round_u32, sqrt, u32_of};
use crate::planning::planner::{Limits, JUNCTION_DEVIATION_MM};
use crate::MAX_AXES;

/// Absolute floor of the step period (ticks; 144 = 500 kHz, the engine's design limit). The
/// binding limits are the pulse rule and the step handler's measured cost, both applied by
/// `Timing::min_period_for`.
pub const ISR_FLOOR_TICKS: u32 = 144;

/// The ramp the profile was built with, for `$I` and the planner's clamp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ramped {
    pub cfg: RampConfig,
    /// Fastest master rate the timing allows.
    pub max_rate_hz: u32,
    /// The axis limits asked for a faster top than fits in the table.
    pub table_limited: bool,
    /// The cap is dual-edge mode's (`$580`).
    pub dual: bool,
    /// The cap is DMA burst mode's (`$581`).
    pub dma: bool,
    /// DMA burst mode: the fastest master rate at a junction joined at speed (one axis;
    /// `Timing::max_junction_rate_for`); 0 in the other modes (no junction limit of their own).
    pub junction_hz: u32,
}

impl Ramped {
    /// What `s` asks for on `axes` axes, before the table is built.
    pub fn wanted(s: &Settings, axes: usize) -> Ramped {
        let timing = s.timing();
        Ramped::of(s.ramp_config(axes, &timing), &timing, false)
    }

    /// The report of `cfg` under `timing`.
    fn of(cfg: RampConfig, timing: &Timing, table_limited: bool) -> Ramped {
        let junction_hz = if timing.dma { timing.max_junction_rate_for(0) } else { 0 };
        Ramped { cfg, max_rate_hz: timing.max_rate_hz(), table_limited, dual: timing.dual, dma: timing.dma, junction_hz }
    }
}

impl Settings {
    /// The pin map `$2`, `$3` and `$580` ask for (the feeder's and the engine's).
    pub fn pins<const N: usize>(&self) -> PinMap<N> {
        let pins = crate::board::pin_map::<N>(self.step_invert, self.dir_invert);
        if self.dual_edge {
            pins.dual_edge()
        } else {
            pins
        }
    }

    /// `other` asks for the same pin map as `self` on `N` axes (`pins` compared without
    /// building both maps): the same `$580`, and `$3`, and `$2` unless dual-edge (its maps
    /// toggle, whatever the level), on the first `N` axes' bits.
    pub fn same_pins<const N: usize>(&self, other: &Settings) -> bool {
        let axes = (1u32 << N) - 1;
        let differ = |a: u8, b: u8| (a ^ b) as u32 & axes != 0;
        self.dual_edge == other.dual_edge
            && !differ(self.dir_invert, other.dir_invert)
            && (self.dual_edge || !differ(self.step_invert, other.step_invert))
    }

    /// Step timing in timer ticks.
    pub fn timing(&self) -> Timing {
        // f32 like the rest of the settings math.
        let pulse = ns_to_ticks(round_u32(self.pulse_us * 1000.0));
        let dir = ns_to_ticks(round_u32(self.dir_setup_us * 1000.0));
        let t = Timing::new(pulse, dir, ISR_FLOOR_TICKS);
        if self.dma_burst {
            t.burst(self.dual_edge)
        } else if self.dual_edge {
            t.dual_edge(0)
        } else {
            t
        }
    }

    /// Table rate per mm/s of path speed on the first `axes` axes: the largest `$100+i`, so no
    /// move's master runs faster than the table and `$40` is the finest axis's start, unless
    /// the table's top would then pass [`MAX_RATE_HZ`]: then lower, so that the fastest path
    /// speed a move may need (`top_path`) is exactly the top, and a coarser axis still
    /// reaches its own limits whatever the finer ones' (a finer axis's master scales the
    /// table up). The top at `MAX_RATE_HZ` leaves the table's low end (its distance sums, in
    /// 1/256 step) the most resolution that range allows.
    pub fn per_mm(&self, axes: usize) -> f32 {
        #[allow(clippy::manual_clamp, reason = "clamp's panic path costs flash")]
        let axes = axes.max(1).min(MAX_AXES);
        let finest = self.steps_per_mm.iter().take(axes).fold(0.0f32, |a, &b| a.max(b));
        finest.min(MAX_RATE_HZ as f32 / self.top_path(axes))
    }

    /// The fastest path speed (mm/s) a move on the first `axes` axes may need: no faster than
    /// all of them at their `$110+i` together, nor than the engine's cap for its master
    /// (`Timing::max_rate_for` its slaves) over the smallest share of the path a master of
    /// that many axes can have (`1 / √Σ 1/$100+i²` over the coarsest ones).
    fn top_path(&self, axes: usize) -> f32 {
        let timing = self.timing();
        // 1/$100+i, coarsest first (insertion sort: at most seven).
        let mut inv = [0.0f32; MAX_AXES];
        let mut v2 = 0.0f32;
        for i in 0..axes {
            let v = self.max_rate[i] / 60.0;
            v2 += v * v;
            let mut x = 1.0 / self.steps_per_mm[i];
            for slot in inv.iter_mut().take(i + 1) {
                if x > *slot {
                    core::mem::swap(&mut x, slot);
                }
            }
        }
        let (mut inv2, mut capped) = (0.0f32, 0.0f32);
        for (slaves, x) in inv.iter().take(axes).enumerate() {
            inv2 += x * x;
            capped = capped.max(timing.max_rate_for(slaves as u32) as f32 * sqrt(inv2));
        }
        sqrt(v2).min(capped)
    }

    /// What the planner takes from the settings for `N` axes, with the ramp table's top rate.
    pub fn planner_limits<const N: usize>(&self, vmax_hz: u32) -> Limits<N> {
        Limits {
            steps_per_mm: core::array::from_fn(|i| self.steps_per_mm[i]),
            max_rate: core::array::from_fn(|i| self.max_rate[i]),
            accel: core::array::from_fn(|i| self.accel[i]),
            ramp_accel: 1.0 / self.s_slope(),
            vmax_hz: vmax_hz.max(1),
            // The table's own path units: the axes in use ($42), as `Settings::build_profile`.
            per_mm: self.per_mm(self.axis_count(N)),
            junction_dev: JUNCTION_DEVIATION_MM,
            timing: self.timing(),
        }
    }

    /// The S-curve's peak slope `k` (`$41=1`, from `$582`), 1 for the trapezoid: moves are
    /// planned and walked at their acceleration over it.
    pub fn s_slope(&self) -> f32 {
        match self.shape {
            Shape::SCurve => peak_slope(self.flexible),
            Shape::Trapezoid => 1.0,
        }
    }

    /// The ramp table's top on `axes` axes once built (what the planner's limits take).
    pub fn wanted_vmax(s: &Settings, axes: usize) -> u32 {
        let mut p: Profile = Profile { ramp: crate::motion::ramp::RampTable::new(), timing: Timing::UNSET, per_mm: 0.0, scurve: crate::motion::ramp::SCurve::OFF };
        s.build_profile(axes, &mut p).cfg.vmax
    }

    /// The ramp asked for by the first `axes` axes (before the table's length is considered).
    /// The table is in path units (rate = path speed × [`Self::per_mm`]): its acceleration is
    /// twice the largest `$120+i` (a diagonal may accelerate faster than one axis; each move
    /// walks it at its own fraction), its top the fastest path speed the axes allow together
    /// (at most [`MAX_RATE_HZ`], which [`Self::per_mm`] keeps above every move's own cap), its
    /// start `$40` on the finest axis.
    pub fn ramp_config(&self, axes: usize, timing: &Timing) -> RampConfig {
        let _ = timing;
        // max/min, not clamp, here and below: clamp's panic message would link integer
        // formatting into the firmware.
        #[allow(clippy::manual_clamp, reason = "clamp's panic path costs flash")]
        let axes = axes.max(1).min(MAX_AXES);
        let c = self.per_mm(axes);
        let finest = self.steps_per_mm.iter().take(axes).fold(0.0f32, |a, &b| a.max(b));
        let mut accel = 0.0f32;
        let mut top2 = 0.0f32;
        for i in 0..axes {
            accel = accel.max(self.accel[i] * 2.0);
            let v = self.max_rate[i] / 60.0;
            top2 += v * v;
        }
        // S-curve: the table and every move's walk are the trapezoid's at a / k (the legs'
        // S then peaks at a: `ramp/scurve.rs`).
        let accel = accel * c / self.s_slope();
        #[allow(clippy::manual_clamp, reason = "clamp's panic path costs flash")]
        let vmax = u32_of(sqrt(top2) * c).max(1).min(MAX_RATE_HZ);
        // `$40` in steps/s of the finest axis: the same path speed in the table's units.
        let v0 = if c < finest { round_u32(self.ramp_start_hz as f32 * (c / finest)) } else { self.ramp_start_hz };
        #[allow(clippy::manual_clamp, reason = "clamp's panic path costs flash")]
        let v0 = v0.max(1).min(vmax);
        RampConfig {
            v0,
            vmax,
            accel: u32_of(accel.min(u32::MAX as f32)).max(1),
            shape: self.shape,
        }
    }

    /// Rebuilds `profile` (table and timing) for `axes` axes. A ramp too long for the table is
    /// built steeper (moves walk it at their own fraction), so the top stays the axes' max rate.
    pub fn build_profile<const L: usize>(&self, axes: usize, profile: &mut Profile<L>) -> Ramped {
        let timing = self.timing();
        let mut cfg = self.ramp_config(axes, &timing);
        let mut table_limited = false;
        profile.timing = timing;
        profile.per_mm = self.per_mm(axes);
        profile.scurve = match self.shape {
            Shape::SCurve => SCurve::build(self.flexible),
            Shape::Trapezoid => SCurve::OFF,
        };
        // The slowest axis's path acceleration in table units (S mode: at a / k, as the table): no move walks the table
        // slower (a move's is the smallest `$120+i / |unitᵢ|` over its axes, never below its
        // slowest axis's `$120+i`).
        #[allow(clippy::manual_clamp, reason = "clamp's panic path costs flash")]
        let n = axes.max(1).min(MAX_AXES);
        let slowest = self.accel.iter().take(n).fold(f32::MAX, |a, &b| a.min(b)) * profile.per_mm / self.s_slope();
        for attempt in 0..6 {
            // Entry 0 at most one ms of the slowest move's acceleration above `$40` (the
            // mean of the table's first ms when every axis accelerates alike).
            let lead = u32_of((slowest / cfg.accel.max(1) as f32 * IDX_ONE as f32).min((IDX_ONE / 2) as f32));
            match profile.ramp.build_led(cfg, lead) {
                // Too long for the table: a steeper table (every move walks it at its own
                // fraction, so no move runs faster), down to a lower top only as a last resort.
                Err(RampError::TooLong { .. }) if attempt < 4 => {
                    let ms = crate::num::f32_of_u64(RampTable::<L>::ramp_ms(&cfg));
                    cfg.accel = u32_of((cfg.accel as f32 * ms / (L as f32 - 2.0).max(1.0)).min(u32::MAX as f32 / 2.0)) + 1;
                }
                Err(RampError::TooLong { reachable_vmax }) => {
                    table_limited = true;
                    cfg.vmax = reachable_vmax.max(cfg.v0);
                }
                // Unreachable with the ranges `set` enforces; an empty table means every move
                // cruises at its own (clamped) rate, so the clamp falls to the start rate.
                Err(_) => cfg.vmax = cfg.v0,
                Ok(()) => break,
            }
        }
        Ramped::of(cfg, &timing, table_limited)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `same_pins` says what comparing the two pin maps says, for every `$2`, `$3` and `$580`.
    #[test]
    fn same_pins_is_pin_map_equality() {
        fn check<const N: usize>() {
            let base = Settings::DEFAULT;
            for dual in [false, true] {
                let mut a = base;
                a.dual_edge = dual;
                a.step_invert = 0x15;
                a.dir_invert = 0x2A;
                for other_dual in [false, true] {
                    for m in 0..=255u8 {
                        for (step, dir) in [(m, a.dir_invert), (a.step_invert, m), (m, m)] {
                            let mut b = base;
                            b.dual_edge = other_dual;
                            b.step_invert = step;
                            b.dir_invert = dir;
                            assert_eq!(a.same_pins::<N>(&b), a.pins::<N>() == b.pins::<N>(), "N {N} {dual} {other_dual} {step:#x} {dir:#x}");
                        }
                    }
                }
            }
        }
        check::<1>();
        check::<3>();
        check::<7>();
    }
}
