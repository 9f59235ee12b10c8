//! The step engine: what the TIM2 interrupt does, one tick at a time.
//!
//! Who uses it: the firmware's TIM2 handler (one call per update event) and host tests.
//!
//! Contract of one tick. At each timer update event the handler first stores
//! [`Engine::word`] into the step port's BSRR (the rising step edges and any direction change,
//! all precomputed, so the edge time never depends on which axes step), then calls
//! [`Engine::tick`], which computes the word for the *next* update event and returns the ARR
//! value to preload now (TIM2's ARR is buffered, so it takes effect at the next update and sets
//! the gap after it). Falling edges come from a compare event `pulse_ticks` after each update,
//! where the handler stores [`Engine::step_off`] (dual-edge mode: no compare event, each step
//! word toggles its pins from a shadow of their level, `step_off` is 0). Periods longer than 65 536 ticks
//! (< 1.1 kHz) are split into filler events whose word is 0 (period extension; the prescaler
//! stays 0, so pulse width and resolution never change).
//!
//! Moves arrive prepared ([`crate::prepared`]) in a ring and run in their slot: a move change
//! is a pointer switch, a position-record swap and the new move's period (the table's period
//! at the index, already looked up, times the move's scale); its deceleration trigger follows
//! on a later tick ([`crate::walk`]): no search, no division, no loop over axes. The ramp
//! index carries over from move to move (look-ahead junctions run through at speed). Ramp work
//! is spread over ticks, one piece at most per tick while periods are short (`ramp_work`).
//! A direction change at a junction is carved out of the gap before the next step (the
//! change, then `dir_setup`) when steps are slow; at speed it comes one period after the last
//! step (the finishing tick's own ARR store may land after the next update, which must then
//! not shorten the setup gap), then `dir_setup`, so the new move's first step waits for the
//! setup. The ticks of a direction change and of the first step after it run no ramp work.
//!
//! Invariants: every move emits exactly its step counts (the ramp only sets periods); each
//! axis's position equals the step words handed out (in dual-edge mode one toggle per step, the
//! pins' level the parity of the steps made since boot); a direction change is written alone and
//! followed by at least `dir_setup_ticks` before the next step. No floats, no division, no
//! loop over the queue: the only loop is the unrolled one over the move's slaves (≤ 6).
//!
//! Cycle budget: see bench/RESULTS.md (modeled on the virtual bench).

use core::sync::atomic::Ordering::Relaxed;

use crate::board::PinMap;
use crate::control::Ctl;
use crate::prepared::{Prepared, RampPlan};
use crate::queue::{Shared, State};
use crate::ramp::{Period, RampSlot, RAMP_LEN};
use crate::ring::RingConsumer;
use crate::walk::{Walk, FRESH, FRESH_MASK, PREDICT};

mod ramp_work;
use ramp_work::SHORT_GAP;
use crate::TICKS_PER_MS;

/// Longest timer period one tick can set (ARR is 16 bits).
pub const MAX_TICK: u32 = 1 << 16;
/// Period of idle ticks while no move runs (0.5 ms: a new move starts within this).
pub const IDLE_TICKS: u32 = TICKS_PER_MS / 2;

/// What the engine is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// No move loaded.
    Idle,
    /// A direction change is the next edge, then the move's first step.
    Dir,
    /// Stepping.
    Run,
    /// Stopped by feed hold, move not finished.
    Held,
}

/// The step engine for `N` axes.
pub struct Engine<'a, const N: usize, const L: usize = RAMP_LEN> {
    shared: &'a Shared<N>,
    ring: RingConsumer<'a, N>,
    ramp: &'a RampSlot<L>,
    step_off: u32,
    /// Dual-edge mode: each step toggles its pin; `level` shadows the step pins' level (the
    /// pins are low when the engine is built: boot drives them low, a mode change restarts).
    dual: bool,
    level: u32,
    // The edge about to happen.
    word: u32,
    extend: u32,
    frac: u32,
    ms_left: i32,
    // The running move (a slot of the ring; valid while `phase != Idle`).
    phase: Phase,
    cur: *mut Prepared<N>,
    plan: RampPlan,
    total: u32,
    left: u32,
    master_on: u32,
    n_slaves: u8,
    min_period: Period,
    period: Period,
    /// The table's period at the walk's index (bits), before the move's scale.
    base: u32,
    /// This tick's own period: from its update event to the next (the previous tick's ARR).
    gap_in: u32,
    /// Plain ticks still to pass before the next piece of ramp work (see `spaced`).
    space: u8,
    /// The index the next ramp millisecond moves to if it moves, and the table's period there
    /// (looked up ahead on a quiet tick, so the millisecond's own tick only scales it).
    next_idx: u32,
    next_base: u32,
    walk: Walk,
    hold: bool,
    /// The running move's direction change is still to be written (kept across a hold).
    dir_pending: bool,
    ctl_seen: Ctl,
}

