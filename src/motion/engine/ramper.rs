//! The ramp half of the engine: the ramp walk and everything it computes, in a lower-priority
//! interrupt the step interrupt pends (see the parent module for the split).
//!
//! Who uses it: the firmware's ramp handler ([`Ramper::run`]), and the host's `Engine` on the
//! host after each tick.
//!
//! Each run compares the step half's counters ([`Link`](super::link::Link)) with its own copies and does
//! what they say, in this order: a move entered or ended, a start from rest to prime, a trigger
//! fired (the walk starts down, if the trigger was the running move's), a hold on or off, the
//! ramp milliseconds passed; then every distance the walk needs next (the trigger, the one from a
//! walk up) at once, and it publishes the running move's period and trigger in its slot and
//! primes its successor's period at the walk's index. The step interrupt preempts it at every
//! edge; it loops until the counters stand still.
//!
//! S mode (`$41=1`, `ramp/scurve.rs`): the walk stays linear (at the move's a / k) and the index
//! in use is its leg's S of it; each ramp millisecond first checks what the walk heads for
//! (`steer`: a new leg from the index in use when that changed), and the trigger,
//! a hold's way down and the successor's priming all start from the index in use.

use core::sync::atomic::Ordering::Relaxed;

use crate::motion::prepared::{Prepared, RampPlan};
use crate::motion::shared::Shared;
use crate::motion::ramp::{peak, Leg, Period, RampSlot, RAMP_LEN};
use crate::motion::ring::RingPeek;
use crate::motion::walk::{period_bits, Step as WalkStep, Walk, TRIGGER};

/// The ramp half for `N` axes.
pub struct Ramper<'a, const N: usize, const L: usize = RAMP_LEN> {
    shared: &'a Shared<N>,
    ring: RingPeek<'a, N>,
    ramp: &'a RampSlot<L>,
    /// The move the walk is on (null: at rest, no move).
    cur: *const Prepared<N>,
    plan: RampPlan,
    min_period: Period,
    /// The running move's period at the walk's index (bits).
    period: u32,
    walk: Walk,
    /// S mode: the leg the walk is on (the index in use is [`Leg::at`] the walk's linear
    /// index), what it was started for (down, its end or the cruise, the target), and whether
    /// a new move's own leg is still to start.
    leg: Leg,
    leg_key: (bool, u32, u32),
    leg_due: bool,
    /// S mode (`$41=1`), as the profile was when the walk's move was entered.
    s_on: bool,
    hold: bool,
    /// A hold brought the walk to rest (the running move's period is 0 until the resume).
    resting: bool,
    /// The trigger last published in the running move's slot, and the successor last
    /// published in the link.
    published_at: u32,
    published_succ: usize,
    /// What the successor was last primed from (its slot, the walk's index, the hold, whether
    /// a move follows it, its exit): the same again primes the same values, so a pass skips
    /// it (cleared when the walk enters a move: only then can the slot be reused).
    primed: (usize, u32, bool, bool, u32),
    /// The ring as this pass saw it ([`Self::look`]).
    succ: Option<*const Prepared<N>>,
    succ_next: bool,
    // The step half's counters as last seen.
    seen_ms: u32,
    seen_decel: u32,
    /// (The position record's sequence: it moves when a move is entered or ended.)
    seen_moves: u32,
    seen_next: usize,
    seen_primes: u32,
}

// SAFETY: `cur` points into the ring the engine consumes; the ramp half is moved into its
// interrupt once and used only there.
unsafe impl<const N: usize, const L: usize> Send for Ramper<'_, N, L> {}

impl<'a, const N: usize, const L: usize> Ramper<'a, N, L> {
    pub(super) fn new(shared: &'a Shared<N>, ring: RingPeek<'a, N>, ramp: &'a RampSlot<L>) -> Self {
        let link = &shared.link;
        Ramper {
            shared,
            ring,
            ramp,
            cur: core::ptr::null(),
            plan: RampPlan::lone(0, Period::ZERO),
            min_period: Period::ZERO,
            period: 0,
            walk: Walk::REST,
            leg: Leg::new(0, 0),
            leg_key: (false, 0, 0),
            leg_due: false,
            s_on: false,
            hold: link.hold.load(Relaxed),
            resting: false,
            published_at: 0,
            published_succ: 0,
            primed: (0, 0, false, false, 0),
            succ: None,
            succ_next: false,
            seen_ms: link.ms.load(Relaxed),
            seen_decel: link.decel.load(Relaxed),
            seen_moves: shared.record_seq(),
            seen_next: link.next.load(Relaxed),
            seen_primes: link.primes.load(Relaxed),
        }
    }

