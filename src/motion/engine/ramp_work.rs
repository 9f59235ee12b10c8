//! The step engine's ramp work: the ramp millisecond, the pieces of work it leaves for the
//! ticks after it (the period at a new index, its look-ahead one walk on, the deceleration
//! trigger, the distance from a walk up) and how they are spread over ticks.
//!
//! Who uses it: `Engine::tick` (the parent module), one piece at most per tick while the tick's
//! own period is short. A piece costs about 150–260 modeled cycles on top of a step (the
//! bench's per-entry ISR log); after one, and after a move change or a trigger, [`SPACE`] plain
//! ticks let the next edges catch up before the next piece, and a ramp millisecond due while
//! pieces are pending waits for them. With a long period (slow steps, a direction change's
//! gaps excepted) everything due runs at once.

use core::sync::atomic::Ordering::Relaxed;

use super::{Engine, Phase};
use crate::queue::State;
use crate::ramp::Period;
use crate::walk::{base_at, scaled, Step as WalkStep, FRESH, FRESH_MASK, PERIOD, PREDICT, TRIGGER};
use crate::TICKS_PER_MS;

/// A tick whose own period (the gap from its update event to the next) is shorter than this
/// (2048 ticks: above 35 kHz, or a direction change's short gaps) runs at most one piece of
/// ramp work, so its ARR store lands before the next update event; with a longer period it
/// does all that is due at once.
pub(super) const SHORT_GAP: u32 = 2048;
/// Plain ticks between two long ones (see `Engine::spaced`): four pieces of ramp work and
/// their spacing take 52 ticks, inside the 72 ticks of a millisecond at the 72 kHz where a
/// period gets shorter than the longest tick (at 35–72 kHz the millisecond's catch-up fits
/// in its period).
const SPACE: u8 = 12;

