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
//! where the handler stores [`PinMap::step_off`]. Periods longer than 65 536 ticks
//! (< 1.1 kHz) are split into filler events whose word is 0 (period extension; the prescaler
//! stays 0, so pulse width and resolution never change).
//!
//! Invariants: every move emits exactly its step counts (the ramp only sets periods); each
//! axis's position counter counts every step word the engine hands out, so it equals the pulses
//! emitted once that word is written at the next edge; a direction change is written alone
//! and followed by at least `dir_setup_ticks` before the next step; the ramp index moves by one
//! entry per millisecond of timer time (at most one boundary per tick, since a tick is ≤ 65 536
//! ticks < 72 000). No floats, no division, no loop over the queue: the only loop is over the
//! move's slave axes (≤ 6).
//!
//! Cycle budget: see bench/RESULTS.md (modeled on the virtual bench).

use core::sync::atomic::Ordering::Relaxed;

use heapless::spsc::Consumer;

use crate::board::PinMap;
use crate::interp::Dda;
use crate::queue::{Move, Shared, State};
use crate::ramp::{Period, RampSlot, RAMP_LEN};
use crate::timing::{Timing, STORE_JITTER_TICKS};
use crate::TICKS_PER_MS;

/// Longest timer period one tick can set (ARR is 16 bits).
pub const MAX_TICK: u32 = 1 << 16;
/// Period of idle ticks while no move runs (0.5 ms: a new move starts within this).
pub const IDLE_TICKS: u32 = TICKS_PER_MS / 2;

/// Where the engine is within a move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// No move loaded.
    Idle,
    /// Walking up the ramp table.
    Accel,
    /// At the move's own cruise period.
    Cruise,
    /// Walking down the ramp table.
    Decel,
    /// Stopped by feed hold, move not finished.
    Held,
}

/// One slave axis of the running move.
#[derive(Clone, Copy, Debug)]
struct Slave {
    dda: Dda,
    on: u32,
    axis: u8,
}

/// The step engine for `N` axes.
pub struct Engine<'a, const N: usize, const L: usize = RAMP_LEN> {
    shared: &'a Shared<N>,
    queue: Consumer<'a, Move<N>>,
    ramp: &'a RampSlot<L>,
    pins: PinMap<N>,
    min_period: Period,
    dir_setup: u32,
    // The edge about to happen.
    word: u32,
    extend: u32,
    frac: u32,
    ms_left: i32,
    // The running move.
    phase: Phase,
    hold_stop: bool,
    ctl_seen: u32,
    idx: u16,
    cruise_idx: u16,
    cruise: Period,
    period: Period,
    left: u32,
    total: u32,
    /// Start decelerating once `left` is at most this (set when accelerating or cruising).
    decel_at: u32,
    /// `left` plus the ramp steps already made when the current acceleration began.
    ramp_base: u32,
    /// Ramp steps made and `left` when the deceleration began (for a released feed hold).
    decel_ramp: u32,
    decel_left: u32,
    master_on: u32,
    master_axis: u8,
    mv_steps: [i32; N],
    slaves: [Slave; N],
    n_slaves: u8,
    dir_neg: u32,
    dir_known: u32,
}

impl<'a, const N: usize, const L: usize> Engine<'a, N, L> {
    /// An idle engine.
    pub fn new(
        shared: &'a Shared<N>,
        queue: Consumer<'a, Move<N>>,
        ramp: &'a RampSlot<L>,
        pins: PinMap<N>,
    ) -> Self {
        Engine {
            shared,
            queue,
            ramp,
            pins,
            min_period: Period::ZERO,
            dir_setup: 0,
            word: 0,
            extend: 0,
            frac: 0,
            ms_left: TICKS_PER_MS as i32,
            phase: Phase::Idle,
            hold_stop: false,
            ctl_seen: shared.ctl.load(Relaxed),
            idx: 0,
            cruise_idx: 0,
            cruise: Period::ZERO,
            period: Period::ZERO,
            left: 0,
            total: 0,
            decel_at: 0,
            ramp_base: 0,
            decel_ramp: 0,
            decel_left: 0,
            master_on: 0,
            master_axis: 0,
            mv_steps: [0; N],
            slaves: [Slave { dda: Dda::new(0, 0), on: 0, axis: 0 }; N],
            n_slaves: 0,
            dir_neg: 0,
            dir_known: 0,
        }
    }

    /// The BSRR word to store at this update event (precomputed by the previous tick).
    #[inline(always)]
    pub fn word(&self) -> u32 {
        self.word
    }

    /// The BSRR word for the compare event (falling step edges).
    #[inline(always)]
    pub fn step_off(&self) -> u32 {
        self.pins.step_off
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
        if self.ms_left <= 0 {
            self.ms_left += TICKS_PER_MS as i32;
            self.walk_ramp();
        }
        (chunk - 1) as u16
    }