    /// (index Q20, decelerating, trigger) for tests.
    pub(super) fn walk_state(&self) -> (u32, bool, u32) {
        (self.idx(), self.walk.decel, self.walk.decel_at)
    }

    /// Does what the step half asked for since the last run (see the module).
    #[cfg_attr(target_os = "none", link_section = ".fill.run")]
    pub fn run(&mut self) {
        loop {
            let link = &self.shared.link;
            let (ms, decel, moves, next, primes, hold) = (
                link.ms.load(Relaxed),
                link.decel.load(Relaxed),
                self.shared.record_seq(),
                link.next.load(Relaxed),
                link.primes.load(Relaxed),
                link.hold.load(Relaxed),
            );
            if (ms, decel, moves, next, primes, hold) == (self.seen_ms, self.seen_decel, self.seen_moves, self.seen_next, self.seen_primes, self.hold) {
                return;
            }
            if (moves, next) != (self.seen_moves, self.seen_next) {
                (self.seen_moves, self.seen_next) = (moves, next);
                // The move being entered, else the running one (the same move when its change
                // completes: the walk is on it already).
                let p = if next != 0 { next as *const Prepared<N> } else { self.shared.running() };
                if p.is_null() {
                    self.cur = p;
                    self.primed.0 = 0;
                    self.rest();
                    self.resting = false;
                } else if p != self.cur {
                    self.enter(p);
                }
            }
            if primes != self.seen_primes {
                self.seen_primes = primes;
                if let Some(p) = self.ring.front() {
                    self.rest();
                    self.resting = false;
                    self.enter(p);
                }
            }
            self.look();
            if decel != self.seen_decel {
                self.seen_decel = decel;
                // (A trigger of a move that has ended since is void: its successor's trigger
                // is computed from where the walk is.)
                if self.running() && !self.walk.decel && link.decel_in.load(Relaxed) == self.cur as usize {
                    self.start_decel();
                }
            }
            if hold != self.hold {
                self.hold = hold;
                self.hold_changed();
            }
            let n = ms.wrapping_sub(self.seen_ms);
            self.seen_ms = ms;
            for _ in 0..n {
                self.walk_ms();
            }
            self.publish();
        }
    }

    /// Looks at the ring once per pass: the move after the walk's, and whether one follows it.
    /// (The walk's move is the front, or the one after it during a move change: the step half
    /// frees the front's slot on the tick after its last step.)
    fn look(&mut self) {
        let at = (self.ring.front() != Some(self.cur)) as u32;
        self.succ = self.ring.nth(at + 1);
        self.succ_next = self.succ.is_some() && self.ring.nth(at + 2).is_some();
    }

    /// A move the walk is on, not resting under a hold.
    fn running(&self) -> bool {
        !self.cur.is_null() && !self.resting
    }

    /// The walk goes on with move `p` (a switch at speed: the index carries over; a start
    /// from rest after the walk was reset).
    #[cfg_attr(target_os = "none", link_section = ".fill.enter")]
    fn enter(&mut self, p: *const Prepared<N>) {
        self.cur = p;
        self.primed.0 = 0;
        // SAFETY: a published slot the step half runs (or is about to); plain fields.
        unsafe {
            self.plan = (*p).ramp;
            self.min_period = (*p).min_period;
        }
        // SAFETY: an atomic field (the trigger primed while it was the successor, or 0).
        self.published_at = unsafe { (*p).decel_at.load(Relaxed) };
        // S mode: the move's own legs start from the index in use (linear: the same index).
        let at = self.idx();
        self.s_on = self.ramp.profile().scurve.on();
        self.walk.idx = at;
        self.leg = Leg::new(at, at);
        self.leg_due = true;
        self.walk.decel = self.hold;
        self.walk.defer_decel();
        self.set_period();
    }

    /// The hold changed: walk down to rest, or go on (from rest: up from the bottom of the
    /// table).
    fn hold_changed(&mut self) {
        if self.cur.is_null() {
            return;
        }
        if self.hold {
            if !self.resting && !self.walk.decel {
                self.start_decel();
            }
        } else if self.resting {
            self.resting = false;
            self.rest();
            self.leg_due = true;
            self.walk.defer_decel();
            self.set_period();
        } else {
            self.walk.decel = false;
            self.walk.replan();
        }
    }

    /// Starts walking down: one walk down now (the step half restarted the millisecond).
    #[cfg_attr(target_os = "none", link_section = ".fill.start_decel")]
    fn start_decel(&mut self) {
        let target = self.target();
        // S mode: the way down is a leg of its own, from the index in use.
        let at = self.idx();
        self.walk.idx = at;
        self.leg = Leg::new(at, target.min(at));
        self.leg_key = (true, target, 0);
        self.leg_due = false;
        self.walk.start_decel(&self.plan, target);
        self.set_period();
    }

