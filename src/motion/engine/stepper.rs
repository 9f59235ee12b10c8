//! The step half of the engine: what the TIM2 interrupt does, one tick at a time (see the
//! parent module for the contract and the split).
//!
//! Who uses it: the firmware's TIM2 handler, and the host's `Engine`, which runs both halves.
//!
//! This file is the step path: a tick, its fast path for a plain step, and one master step
//! with its slaves' bits and the deceleration trigger. The rest, one mechanism per file:
//! - `state`: the step half's state, its accessors, ramp time and the ramp half's requests;
//! - `word`: the step word (the slaves' DDA bits, dual-edge mode's toggle);
//! - `extend`: period extension (periods longer than one timer event, as fillers);
//! - `change`: move change (the last step finds the successor, the next tick enters it);
//! - `hold`: feed hold, immediate stop, going idle;
//! - `refill`: the next move from rest;
//! - `plain`: the DMA fill's lanes of plain entries.

use core::sync::atomic::Ordering::Relaxed;

use crate::TICKS_PER_MS;

mod change;
mod extend;
mod hold;
pub(crate) mod plain;
mod refill;
mod state;
mod word;

use state::{bump, Phase};
pub use state::Stepper;
use word::{slave_bits, toggle};

impl<'a, const N: usize, const L: usize> Stepper<'a, N, L> {
    /// Computes the next edge's word; returns the ARR value to preload now.
    /// Not inlined, so the handler's own prologue stays small and the BSRR store comes first.
    /// Period extension stays off this path: only a period over 65 536 ticks (< 1.1 kHz) or
    /// its filler events take the out-of-line branch.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".data.ramfunc.tick")]
    pub fn tick(&mut self) -> u16 {
        let arr = self.whole_tick();
        self.quick = self.phase == Phase::Run && self.extend == 0;
        arr
    }

    #[inline(always)]
    fn whole_tick(&mut self) -> u16 {
        if self.extend != 0 {
            return self.filler();
        }
        let (word, ticks) = self.next_event();
        self.word = word;
        if ticks > self.max_tick {
            return self.extended(ticks);
        }
        self.elapse(ticks)
    }

    /// [`Self::tick`] with a fast path for the step interrupt: a plain step (running, no control
    /// change, neither the deceleration trigger nor the move's last step, no ramp millisecond
    /// ending, one event) takes only those checks, inline in the handler, and a call that
    /// computes it; every other tick is a whole one (no second prologue on its way). The same
    /// words and periods as `tick` (the property tests compare them).
    #[inline(always)]
    pub fn tick_quick(&mut self) -> u16 {
        if !self.quick || self.shared.ctl.load() != self.ctl_seen {
            return self.tick();
        }
        let p = self.cur;
        // SAFETY: `quick` is only set while a move runs (`cur` is its slot, see `step`).
        let (period, at) = unsafe { ((*p).period.load(Relaxed), (*p).decel_at.load(Relaxed)) };
        let left = self.left.wrapping_sub(1);
        // Past the trigger or at the last step (left ≤ at, at ≥ 0), or held to rest: a whole tick.
        if period == 0 || left <= at {
            return self.tick();
        }
        let acc = self.frac + period;
        let ms_left = self.ms_left - (acc >> 4) as i32;
        if ms_left <= 0 || acc >> 4 > self.max_tick {
            return self.tick();
        }
        self.plain_step(left, acc, ms_left)
    }