    /// The next edge: a step, a direction change or an idle gap, with the gap after it.
    #[inline(always)]
    fn next_event(&mut self) -> (u32, u32) {
        let ctl = self.shared.ctl.load(Relaxed);
        if ctl != self.ctl_seen {
            self.control(ctl);
        }
        match self.phase {
            Phase::Accel | Phase::Cruise | Phase::Decel => self.step(),
            Phase::Held => (0, IDLE_TICKS),
            Phase::Idle => self.refill(),
        }
    }

    /// One master step (and the slaves' share): the hot path.
    #[inline(always)]
    fn step(&mut self) -> (u32, u32) {
        let mut word = self.master_on;
        let total = self.total;
        // Unrolled over the slots (N is a constant), stopping after the move's last slave: no
        // loop counter, no bounds checks, no branch inside a slot.
        let n = self.n_slaves as usize;
        macro_rules! slaves {
            ($out:lifetime; $($i:literal)*) => {$(
                if $i + 1 >= N || $i >= n {
                    break $out;
                }
                let s = &mut self.slaves[$i];
                word |= s.on & s.dda.step_mask(total);
            )*};
        }
        'slaves: {
            slaves!('slaves; 0 1 2 3 4 5 6);
        }
        self.left -= 1;
        self.shared.mv_done.store(total - self.left, Relaxed);
        if self.left <= self.decel_at {
            self.start_decel();
        }
        let acc = self.frac + self.period.to_bits();
        self.frac = acc & 15;
        if self.left == 0 {
            self.end_move(true);
        }
        (word, acc >> 4)
    }

    /// One millisecond has passed: move one entry along the ramp.
    #[inline(never)]
    fn walk_ramp(&mut self) {
        match self.phase {
            Phase::Accel => {
                self.idx += 1;
                if self.idx >= self.cruise_idx {
                    self.idx = self.cruise_idx;
                    self.cruise_now();
                }
            }
            Phase::Decel => {
                if self.idx > 0 {
                    self.idx -= 1;
                } else if self.hold_stop {
                    self.phase = Phase::Held;
                    self.publish(State::Held);
                    return;
                }
            }
            _ => return,
        }
        self.set_period();
    }

    /// Turns round on the ramp so the way down mirrors the way up: from cruise, the next entry
    /// down gets a whole millisecond; mid-ramp, the current entry gets as long again as it has
    /// had, so the steps down equal the steps up (`ramp_steps`).
    #[inline(never)]
    fn start_decel(&mut self) {
        if self.phase == Phase::Decel {
            return;
        }
        self.decel_ramp = self.ramp_steps();
        self.decel_left = self.left;
        self.decel_at = 0;
        if self.phase == Phase::Cruise {
            if self.idx > 0 {
                self.idx -= 1;
                self.set_period();
            }
            self.ms_left = TICKS_PER_MS as i32;
        } else {
            self.ms_left = TICKS_PER_MS as i32 - self.ms_left;
        }
        self.phase = Phase::Decel;
    }

    /// Period for the current ramp index.
    #[inline(always)]
    fn set_period(&mut self) {
        let p = if self.idx >= self.cruise_idx {
            self.cruise
        } else {
            self.ramp.profile().ramp.period(self.idx as usize)
        };
        self.period = p.max(self.min_period);
        self.shared.period_bits.store(self.period.to_bits(), Relaxed);
    }

    /// Ramp steps made so far: steps up the table, less steps back down.
    fn ramp_steps(&self) -> u32 {
        match self.phase {
            Phase::Accel => self.ramp_base - self.left,
            Phase::Cruise => self.decel_at,
            Phase::Decel => self.decel_ramp.saturating_sub(self.decel_left - self.left),
            _ => 0,
        }
    }

    /// (Re)starts accelerating with `made` ramp steps already behind.
    fn accel_now(&mut self, made: u32) {
        self.phase = Phase::Accel;
        self.ramp_base = self.left + made;
        // left ≤ made + (steps from here) ⟺ 2·left ≤ ramp_base.
        self.decel_at = self.ramp_base >> 1;
    }

    /// Reaches the cruise rate: the steps it took up are the steps it needs down.
    fn cruise_now(&mut self) {
        self.decel_at = self.ramp_steps();
        self.phase = Phase::Cruise;
    }

    /// The control word changed: an immediate stop, or a feed hold on or off.
    #[inline(never)]
    fn control(&mut self, ctl: u32) {
        let old = core::mem::replace(&mut self.ctl_seen, ctl);
        if (old ^ ctl) >> 1 != 0 {
            self.end_move(false);
        }
        let hold = ctl & 1 != 0;
        match self.phase {
            Phase::Accel | Phase::Cruise | Phase::Decel if hold != self.hold_stop => self.toggle_hold(hold),
            Phase::Held if !hold => self.resume(),
            _ => {}
        }
    }