    /// The exit target: 0 under a hold or when no successor is queued yet; never above the
    /// cruise (an override may have lowered it below the planned exit).
    #[cfg_attr(target_os = "none", link_section = ".fill.target")]
    fn target(&self) -> u32 {
        if self.hold || self.succ.is_none() {
            0
        } else {
            // SAFETY: an atomic field of the running slot.
            unsafe { (*self.cur).exit_q.load(Relaxed) }.min(self.plan.cruise_q)
        }
    }

    /// One millisecond has passed: move along the ramp.
    fn walk_ms(&mut self) {
        if !self.running() {
            return;
        }
        self.settle();
        self.cruise_update();
        let target = self.target();
        // SAFETY: a plain field of the running slot.
        let left = unsafe { (*self.cur).total }.wrapping_sub(self.shared.mv_done.load(Relaxed));
        if self.s_on {
            self.steer(target, left);
        }
        match self.walk.per_ms(&self.walk_plan(), target, left) {
            WalkStep::Same => {}
            WalkStep::AtRest if self.hold => self.resting = true,
            _ => self.set_period(),
        }
    }

    /// The running move's cruise as the feeder last priced it (an override changed); a new
    /// index re-plans the trigger. (The feeder stores the index, then the floor, and cannot run
    /// between these two loads.)
    fn cruise_update(&mut self) {
        // SAFETY: atomic fields of the running slot.
        let (bits, q) = unsafe { ((*self.cur).cruise_bits.load(Relaxed), (*self.cur).cruise_q.load(Relaxed)) };
        self.plan.cruise = Period::from_bits(bits);
        if q != self.plan.cruise_q {
            self.plan.cruise_q = q;
            self.walk.replan();
        }
    }

    /// Every distance the walk needs next: the trigger for the index and target, then the one
    /// from a walk up.
    #[cfg_attr(target_os = "none", link_section = ".fill.settle")]
    fn settle(&mut self) {
        let table = &self.ramp.profile().ramp;
        if self.walk.pending & TRIGGER != 0 {
            let target = self.target();
            self.walk.settle_trigger(&self.plan, target, table);
        }
        if self.walk.unsettled() {
            self.walk.settle_up(&self.walk_plan(), table);
        }
    }

    /// The walk back at rest (index 0, no leg).
    fn rest(&mut self) {
        self.walk = Walk::REST;
        self.leg = Leg::new(0, 0);
    }

    /// The index in use: the walk's linear index through the leg's S (itself in trapezoid
    /// mode).
    #[inline(never)]
    fn idx(&self) -> u32 {
        if self.s_on {
            self.leg.at(self.walk.idx, &self.ramp.profile().scurve)
        } else {
            self.walk.idx
        }
    }

    /// The plan the linear walk runs: in S mode an up leg's end caps the cruise (its peak).
    #[inline(always)]
    fn walk_plan(&self) -> RampPlan {
        let mut plan = self.plan;
        if self.s_on && !self.leg.down() && !self.walk.decel {
            plan.cruise_q = plan.cruise_q.min(self.leg.to);
        }
        plan
    }

    /// S mode, once per ramp millisecond: a new leg from the index in use wherever the walk
    /// now heads elsewhere (a move entered, a resume, a target or cruise that changed, a
    /// deceleration that ended); an up leg ends at the move's peak (`ramp::peak`).
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.steer")]
    fn steer(&mut self, target: u32, left: u32) {
        let at = self.idx();
        let cruise = self.plan.cruise_q;
        let (leg, key) = if self.walk.decel || at > cruise {
            let end = if self.walk.decel { target.min(at) } else { cruise };
            let key = (true, end, 0);
            if !self.leg_due && self.leg_key == key {
                return;
            }
            (Leg::new(at, end), key)
        } else {
            let key = (false, cruise, target);
            let table = &self.ramp.profile().ramp;
            if !self.leg_due && self.leg_key == key {
                // At a peak below the cruise: higher if the steps left allow (a peak found
                // short), else wait there for the trigger.
                if self.leg.to >= cruise || self.walk.idx < self.leg.to {
                    return;
                }
                let top = peak(at, cruise, target, left, (self.plan.walk_q, self.plan.dist_q), table);
                if top <= at {
                    return;
                }
                (Leg::new(at, top), key)
            } else {
                // (A move's peak once the step half runs it: until then the steps left are
                // the previous move's.)
                if self.shared.running() != self.cur {
                    return;
                }
                (Leg::new(at, peak(at, cruise, target, left, (self.plan.walk_q, self.plan.dist_q), table)), key)
            }
        };
        self.leg = leg;
        self.leg_key = key;
        self.leg_due = false;
        self.walk.idx = at;
        self.walk.replan();
        self.settle();
    }

