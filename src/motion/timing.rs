//! Step-driver timing as data: pulse width and direction setup/hold per driver family.
//!
//! Who uses it: settings defaults and docs; the engine itself only sees timer ticks
//! ([`Timing`]). Figures are the minimums from each driver's datasheet.

use crate::motion::rate::MAX_RATE_HZ;
use crate::TIMER_HZ;

/// Minimum timing a step/dir driver needs, in nanoseconds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DriverTiming {
    /// Minimum STEP high (active) time.
    pub pulse_ns: u32,
    /// Minimum STEP low (inactive) time.
    pub low_ns: u32,
    /// Minimum DIR stable before the STEP rising edge.
    pub dir_setup_ns: u32,
    /// Minimum DIR stable after the STEP rising edge.
    pub dir_hold_ns: u32,
}

/// TB6600 modules (opto-isolated inputs): sellers' manuals ask for ≥ 2.2 µs pulses and
/// ≥ 5 µs direction lead; we default to 3 µs pulses as the project guide demands.
pub const TB6600: DriverTiming =
    DriverTiming { pulse_ns: 3_000, low_ns: 3_000, dir_setup_ns: 5_000, dir_hold_ns: 5_000 };
/// TI DRV8825 datasheet (SLVSA73F), 7.6 Timing Requirements: t_WH/t_WL ≥ 1.9 µs,
/// t_SU/t_H ≥ 650 ns.
pub const DRV8825: DriverTiming =
    DriverTiming { pulse_ns: 1_900, low_ns: 1_900, dir_setup_ns: 650, dir_hold_ns: 650 };
/// Allegro A4988 datasheet, Figure 1 logic timing: STEP high/low ≥ 1 µs, setup/hold ≥ 200 ns.
pub const A4988: DriverTiming =
    DriverTiming { pulse_ns: 1_000, low_ns: 1_000, dir_setup_ns: 200, dir_hold_ns: 200 };
/// Trinamic TMC2209 datasheet rev 1.09, 13.1 STEP/DIR timing: t_SH/t_SL ≥ 100 ns,
/// t_DSU ≥ 20 ns.
pub const TMC2209: DriverTiming =
    DriverTiming { pulse_ns: 100, low_ns: 100, dir_setup_ns: 20, dir_hold_ns: 20 };

/// Timing the engine honours, in timer ticks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timing {
    /// Step pulse width: where the firmware sets the compare event (CCR1).
    pub pulse_ticks: u32,
    /// Direction setup: gap between a direction change and the next step edge.
    pub dir_setup_ticks: u32,
    /// Shortest step period allowed (pulse + low time + interrupt headroom).
    pub min_period_ticks: u32,
    /// Dual-edge stepping (`$580`): each step toggles its pin, no falling-edge event; the
    /// "pulse" is the shortest time between two toggles of one pin.
    pub dual: bool,
    /// DMA burst output (`$581`): TIM2's events have DMA store buffered words; the pulse is
    /// hardware-timed and the cost per step is the buffer fill's ([`DMA_BASE_TICKS`]).
    pub dma: bool,
}

impl Timing {
    /// 3 µs pulses, 5 µs direction setup: safe for every driver in this module until
    /// settings say otherwise. The 3 µs pulse (216 ticks) sets the shortest period to 504
    /// ticks, so this allows 142.9 kHz; 144 ticks (500 kHz) is only the absolute floor, below the
    /// handler's measured cost (`min_period_for`).
    pub const DEFAULT: Timing = Timing::new(216, 360, 144);

    /// All zero: "not set yet"; the engine uses [`Timing::DEFAULT`] in its place.
    pub const UNSET: Timing = Timing { pulse_ticks: 0, dir_setup_ticks: 0, min_period_ticks: 0, dual: false, dma: false };

    /// Timing from its parts (ticks); the shortest period is never below twice the pulse plus
    /// [`STORE_LATENCY_TICKS`] (the pulse is stretched by that much, see the firmware).
    pub const fn new(pulse_ticks: u32, dir_setup_ticks: u32, min_period_ticks: u32) -> Self {
        let floor = 2 * pulse_ticks + STORE_LATENCY_TICKS;
        Timing {
            pulse_ticks,
            dir_setup_ticks,
            min_period_ticks: if min_period_ticks > floor { min_period_ticks } else { floor },
            dual: false,
            dma: false,
        }
    }