// SAFETY: `cur` points into the ring the engine consumes; the engine is moved into the
// interrupt once and used only there.
unsafe impl<const N: usize, const L: usize> Send for Engine<'_, N, L> {}

impl<'a, const N: usize, const L: usize> Engine<'a, N, L> {
    /// An idle engine.
    pub fn new(shared: &'a Shared<N>, ring: RingConsumer<'a, N>, ramp: &'a RampSlot<L>, pins: PinMap<N>) -> Self {
        Engine {
            shared,
            ring,
            ramp,
            step_off: pins.step_off,
            dual: pins.dual,
            level: 0,
            word: 0,
            extend: 0,
            frac: 0,
            ms_left: TICKS_PER_MS as i32,
            phase: Phase::Idle,
            cur: core::ptr::null_mut(),
            plan: RampPlan::lone(0, Period::ZERO),
            total: 0,
            left: 0,
            master_on: 0,
            n_slaves: 0,
            min_period: Period::ZERO,
            period: Period::ZERO,
            base: 0,
            gap_in: 0,
            space: 0,
            next_idx: u32::MAX,
            next_base: 0,
            walk: Walk::REST,
            hold: false,
            dir_pending: false,
            ctl_seen: shared.ctl.load(),
        }
    }

    /// Ramp-walk state for tests: (index Q20, decelerating, decel trigger, master steps left).
    pub fn walk_state(&self) -> (u32, bool, u32, u32) {
        (self.walk.idx, self.walk.decel, self.walk.decel_at, self.left)
    }

    /// The BSRR word to store at this update event (precomputed by the previous tick).
    #[inline(always)]
    pub fn word(&self) -> u32 {
        self.word
    }

    /// The BSRR word for the compare event (falling step edges).
    #[inline(always)]
    pub fn step_off(&self) -> u32 {
        self.step_off
    }

    /// Computes the next edge's word; returns the ARR value to preload now.
    /// Not inlined, so the handler's own prologue stays small and the BSRR store comes first.
    #[inline(never)]
    pub fn tick(&mut self) -> u16 {
        if self.extend == 0 {
            let (word, ticks) = self.next_event();
            self.word = word;
            self.extend = ticks;
        } else {
            self.word = 0;
        }
        self.emit_chunk()
    }

    /// Takes the next ≤ 65 536-tick piece of the current period and keeps time for the ramp.
    #[inline(always)]
    fn emit_chunk(&mut self) -> u16 {
        let rem = self.extend;
        // Pieces are ≥ 32 768 ticks, so a filler never gets shorter than a real period.
        let chunk = if rem <= MAX_TICK {
            rem
        } else if rem >= MAX_TICK + MAX_TICK / 2 {
            MAX_TICK
        } else {
            MAX_TICK / 2
        };
        self.extend = rem - chunk;
        self.ms_left -= chunk as i32;
        if self.ms_left <= 0 && !self.quiet_tick() {
            self.ms_left += TICKS_PER_MS as i32;
            self.walk_ramp();
        } else if self.walk.unsettled() {
            let pending = self.walk.pending;
            if pending & FRESH_MASK != 0 {
                // Set by this tick's step (this tick has paid for that), or a short gap comes.
                self.walk.pending = pending - FRESH;
            } else if self.space != 0 {
                // The delay a long tick added to the next edges is still being made up.
                self.space -= 1;
            } else {
                self.settle();
            }
        }
        self.gap_in = chunk;
        (chunk - 1) as u16
    }