    /// The running move's period for the walk's index.
    #[cfg_attr(target_os = "none", link_section = ".fill.set_period")]
    fn set_period(&mut self) {
        let idx = self.idx();
        self.period = period_bits(idx, &self.ramp.profile().ramp, &self.plan, self.min_period);
        self.shared.period_bits.store(self.period, Relaxed);
    }

    /// The period (bits) one walk down from the walk's index towards `target`, for a move with
    /// `plan` and floor `min`: where a trigger puts it at once.
    #[cfg_attr(target_os = "none", link_section = ".fill.down_period")]
    fn down_period(&self, plan: &RampPlan, min: Period, target: u32) -> u32 {
        let idx = self.idx();
        // (S mode: the first millisecond of a leg from here down to `target`.)
        let lin = idx.saturating_sub(plan.walk_q).max(target);
        let down = if idx <= target {
            idx
        } else if self.s_on {
            Leg::new(idx, target).at(lin, &self.ramp.profile().scurve)
        } else {
            lin
        };
        period_bits(down, &self.ramp.profile().ramp, plan, min)
    }

    /// Primes successor `n` (its exit `exit`) at the walk's index: its period, and its trigger
    /// and the period one walk down for its own target (as `target` will find it).
    #[inline(always)]
    fn prime(&self, n: *const Prepared<N>, exit: u32) {
        // SAFETY: a published slot after the running one; plain fields the step half never
        // writes and atomics, through the pointer (the step half may enter it meanwhile).
        let (ramp, min) = unsafe { ((*n).ramp, (*n).min_period) };
        let table = &self.ramp.profile().ramp;
        let idx = self.idx();
        // SAFETY: as above.
        unsafe { (*n).period.store(period_bits(idx, table, &ramp, min), Relaxed) };
        let mut w = self.walk;
        w.idx = idx;
        let at = if self.hold {
            0
        } else {
            let target = if self.succ_next { exit.min(ramp.cruise_q) } else { 0 };
            w.settle_trigger(&ramp, target, table);
            // SAFETY: as above.
            unsafe { (*n).down_period.store(self.down_period(&ramp, min, target), Relaxed) };
            w.decel_at
        };
        // SAFETY: as above.
        unsafe { (*n).decel_at.store(at, Relaxed) };
    }

    /// Publishes the results in the slots: the running move's period and trigger (0 while
    /// decelerating, and the period 0 at rest under a hold), the walk's index, and the
    /// successor's period at this index.
    fn publish(&mut self) {
        if self.cur.is_null() {
            self.shared.link.idx.store(0, Relaxed);
            self.published_succ = self.shared.link.succ.load(Relaxed);
            return;
        }
        self.settle();
        // SAFETY: atomic fields of the running slot.
        // (Fields through the pointer: the step half borrows the running move's slaves.)
        let p = self.cur;
        // SAFETY: atomic fields of the running slot.
        unsafe { (*p).period.store(if self.resting { 0 } else { self.period }, Relaxed) };
        let at = if self.walk.decel || self.resting { 0 } else { self.walk.decel_at };
        if at != 0 {
            let target = self.target();
            // SAFETY: as above.
            unsafe { (*p).down_period.store(self.down_period(&self.plan, self.min_period, target), Relaxed) };
        }
        // Only over the value this half left: a trigger the step half fired (0) stays fired
        // until this half has seen it.
        if at != self.published_at {
            // SAFETY: as above.
            self.published_at = match unsafe { (*p).decel_at.compare_exchange(self.published_at, at, Relaxed, Relaxed) } {
                Ok(_) => at,
                Err(now) => now,
            };
        }
        let idx = self.idx();
        self.shared.link.idx.store(idx, Relaxed);
        let next = self.succ;
        if let Some(n) = next {
            // SAFETY: a published slot after the running one; an atomic field.
            let exit = unsafe { (*n).exit_q.load(Relaxed) };
            let key = (n as usize, idx, self.hold, self.succ_next, exit);
            if key != self.primed {
                self.primed = key;
                self.prime(n, exit);
            }
        }
        // Only over the value this half left: if the step half entered the successor since
        // (and cleared it), the next pass primes the new one's.
        let succ = next.map_or(0, |n| n as usize);
        if succ != self.published_succ {
            self.published_succ = match self.shared.link.succ.compare_exchange(self.published_succ, succ, Relaxed, Relaxed) {
                Ok(_) => succ,
                Err(now) => now,
            };
        }
    }
}