    /// The same pulse and setup in DMA burst mode (`$581`), single- or dual-edge: every edge
    /// is a DMA store at a timer event, so the pulse is the compare value plus the stores'
    /// latency spread ([`DMA_MARGIN_TICKS`] each side) and the period's floor follows the pulse
    /// and low time alone (never below [`DMA_FLOOR_TICKS`], 1 MHz); the fill's cost comes in
    /// [`Self::min_period_for`].
    pub const fn burst(self, dual: bool) -> Self {
        let fall = dma_fall_ticks(self.pulse_ticks);
        let floor = if dual { fall } else { 2 * fall };
        let floor = if floor > DMA_FLOOR_TICKS { floor } else { DMA_FLOOR_TICKS };
        Timing { min_period_ticks: floor, dual, dma: true, ..self }
    }

    /// The same pulse and setup in dual-edge mode: a step is one toggle at an update event, so
    /// two toggles of a pin are at least one period minus the store jitter apart, and the
    /// period's floor is the pulse plus [`STORE_JITTER_TICKS`] (and `min_period_ticks`).
    pub const fn dual_edge(self, min_period_ticks: u32) -> Self {
        let floor = self.pulse_ticks + STORE_JITTER_TICKS;
        Timing { min_period_ticks: if min_period_ticks > floor { min_period_ticks } else { floor }, dual: true, ..self }
    }

    /// Shortest master period for a move with `slaves` slave axes: the pulse timing, the step
    /// handler's cost (so the CPU stays ≤ 95 % busy), and room for a low time of at least one
    /// pulse after a falling edge that comes only at the end of the handler (its longest run).
    pub const fn min_period_for(&self, slaves: u32) -> u32 {
        if self.dma {
            // The fill's cost per step (CPU ≤ 95 %, the DMA's bus cycles counted).
            let cpu = if slaves == 0 {
                DMA_LANE_TICKS
            } else if self.dual {
                DMA_DUAL_BASE_TICKS + DMA_DUAL_PER_SLAVE_TICKS * slaves
            } else {
                DMA_BASE_TICKS + DMA_PER_SLAVE_TICKS * slaves
            };
            return if cpu > self.min_period_ticks { cpu } else { self.min_period_ticks };
        }
        if self.dual {
            // One event per step: the handler's cost (CPU ≤ 95 %), and two toggles of a pin a
            // pulse apart when a long tick delays the second's store.
            let cpu = DUAL_BASE_TICKS + HANDLER_PER_SLAVE_TICKS * slaves;
            let long = (DUAL_LONG_TICKS + HANDLER_PER_SLAVE_TICKS * slaves + self.pulse_ticks).div_ceil(2);
            let p = if cpu > self.min_period_ticks { cpu } else { self.min_period_ticks };
            return if long > p { long } else { p };
        }
        let cpu = HANDLER_BASE_TICKS + HANDLER_PER_SLAVE_TICKS * slaves;
        // (A pulse within the gap handlers keep between a falling and the next rising store
        // needs no room of its own.)
        let low = if self.pulse_ticks > HANDLER_GAP_TICKS {
            HANDLER_FALL_TICKS + HANDLER_PER_SLAVE_TICKS * slaves + self.pulse_ticks
        } else {
            0
        };
        // A long tick (ramp work, a move change) must check for the compare event before the
        // next period's compare event comes, or it takes that one too and a pulse runs into
        // the next step.
        let long = (HANDLER_LONG_TICKS + HANDLER_PER_SLAVE_TICKS * slaves)
            .saturating_sub(self.pulse_ticks + STORE_LATENCY_TICKS + HANDLER_TAIL_TICKS);
        let mut p = self.min_period_ticks;
        if cpu > p {
            p = cpu;
        }
        if low > p {
            p = low;
        }
        if long > p {
            p = long;
        }
        p
    }

    /// Fastest master rate (steps/s) for a move with `slaves` slave axes.
    pub fn max_rate_for(&self, slaves: u32) -> u32 {
        (crate::TIMER_HZ / self.min_period_for(slaves).max(1)).min(MAX_RATE_HZ)
    }