    /// A feed-hold request changed.
    #[inline(never)]
    fn toggle_hold(&mut self, hold: bool) {
        {
            self.hold_stop = hold;
            if hold {
                if self.phase != Phase::Decel {
                    self.start_decel();
                }
                self.publish(State::Holding);
            } else {
                let made = self.ramp_steps();
                if self.left > made {
                    self.accel_now(made);
                }
                self.publish(State::Run);
            }
        }
    }

    /// Leaves a completed feed hold: accelerate again from the bottom of the table.
    #[inline(never)]
    fn resume(&mut self) {
        self.hold_stop = false;
        self.idx = 0;
        if self.left == 0 {
            self.phase = Phase::Idle;
            self.publish(State::Idle);
            return;
        }
        self.start_ramp();
        self.set_period();
        self.publish(State::Run);
    }

    /// From rest: accelerate, or cruise at once when the cruise rate is below the table.
    fn start_ramp(&mut self) {
        self.accel_now(0);
        if self.cruise_idx == 0 {
            self.cruise_now();
        }
    }

    /// Ends the running move (counted as done only when completed).
    #[inline(never)]
    fn end_move(&mut self, completed: bool) {
        if self.phase != Phase::Idle {
            // What each axis made: all of it, or (stopped) the master's and the slaves' counts.
            let done = self.total - self.left;
            let mut made = [0u32; N];
            made[self.master_axis as usize] = done;
            for s in self.slaves.iter().take(self.n_slaves as usize) {
                made[s.axis as usize] = s.dda.made(done, self.total);
            }
            let steps = self.mv_steps;
            self.shared.end_move(|i| if steps[i] < 0 { -(made[i] as i32) } else { made[i] as i32 });
        }
        if completed {
            self.shared.moves_done.fetch_add(1, Relaxed);
        }
        self.left = 0;
        self.phase = Phase::Idle;
        self.hold_stop = false;
        self.shared.period_bits.store(0, Relaxed);
        self.publish(State::Idle);
    }

    /// Loads the next move, if any (queue refill; never in the step path).
    #[inline(never)]
    fn refill(&mut self) -> (u32, u32) {
        if self.ctl_seen & 1 != 0 {
            self.publish(State::Held);
            return (0, IDLE_TICKS);
        }
        if !self.ramp.enter() {
            return (0, IDLE_TICKS);
        }
        let Some(mv) = self.queue.dequeue() else {
            self.publish(State::Idle);
            return (0, IDLE_TICKS);
        };
        if mv.epoch != self.ctl_seen >> 1 {
            return (0, IDLE_TICKS); // dropped by an immediate stop
        }
        self.load(&mv)
    }

    /// Sets up a move: master, slaves, ramp; returns a direction event when a pin must change.
    fn load(&mut self, mv: &Move<N>) -> (u32, u32) {
        let m = mv.master as usize;
        self.master_axis = mv.master;
        self.mv_steps = mv.steps;
        self.total = mv.steps[m].unsigned_abs();
        self.left = self.total;
        self.master_on = self.pins.step_on[m];
        self.shared.start_move(&mv.steps, self.total);
        let mut n = 0;
        let mut dir_word = 0;
        let mut dir_neg = self.dir_neg;
        let mut moving = 0;
        for (i, &s) in mv.steps.iter().enumerate() {
            if s == 0 {
                continue;
            }
            moving |= 1 << i;
            let neg = (s < 0) as u32;
            if (self.dir_known >> i & 1) == 0 || (dir_neg >> i & 1) != neg {
                dir_word |= if neg == 1 { self.pins.dir_neg[i] } else { self.pins.dir_pos[i] };
                dir_neg = (dir_neg & !(1 << i)) | neg << i;
            }
            if i != m {
                self.slaves[n] = Slave {
                    dda: Dda::new(s.unsigned_abs(), self.total),
                    on: self.pins.step_on[i],
                    axis: i as u8,
                };
                n += 1;
            }
        }
        self.n_slaves = n as u8;
        self.dir_neg = dir_neg;
        self.dir_known |= moving;
        self.cruise = mv.cruise;
        let profile = self.ramp.profile();
        self.cruise_idx = profile.ramp.cruise_index(mv.cruise);
        let t = match profile.timing {
            Timing::UNSET => Timing::DEFAULT,
            t => t,
        };
        self.min_period = Period::from_bits(t.min_period_for(n as u32).saturating_mul(16));
        self.dir_setup = (t.dir_setup_ticks + STORE_JITTER_TICKS).max(t.min_period_ticks);
        self.idx = 0;
        self.hold_stop = false;
        self.start_ramp();
        self.set_period();
        self.publish(State::Run);
        // The ramp's milliseconds start at the move's first step.
        self.ms_left = TICKS_PER_MS as i32;
        if dir_word != 0 {
            let gap = self.dir_setup;
            self.ms_left += gap as i32;
            (dir_word, gap)
        } else {
            self.step()
        }
    }

    #[inline(always)]
    fn publish(&self, s: State) {
        self.shared.state.store(s as u8, Relaxed);
    }
}