    /// The next edge: a step, a direction change or an idle gap, with the gap after it.
    #[inline(always)]
    fn next_event(&mut self) -> (u32, u32) {
        let ctl = self.shared.ctl.load();
        if ctl != self.ctl_seen {
            self.control(ctl);
        }
        match self.phase {
            Phase::Run => self.step(),
            Phase::Dir => self.dir_change(),
            Phase::Held => (0, IDLE_TICKS),
            Phase::Idle => self.refill(),
        }
    }

    /// One master step (and the slaves' share): the hot path.
    #[inline(always)]
    fn step(&mut self) -> (u32, u32) {
        let mut word = self.master_on;
        let total = self.total;
        // SAFETY: `cur` is the front slot of the ring, owned by the engine until it pops it;
        // only its slaves are borrowed (the feeder may store its `exit_q` concurrently).
        let slaves = unsafe { &mut (*self.cur).slaves };
        // Unrolled over the slots (N is a constant), stopping after the move's last slave: no
        // loop counter, no bounds checks, no branch inside a slot.
        let n = self.n_slaves as usize;
        macro_rules! slaves {
            ($out:lifetime; $($i:literal)*) => {$(
                if $i + 1 >= N || $i >= n {
                    break $out;
                }
                let s = &mut slaves[$i];
                word |= s.on & s.dda.step_mask(total);
            )*};
        }
        'slaves: {
            slaves!('slaves; 0 1 2 3 4 5 6);
        }
        if self.dual {
            // Toggle: set the pins that are low, reset those that are high.
            let level = self.level;
            self.level = level ^ word;
            word = (word & !level) | (word & level) << 16;
        }
        self.left -= 1;
        self.shared.mv_done.store(total - self.left, Relaxed);
        // (Not at the last step: a successor takes over the walk there, and with none the
        // move has reached its exit.)
        if self.left <= self.walk.decel_at && !self.walk.decel && self.left != 0 {
            self.start_decel();
        }
        let acc = self.frac + self.period.to_bits();
        self.frac = acc & 15;
        let mut gap = acc >> 4;
        if self.left == 0 {
            gap = self.finish(gap);
        }
        (word, gap)
    }

    /// The direction change before a move's first step, then the setup gap.
    #[inline(never)]
    fn dir_change(&mut self) -> (u32, u32) {
        self.phase = Phase::Run;
        self.dir_pending = false;
        // SAFETY: as in `step`; plain fields the feeder never writes after publishing.
        unsafe { ((*self.cur).dir_word, (*self.cur).dir_setup) }
    }

    /// The control word changed: an immediate stop, or a feed hold on or off.
    #[inline(never)]
    fn control(&mut self, ctl: Ctl) {
        let old = core::mem::replace(&mut self.ctl_seen, ctl);
        if ctl.stopped_since(old) && self.phase != Phase::Idle {
            self.stop_move();
        }
        let hold = ctl.hold();
        if hold == self.hold {
            return;
        }
        self.hold = hold;
        match self.phase {
            Phase::Run | Phase::Dir if hold => {
                if !self.walk.decel {
                    self.start_decel();
                }
                self.publish(State::Holding);
            }
            Phase::Run | Phase::Dir => {
                self.walk.decel = false;
                self.plan_decel();
                self.walk.pending |= PREDICT;
                self.publish(State::Run);
            }
            Phase::Held => {
                // Resume: accelerate again from the bottom of the table.
                self.walk = Walk::REST;
                self.plan_decel();
                self.set_period();
                self.predict();
                self.ms_left = TICKS_PER_MS as i32;
                self.phase = if self.dir_pending { Phase::Dir } else { Phase::Run };
                self.publish(State::Run);
            }
            Phase::Idle => {}
        }
    }

    /// Makes the front slot the running move (its steps, slaves, ramp plan).
    #[inline(always)]
    fn enter(&mut self, p: *mut Prepared<N>) {
        self.cur = p;
        // SAFETY: a published slot, now owned by the engine; plain fields only.
        unsafe {
            self.plan = (*p).ramp;
            self.total = (*p).total;
            self.master_on = (*p).master_on;
            self.n_slaves = (*p).n_slaves;
            self.min_period = (*p).min_period;
        }
        self.left = self.total;
        self.shared.start_move(p as *const Prepared<N>);
        self.walk.decel = self.hold;
        // The trigger comes at the next tick (a move change costs no distance), and the
        // table's period at the index is the one the previous move ran at.
        self.walk.defer_decel();
        self.walk.pending |= PREDICT;
        self.apply_period();
    }