    /// The plain step [`Self::tick_quick`] found: `left` steps after it, `acc` the period's
    /// sum with the fraction, `ms_left` the millisecond's ticks after its gap.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".data.ramfunc.plain_step")]
    fn plain_step(&mut self, left: u32, acc: u32, ms_left: i32) -> u16 {
        let p = self.cur;
        let gap = acc >> 4;
        // SAFETY: as in `tick_quick`; plain fields, and the slaves only the step half touches.
        let (mut word, total, n) = unsafe { ((*p).master_on, (*p).total, (*p).n_slaves as usize) };
        // SAFETY: as above.
        word |= slave_bits(unsafe { &mut (*p).slaves }, n, total);
        if self.dual {
            word = toggle(word, &mut self.level);
        }
        self.word = word;
        self.left = left;
        self.shared.mv_done.store(total - left, Relaxed);
        self.frac = acc & 15;
        self.ms_left = ms_left;
        self.gap_in = gap;
        (gap - 1) as u16
    }

    /// The next edge: a step, a direction change or an idle gap, with the gap after it.
    #[inline(always)]
    fn next_event(&mut self) -> (u32, u32) {
        let ctl = self.shared.ctl.load();
        if ctl != self.ctl_seen {
            self.control(ctl);
        }
        if self.phase != Phase::Run {
            if self.phase == Phase::Enter {
                self.enter_next();
            } else if let Some(event) = self.other_event() {
                return event;
            }
        }
        self.step()
    }

    /// The next edge when not simply stepping: a move change's second half, a direction
    /// change, a hold, idle; `None` when it is a step after all (the phase is `Run` now).
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.other_event")]
    fn other_event(&mut self) -> Option<(u32, u32)> {
        match self.phase {
            Phase::Run => None,
            Phase::Enter => {
                self.enter_next();
                None
            }
            Phase::Dir => Some(self.dir_change()),
            Phase::Held => self.held(),
            Phase::Idle => self.refill(),
        }
    }

    /// One master step (and the slaves' share): the hot path.
    #[inline(always)]
    fn step(&mut self) -> (u32, u32) {
        let p = self.cur;
        // SAFETY: `cur` is the front slot of the ring, owned by the engine until it pops it;
        // its fields are reached through the pointer, never a reference to the whole move:
        // only its slaves are borrowed mutably (the feeder and the ramp half store its atomics).
        let mut period = unsafe { (*p).period.load(Relaxed) };
        if period == 0 {
            // The ramp half brought a hold to rest.
            return self.halt();
        }
        // SAFETY: as above; plain fields nobody writes while the move is published.
        let (mut word, total, n) = unsafe { ((*p).master_on, (*p).total, (*p).n_slaves as usize) };
        // SAFETY: as above; only the step half touches the slaves of the running move.
        word |= slave_bits(unsafe { &mut (*p).slaves }, n, total);
        if self.dual {
            word = toggle(word, &mut self.level);
        }
        self.left -= 1;
        self.shared.mv_done.store(total - self.left, Relaxed);
        // The trigger is 0 (cannot fire) until the ramp half has computed it for this move and
        // once it fired. (Not at the last step: a successor takes over the walk there, and with
        // none the move has reached its exit.)
        // SAFETY: as above; an atomic field.
        if self.left <= unsafe { (*p).decel_at.load(Relaxed) } && self.left != 0 {
            period = self.trigger();
        }
        let acc = self.frac + period;
        self.frac = acc & 15;
        let mut gap = acc >> 4;
        if self.left == 0 {
            gap = self.finish(gap, period);
        }
        (word, gap)
    }

    /// The deceleration trigger fired: the walk steps down at once, on a fresh millisecond
    /// (this step's gap already at the period one walk down, which the ramp half published with
    /// the trigger; it takes the walk from there). Returns that period.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.trigger")]
    fn trigger(&mut self) -> u32 {
        let p = self.cur;
        // SAFETY: `cur` is the running move's slot (as in `step`); only its atomic fields.
        let period = unsafe {
            (*p).decel_at.store(0, Relaxed);
            let period = (*p).down_period.load(Relaxed);
            (*p).period.store(period, Relaxed);
            period
        };
        self.ms_left = TICKS_PER_MS as i32;
        self.link().decel_in.store(self.cur as usize, Relaxed);
        bump(&self.link().decel);
        self.pend();
        period
    }
}