    /// Fastest master rate (steps/s) at a junction joined at speed, for moves with up to
    /// `slaves` slave axes: in DMA burst mode a move change runs inside a buffer fill (the
    /// step half's two ticks and the ramp half's work twice), which must end before DMA
    /// reaches the entries after it ([`DMA_JUNCTION_BASE_TICKS`]). Elsewhere no limit of its
    /// own (`u32::MAX`: each move's cap binds, the step interrupt's long ticks are in it).
    pub fn max_junction_rate_for(&self, slaves: u32) -> u32 {
        if !self.dma {
            return u32::MAX;
        }
        self.max_rate_for(slaves).min(crate::TIMER_HZ / (DMA_JUNCTION_BASE_TICKS + DMA_JUNCTION_PER_SLAVE_TICKS * slaves))
    }

    /// Fastest master rate (steps/s) this timing allows any move (a single axis).
    pub fn max_rate_hz(&self) -> u32 {
        self.max_rate_for(0)
    }
}

/// Step-handler cost per master step, timer ticks (plus [`HANDLER_PER_SLAVE_TICKS`] per
/// slave): keeps the CPU ≤ 95 % busy, with about 1.5 % left for code placement. Measured:
/// bench/RESULTS.md, "Results" (the step-rate sweep with the caps lifted).
pub const HANDLER_BASE_TICKS: u32 = 245;
/// Extra handler ticks per slave axis (see [`HANDLER_BASE_TICKS`]).
pub const HANDLER_PER_SLAVE_TICKS: u32 = 17;
/// The longest step-handler run at speed, a move change, timer ticks (plus
/// [`HANDLER_PER_SLAVE_TICKS`] per slave). Measured: bench/RESULTS.md, "Moves changing at the
/// rate cap" (`ddastep_bench::emu::changes`).
pub const HANDLER_LONG_TICKS: u32 = 330;
/// From a handler's compare-flag check to its end (the self-measurement), less a margin.
pub const HANDLER_TAIL_TICKS: u32 = 10;
/// Where a late falling edge lands after the next update's rising store, timer ticks (plus
/// [`HANDLER_PER_SLAVE_TICKS`] per slave), for pulses over [`HANDLER_GAP_TICKS`]: a low time of
/// at least the pulse needs a period of this plus the pulse. Measured with margin:
/// `bench/tests/firmware_lookahead.rs` (back-to-back moves at the cap, 2 µs pulses).
pub const HANDLER_FALL_TICKS: u32 = 250;

/// The shortest time from a falling store to the next handler's rising store when a long
/// handler delays the next update, timer ticks: a pulse up to this needs no room for a low
/// time ([`HANDLER_FALL_TICKS`]). Measured with margin: `bench/tests/firmware_lookahead.rs`.
pub const HANDLER_GAP_TICKS: u32 = 48;

/// Step-handler cost per master step in dual-edge mode, timer ticks (plus
/// [`HANDLER_PER_SLAVE_TICKS`] per slave): the toggle costs about what the compare check saves,
/// so the same as [`HANDLER_BASE_TICKS`]. Measured: bench/RESULTS.md, "Dual-edge mode".
pub const DUAL_BASE_TICKS: u32 = 245;
/// Dual-edge mode: a long tick (a move change) brings two toggles of a pin to `2 × period −
/// this` apart (plus [`HANDLER_PER_SLAVE_TICKS`] per slave), so the period is at least half of
/// this plus the pulse. Measured with margin: `bench/tests/firmware_dual_edge.rs`.
pub const DUAL_LONG_TICKS: u32 = 320;