impl<const N: usize, const L: usize> Engine<'_, N, L> {
    /// A ramp millisecond due now waits while this tick's period is short and ramp work is
    /// still pending (it would run all of it at once) or the tick must run none ([`FRESH`]);
    /// with a long period it runs at once. (Work is pending at a millisecond only after a move
    /// change or a trigger just before it: the pieces of one millisecond and their spacing
    /// fit in it.)
    #[inline(always)]
    pub(super) fn quiet_tick(&self) -> bool {
        self.walk.pending != 0 && self.gap_in < SHORT_GAP
    }


    /// Starts walking down: one walk down now and a fresh millisecond for it.
    #[inline(never)]
    pub(super) fn start_decel(&mut self) {
        let target = self.target();
        self.walk.start_decel(&self.plan, target);
        self.ms_left = TICKS_PER_MS as i32;
        self.period_soon();
        self.walk.pending |= PREDICT;
        self.fresh(1);
        self.spaced();
    }

    /// After a long tick with a short period: [`SPACE`] plain ticks (with work pending)
    /// before the next piece of ramp work, so the delay it added to the next edges is made up
    /// first (at 95 % load a plain tick makes up about 5 % of a period).
    #[inline(always)]
    pub(super) fn spaced(&mut self) {
        if self.gap_in < SHORT_GAP {
            self.space = SPACE;
        }
    }

    /// No ramp work on this tick and the `n - 1` after it (the count never drops).
    #[inline(always)]
    pub(super) fn fresh(&mut self, n: u8) {
        if self.walk.pending & FRESH_MASK < n * FRESH {
            self.walk.pending = (self.walk.pending & !FRESH_MASK) | n * FRESH;
        }
    }

    /// The exit target: 0 under a hold or when no successor is queued yet; never above the
    /// cruise (an override may have lowered it below the planned exit).
    #[inline(always)]
    pub(super) fn target(&self) -> u32 {
        if self.hold || !self.ring.has_next() {
            0
        } else {
            // SAFETY: an atomic field of the running slot.
            unsafe { (*self.cur).exit_q.load(Relaxed) }.min(self.plan.cruise_q)
        }
    }

    /// One millisecond has passed: move along the ramp.
    #[inline(never)]
    pub(super) fn walk_ramp(&mut self) {
        if !matches!(self.phase, Phase::Run | Phase::Dir) {
            return;
        }
        while self.walk.unsettled() {
            // Slow steps: the work of the ticks in between happens here.
            self.settle();
        }
        self.cruise_update();
        let target = self.target();
        match self.walk.per_ms(&self.plan, target, self.left) {
            WalkStep::Same => {}
            WalkStep::AtRest if self.hold => {
                self.phase = Phase::Held;
                self.publish(State::Held);
            }
            _ => {
                if self.walk.idx == self.next_idx {
                    self.base = self.next_base;
                    self.apply_period();
                } else {
                    self.period_soon();
                }
                self.walk.pending |= PREDICT;
                self.spaced();
            }
        }
    }

    /// The running move's cruise as the feeder last priced it (an override changed); a new
    /// index re-plans the trigger. (Relaxed: the interrupt reads both while the feeder cannot
    /// run, so it sees either store order's halves as [`crate::prepared::Prepared`] describes.)
    #[inline(always)]
    pub(super) fn cruise_update(&mut self) {
        // SAFETY: atomic fields of the running slot.
        let (bits, q) = unsafe { ((*self.cur).cruise_bits.load(Relaxed), (*self.cur).cruise_q.load(Relaxed)) };
        self.plan.cruise = Period::from_bits(bits);
        if q != self.plan.cruise_q {
            self.plan.cruise_q = q;
            self.walk.replan();
        }
    }

    /// Looks up the period one walk on (where the next ramp millisecond goes).
    #[inline(always)]
    pub(super) fn predict(&mut self) {
        let target = self.target();
        self.next_idx = self.walk.next_idx(&self.plan, target);
        self.next_base = base_at(self.next_idx, &self.ramp.profile().ramp);
    }

    /// Pending ramp work, one piece (a tick without a ramp millisecond): the period at a new
    /// index, else one trigger distance.
    #[inline(never)]
    pub(super) fn settle(&mut self) {
        if !matches!(self.phase, Phase::Run | Phase::Dir) {
            self.walk.pending = 0;
            return;
        }
        let pending = self.walk.pending;
        if pending & FRESH_MASK != 0 {
            // Set by this tick's step (this tick has paid for that), or a short gap follows.
            self.walk.pending = pending - FRESH;
        } else {
            if pending & PERIOD != 0 {
                self.walk.pending = pending & !PERIOD;
                self.set_period();
            } else if pending & PREDICT != 0 {
                self.walk.pending = pending & !PREDICT;
                self.predict();
            } else if pending & TRIGGER != 0 {
                let target = self.target();
                self.walk.settle_trigger(&self.plan, target, &self.ramp.profile().ramp);
            } else {
                self.walk.settle_up(&self.plan, &self.ramp.profile().ramp);
            }
            self.spaced();
        }
    }

    /// The index moved: its period now when this tick's period is long, else on a later tick.
    #[inline(always)]
    pub(super) fn period_soon(&mut self) {
        if self.gap_in < SHORT_GAP {
            self.walk.pending |= PERIOD;
        } else {
            self.set_period();
        }
    }

    /// Period for the current ramp index (a table lookup).
    #[inline(always)]
    pub(super) fn set_period(&mut self) {
        self.base = self.walk.base(&self.ramp.profile().ramp);
        self.apply_period();
    }

    /// Period for the table's period already looked up and the running move's scale.
    #[inline(always)]
    pub(super) fn apply_period(&mut self) {
        self.period = scaled(self.base, self.walk.idx, &self.plan, self.min_period);
        self.shared.period_bits.store(self.period.to_bits(), Relaxed);
    }


    pub(super) fn plan_decel(&mut self) {
        let target = self.target();
        self.walk.plan_decel(&self.plan, target, &self.ramp.profile().ramp);
    }
}
