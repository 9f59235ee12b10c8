//! The ramp walk: where on the ramp table the running motion is, one update per millisecond.
//!
//! Who uses it: the step engine, at each millisecond of timer time and when a move starts.
//!
//! The index (Q20) is a path speed, the same across moves (see [`crate::motion::prepared`]), so it
//! simply carries over from one move to the next. Each millisecond the walk moves it by the
//! running move's walk rate: up towards the move's cruise index while accelerating, down
//! towards the exit index once decelerating (to 0 under a feed hold or when no successor is
//! queued yet). The deceleration starts when the master steps left are at most the distance
//! from the current index down to the exit, from the table's distance sums (an integer
//! multiply, no division): it steps one walk down at once and restarts the millisecond, so the
//! way down samples the table exactly as the distance assumes (a left Riemann sum: the sums'
//! integral less half the end slopes). The walk goes up only if the way down from one walk up
//! still fits in the steps left, otherwise it stays (cruises) until the trigger fires.
//! An override may move the cruise index while the move runs (the engine reads it once per
//! ms): above it the walk goes down to it at the same rate, below it up as above; a target
//! that rises while walking down (a successor queued late, a higher cruise) ends the
//! deceleration.
//!
//! Who runs it: the engine's ramp half, in its own interrupt below the step interrupt: a ramp
//! millisecond moves the index, and the distances it needs next (the trigger here, the one from
//! a walk up) are left pending ([`Walk::pending`]) until the ramp half settles them before it
//! publishes the trigger.

use crate::motion::prepared::RampPlan;
use crate::motion::ramp::{Period, RampTable};

/// Steps added to the deceleration distance (0: an early start would leave steps to crawl at
/// the table's first entry; a late one ends at most a step's worth of walk high).
pub const DECEL_MARGIN: u32 = 0;

/// What a millisecond of walking did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// The index (or the trigger) changed: set the period again.
    Moved,
    /// Nothing changed.
    Same,
    /// Walking down to 0 has come to rest.
    AtRest,
}

/// Work left after a ramp millisecond or a move change (the ramp half does it before it
/// publishes): the trigger distance for the current index and target, then the one from a walk
/// up.
const SETTLED: u8 = 0;
/// The trigger distance for the current index and target is due (bit).
pub const TRIGGER: u8 = 2;
const UP: u8 = 4;

/// The walk's state.
#[derive(Clone, Copy, Debug, Default)]
pub struct Walk {
    /// Table index, Q20.
    pub idx: u32,
    /// Walking down (towards the exit, or 0 under a hold).
    pub decel: bool,
    /// Start walking down once the master steps left are at most this.
    pub decel_at: u32,
    /// The target `decel_at` and `up_at` were computed for.
    pub decel_for: u32,
    /// The deceleration distance from one walk up: going up needs at least this many steps
    /// left (and it becomes `decel_at` there).
    pub up_at: u32,
    /// Distances still to compute ([`TRIGGER`], the one from a walk up).
    pub pending: u8,
    /// `decel_for`'s distance sum and slope on the table (so the distance from one walk up
    /// costs only its own end).
    t_sum: u32,
    t_slope: u32,
}

impl Walk {
    /// From rest.
    pub const REST: Walk =
        Walk { idx: 0, decel: false, decel_at: 0, decel_for: u32::MAX, up_at: u32::MAX, pending: SETTLED, t_sum: 0, t_slope: 0 };

    /// True when a distance is pending ([`TRIGGER`], the one from a walk up).
    #[inline(always)]
    pub fn unsettled(&self) -> bool {
        self.pending != SETTLED
    }

    /// One millisecond has passed: move the index. Returns what changed. The distances it
    /// needs were computed before; the new ones are left pending ([`Self::pending`]).
    #[inline(always)]
    pub fn per_ms(&mut self, plan: &RampPlan, target: u32, left: u32) -> Step {
        if self.decel {
            if self.idx > target {
                self.idx = self.idx.saturating_sub(plan.walk_q).max(target);
                return Step::Moved;
            }
            if target > self.idx {
                // The target rose (a successor came after all, or an override raised the
                // cruise): the deceleration is over; up again where the way down fits.
                self.decel = false;
                self.pending |= TRIGGER;
            }
            return if target == 0 { Step::AtRest } else { Step::Same };
        }
        if self.idx > plan.cruise_q {
            // An override lowered the cruise: down to it at the move's own rate (the trigger
            // from the higher index fires early until it is computed again).
            self.idx = self.idx.saturating_sub(plan.walk_q).max(plan.cruise_q);
            self.pending |= TRIGGER;
            return Step::Moved;
        }
        if target != self.decel_for {
            self.pending |= TRIGGER; // a successor came (or went): both distances again
            return Step::Same;
        }
        // Up one walk only if the way down from there still fits in the steps left;
        // otherwise stay (cruise) until the trigger for this index.
        if self.idx < plan.cruise_q && left >= self.up_at {
            self.idx = (self.idx + plan.walk_q).min(plan.cruise_q);
            self.decel_at = self.up_at;
            self.pending |= UP;
            return Step::Moved;
        }
        Step::Same
    }