    /// The running move made its last step: switch to the next one at speed, or go idle.
    /// Returns the gap after the last step: shortened when a direction change comes first and
    /// steps are slow (then this tick's own work fits in the period before it); at speed the
    /// change comes one whole period after the last step, since this tick's late ARR store
    /// would otherwise shorten the setup gap instead. The direction tick and the first step's
    /// run no ramp work, so both fit in their gaps.
    #[inline(never)]
    fn finish(&mut self, gap: u32) -> u32 {
        self.shared.moves_done.fetch_add(1, Relaxed);
        self.ring.pop();
        if let Some(p) = self.ring.front() {
            // SAFETY: a published slot; plain fields.
            let (epoch, dir, setup, min_gap) = unsafe { ((*p).epoch, (*p).dir_word, (*p).dir_setup, (*p).min_gap) };
            if epoch == self.ctl_seen.epoch() {
                let slow = self.gap_in >= SHORT_GAP;
                self.enter(p);
                self.spaced();
                if dir != 0 {
                    self.phase = Phase::Dir;
                    self.dir_pending = true;
                    self.fresh(3);
                    if slow {
                        return gap.saturating_sub(setup).max(min_gap);
                    }
                }
                return gap;
            }
        }
        // Nothing queued: at rest unless the feeder was late at speed (counted).
        if self.walk.idx != 0 && !self.hold {
            self.shared.starved.fetch_add(1, Relaxed);
        }
        self.go_idle(|p, i| p.steps[i]);
        gap
    }

    /// An immediate stop: the running move ends where it is, each axis at the steps it made.
    #[inline(never)]
    fn stop_move(&mut self) {
        let done = self.total - self.left;
        let total = self.total;
        self.ring.pop();
        self.go_idle(|p, i| {
            let made = if i == p.master as usize {
                done
            } else {
                p.slaves[..p.n_slaves as usize].iter().find(|s| s.axis as usize == i).map_or(0, |s| s.dda.made(done, total))
            };
            if p.steps[i] < 0 {
                -(made as i32)
            } else {
                made as i32
            }
        });
    }

    /// Publishes the positions after the running move (`made(move, axis)`) and goes idle.
    fn go_idle(&mut self, made: impl Fn(&Prepared<N>, usize) -> i32) {
        // SAFETY: the slot was just popped but is not reused before the producer sees the pop
        // and pushes again, which cannot happen inside this interrupt.
        let p = unsafe { &*self.cur };
        self.shared.idle_at(|i| p.start[i].wrapping_add(made(p, i)));
        self.cur = core::ptr::null_mut();
        self.left = 0;
        self.walk = Walk::REST;
        self.phase = Phase::Idle;
        self.dir_pending = false;
        self.shared.period_bits.store(0, Relaxed);
        self.publish(State::Idle);
    }

    /// Loads the next move from rest, if any (queue refill; never in the step path).
    #[inline(never)]
    fn refill(&mut self) -> (u32, u32) {
        if self.hold {
            self.publish(State::Held);
            return (0, IDLE_TICKS);
        }
        if !self.ramp.enter() {
            return (0, IDLE_TICKS);
        }
        let Some(p) = self.ring.front() else {
            self.publish(State::Idle);
            return (0, IDLE_TICKS);
        };
        // SAFETY: a published slot; plain fields.
        let (epoch, dir, setup) = unsafe { ((*p).epoch, (*p).dir_word, (*p).dir_setup) };
        if epoch != self.ctl_seen.epoch() {
            self.ring.pop(); // dropped by an immediate stop
            return (0, IDLE_TICKS);
        }
        self.walk = Walk::REST;
        self.base = self.walk.base(&self.ramp.profile().ramp);
        self.enter(p);
        self.predict();
        self.walk.pending &= !PREDICT;
        self.phase = Phase::Run;
        self.publish(State::Run);
        // The ramp's milliseconds start at the move's first step.
        self.ms_left = TICKS_PER_MS as i32;
        if dir != 0 {
            self.ms_left += setup as i32;
            self.fresh(2);
            (dir, setup)
        } else {
            self.step()
        }
    }

    #[inline(always)]
    fn publish(&self, s: State) {
        self.shared.state.store(s as u8, Relaxed);
    }
}