/// DMA burst mode: the buffer fill's cost per master step of a move with slaves, timer ticks
/// (plus [`DMA_PER_SLAVE_TICKS`] per slave; DMA's bus cycles and `idle` counted). Bound by
/// back-to-back moves, where a fill late after a move change must not let DMA reach words not
/// yet whole (`$I`'s `late`). Measured: bench/RESULTS.md, "DMA burst mode";
/// `bench/tests/firmware_dma.rs`.
pub const DMA_BASE_TICKS: u32 = 100;
/// The same in dual-edge DMA mode (plus [`DMA_DUAL_PER_SLAVE_TICKS`] per slave; one axis
/// takes [`DMA_LANE_TICKS`]): back-to-back moves bind. Measured: bench/RESULTS.md, "DMA burst
/// mode, dual-edge"; `bench/tests/firmware_dma.rs`.
pub const DMA_DUAL_BASE_TICKS: u32 = 170;
/// Extra fill ticks per slave axis in dual-edge DMA mode.
pub const DMA_DUAL_PER_SLAVE_TICKS: u32 = 10;
/// DMA burst mode, one axis (the fill's own lane, entry by entry): its cost does not bind
/// below the 1 MHz floor ([`DMA_FLOOR_TICKS`]). Measured: `bench/tests/firmware_dma.rs`,
/// `one_axis_runs_at_the_dma_cap`.
pub const DMA_LANE_TICKS: u32 = 72;
/// Extra fill ticks per slave axis in DMA burst mode.
pub const DMA_PER_SLAVE_TICKS: u32 = 13;
/// DMA burst mode: the shortest master period at a junction joined at speed, timer ticks (plus
/// [`DMA_JUNCTION_PER_SLAVE_TICKS`] per slave of the busier move): a move change runs inside
/// one buffer fill, which must end before DMA reaches the entries after it. Measured: no late
/// fill in `bench/tests/firmware_dma.rs`'s back-to-back moves; `$I` prints the one-axis rate.
pub const DMA_JUNCTION_BASE_TICKS: u32 = 200;
/// Extra junction ticks per slave axis in DMA burst mode (see [`DMA_JUNCTION_BASE_TICKS`]).
pub const DMA_JUNCTION_PER_SLAVE_TICKS: u32 = 20;
/// Shortest period in DMA burst mode: 72 ticks, 1 MHz (the ramp tables' top rate).
pub const DMA_FLOOR_TICKS: u32 = 72;
/// DMA burst mode: the spread of a DMA store's latency after its timer event (arbitration,
/// the bus matrix, a bridge busy with the other channel's store), timer ticks. The falling
/// edge's compare event comes this much after the pulse width, and the low time gets the
/// same margin.
pub const DMA_MARGIN_TICKS: u32 = 8;

/// DMA burst mode: the falling edge's compare value for a pulse of `pulse_ticks` (the pulse
/// plus [`DMA_MARGIN_TICKS`]).
pub const fn dma_fall_ticks(pulse_ticks: u32) -> u32 {
    pulse_ticks + DMA_MARGIN_TICKS
}

/// Timer ticks from an update event to the step handler's BSRR store, at most (rounded up to
/// 1 µs): the compare event comes this much after the pulse width, so the high time is never
/// short. Measured: bench/golden/paper_532.json, `bsrr_offset_*`.
pub const STORE_LATENCY_TICKS: u32 = 72;

/// Spread of that latency (the instruction an interrupt lands on, flash wait states): the
/// engine adds it to the direction-setup gap, since the direction store and the step store are
/// two interrupts whose latencies differ by up to this much.
pub const STORE_JITTER_TICKS: u32 = 24;

/// Converts nanoseconds to timer ticks, rounding up so a minimum is never undercut.
pub const fn ns_to_ticks(ns: u32) -> u32 {
    // 72 ticks per µs is 9 per 125 ns (32-bit math: no 64-bit division in the firmware).
    const _: () = assert!(TIMER_HZ == 72_000_000);
    let ns = if ns > u32::MAX / 9 { u32::MAX / 9 } else { ns };
    (ns * 9).div_ceil(125)
}

/// Converts timer ticks to nanoseconds (rounded down).
pub const fn ticks_to_ns(ticks: u64) -> u64 {
    ticks * 1_000_000_000 / TIMER_HZ as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ns_round_trip_never_undercuts() {
        for ns in [0u32, 1, 13, 14, 100, 650, 1_000, 1_900, 3_000, 1_000_000] {
            let t = ns_to_ticks(ns);
            assert!(ticks_to_ns(t as u64) + 1 >= ns as u64, "{ns} ns -> {t} ticks");
            assert!(t == 0 || ticks_to_ns(t as u64 - 1) < ns as u64);
        }
        assert_eq!(ns_to_ticks(1_000), 72);
    }
}