    /// Sets the target the distances are computed for (its sum and slope on the table).
    #[inline(always)]
    fn aim<const L: usize>(&mut self, target: u32, table: &RampTable<L>) {
        self.decel_for = target;
        let t = target.min(table.top_q());
        self.t_sum = table.sum_at(t);
        self.t_slope = table.per_ms_at(t);
    }

    /// Master steps walking down from `idx` to `decel_for` (samples at idx − walk, …, target, one
    /// per ms: the table distance less half the end slopes, plus [`DECEL_MARGIN`]), with the
    /// target's end cached; none when `idx` is not above the target.
    // Out of line (in the DMA fill's block): three callers (trigger, walk up, priming).
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.decel_from")]
    fn decel_from<const L: usize>(&self, idx: u32, plan: &RampPlan, table: &RampTable<L>) -> u32 {
        if idx <= self.decel_for {
            return DECEL_MARGIN;
        }
        ends_steps(table.sum_at(idx) - self.t_sum, table.per_ms_at(idx).saturating_sub(self.t_slope), plan)
    }

    /// Both distances again on the next ticks (the cruise changed); the trigger in force
    /// stays until then.
    #[inline(always)]
    pub fn replan(&mut self) {
        self.pending |= TRIGGER;
    }

    /// The trigger for a new move at the next tick; until then it cannot fire.
    #[inline(always)]
    pub fn defer_decel(&mut self) {
        self.decel_at = 0;
        self.decel_for = u32::MAX;
        self.up_at = u32::MAX;
        self.pending = TRIGGER;
    }

    /// Pending trigger work: the trigger for the current index and `target` (only when
    /// [`TRIGGER`] is pending).
    // Out of line (in the DMA fill's block): the ramp half runs it from `settle` and from
    // priming a successor; inlined in both it cost ~300 B of flash for no cycle saved that
    // matters (once per trigger change, not per step).
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.settle_trigger")]
    pub fn settle_trigger<const L: usize>(&mut self, plan: &RampPlan, target: u32, table: &RampTable<L>) {
        self.aim(target, table);
        self.decel_at = self.decel_from(self.idx, plan, table);
        self.pending = UP;
    }

    /// Pending trigger work: the distance from one walk up (the last piece).
    #[inline(always)]
    pub fn settle_up<const L: usize>(&mut self, plan: &RampPlan, table: &RampTable<L>) {
        self.up_at = if self.idx < plan.cruise_q {
            self.decel_from((self.idx + plan.walk_q).min(plan.cruise_q), plan, table)
        } else {
            u32::MAX
        };
        self.pending = SETTLED;
    }
}

/// Steps of a walk down over table distance `d` whose end slopes differ by `slopes`.
#[inline(always)]
fn ends_steps(d: u32, slopes: u32, plan: &RampPlan) -> u32 {
    let ends = (slopes as u64 * plan.walk_q as u64) >> 21;
    let steps = ((d as u64).saturating_sub(ends).min(u32::MAX as u64) * plan.dist_q as u64) >> 24;
    (steps.min(u32::MAX as u64 - DECEL_MARGIN as u64) as u32) + DECEL_MARGIN
}

impl Walk {
    /// Starts walking down now: one walk down at once (the caller restarts the millisecond).
    #[inline(always)]
    pub fn start_decel(&mut self, plan: &RampPlan, target: u32) {
        self.decel = true;
        self.decel_at = 0;
        self.pending = SETTLED;
        if self.idx > target {
            self.idx = self.idx.saturating_sub(plan.walk_q).max(target);
        }
    }
}

/// The table's period (bits) at index `idx` (0 for an empty table: moves cruise).
#[inline(always)]
pub fn base_at<const L: usize>(idx: u32, table: &RampTable<L>) -> u32 {
    if table.is_empty() {
        0
    } else {
        table.period_at(idx).to_bits()
    }
}

/// [`scaled`] of [`base_at`]: a move's master period (bits) at index `idx`. Out of line (in
/// the DMA fill's block): the ramp half's three callers (its period, the period one walk down,
/// a successor's) share one copy.
#[inline(never)]
#[cfg_attr(target_os = "none", link_section = ".fill.period_bits")]
pub fn period_bits<const L: usize>(idx: u32, table: &RampTable<L>, plan: &RampPlan, min: Period) -> u32 {
    scaled(base_at(idx, table), idx, plan, min).to_bits()
}

/// A move's master period from the table's period `base` (bits) at index `idx`: scaled by its
/// master's share, never below `min`, nor below the cruise up to its index (above it, walking
/// down to a cruise an override lowered, the table alone).
#[inline(always)]
pub fn scaled(base: u32, idx: u32, plan: &RampPlan, min: Period) -> Period {
    let scaled = ((base as u64 * plan.scale as u64) >> 16).min(u32::MAX as u64) as u32;
    let floor = if idx > plan.cruise_q { min } else { plan.cruise.max(min) };
    Period::from_bits(scaled).max(floor)
}
