//! Move change: the running move's last step finds its successor (primed by the ramp half,
//! or queued too late), the next tick enters it, with a direction change and its setup gap
//! when the pins change; or the queue ended.
//!
//! Who uses it: the step path (the last step of a move, and the tick after it).

use core::sync::atomic::Ordering::Relaxed;

use super::state::{bump, Phase, Stepper, CLEARED};
use crate::motion::prepared::Prepared;

/// A tick whose own period (the gap from its update event to the next) is at least this (2048
/// ticks: below 35 kHz) leaves room before a direction change for the change itself: the
/// finishing step's gap is shortened by the setup.
const SHORT_GAP: u32 = 2048;

impl<'a, const N: usize, const L: usize> Stepper<'a, N, L> {
    /// The move after the running one becomes the running one (the second half of a move
    /// change, on the tick after the last step: the first half found it).
    #[inline(always)]
    pub(super) fn enter_next(&mut self) {
        self.ring.pop();
        let link = self.link();
        self.enter(link.next.load(Relaxed) as *mut Prepared<N>);
        link.next.store(0, Relaxed);
        // Primed for the move before: the ramp half primes this one's successor next.
        link.succ.store(CLEARED, Relaxed);
        self.phase = Phase::Run;
    }

    /// Makes `p` the running move (its steps and position record; the step path reads the
    /// rest from its slot, where the ramp half primed its period).
    #[inline(always)]
    pub(super) fn enter(&mut self, p: *mut Prepared<N>) {
        self.cur = p;
        // SAFETY: a published slot, now owned by the engine; a plain field.
        self.left = unsafe { (*p).total };
        // (The position record's sequence tells the ramp half, at its next run: until then the
        // move runs on the period and trigger it primed.)
        self.shared.start_move(p as *const Prepared<N>);
    }

    /// The next move starts with its direction change, then the setup gap.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.dir_change")]
    pub(super) fn dir_change(&mut self) -> (u32, u32) {
        self.enter_next();
        // SAFETY: as in `step`; plain fields the feeder never writes after publishing.
        unsafe { ((*self.cur).dir_word, (*self.cur).dir_setup) }
    }

    /// The running move made its last step (at `period`): the next one starts at the next
    /// edge (that tick frees this move's slot and enters it), or go idle now. Returns the gap
    /// after the last step: shortened when a direction change comes first and steps are slow;
    /// at speed the change comes one whole period after the last step, since this tick's late
    /// ARR store would otherwise shorten the setup gap instead.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.finish")]
    pub(super) fn finish(&mut self, gap: u32, period: u32) -> u32 {
        bump(&self.shared.moves_done);
        // The successor the ramp half primed (its period and trigger), else one queued since
        // it last ran. Primed means the slot after this move's: a ramp pass preempted between
        // its look at the ring and its store of `succ` can store, after this half entered
        // that move and cleared `succ`, the move now running (or a freed one); entering it
        // would free a slot past the ring's tail and replay stale moves.
        let mut p = self.link().succ.load(Relaxed) as *mut Prepared<N>;
        if self.ring.second() != Some(p) {
            p = self.unprimed(period);
            if p.is_null() {
                return self.end_of_queue(gap);
            }
        }
        // SAFETY: a published slot; plain fields and its atomics (read where needed, so the
        // common path keeps few registers).
        unsafe {
            // The rate in force from the next step on (reports, and the ramp half's own once
            // it sees the change, right after this tick).
            self.shared.period_bits.store((*p).period.load(Relaxed), Relaxed);
            self.link().next.store(p as usize, Relaxed);
            if (*p).dir_word == 0 {
                self.phase = Phase::Enter;
                return gap;
            }
        }
        self.phase = Phase::Dir;
        if self.gap_in >= SHORT_GAP {
            return self.room_for_dir(p, gap);
        }
        gap
    }

    /// Slow steps before a direction change: the change comes `dir_setup` before the next
    /// step would have (never sooner than the move's shortest gap after the last step).
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.room_for_dir")]
    pub(super) fn room_for_dir(&self, p: *mut Prepared<N>, gap: u32) -> u32 {
        // SAFETY: a published slot; plain fields.
        let (setup, min_gap) = unsafe { ((*p).dir_setup, (*p).min_gap) };
        gap.saturating_sub(setup).max(min_gap)
    }

    /// The running move ended with nothing queued after it: idle (at rest unless the feeder
    /// was late at speed, counted).
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.end_of_queue")]
    pub(super) fn end_of_queue(&mut self, gap: u32) -> u32 {
        self.ring.pop();
        if self.link().idx.load(Relaxed) != 0 && !self.hold {
            self.shared.starved.fetch_add(1, Relaxed);
        }
        self.go_idle(|p, i| p.steps[i]);
        gap
    }

    /// No successor primed: the move after the running one in the ring, if any, of this
    /// epoch, queued too late for the ramp half to prime it: the last period, never faster than
    /// that move allows, until the ramp half has seen the change (now: it computes the trigger
    /// too). Null when none.
    #[cold]
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.unprimed")]
    pub(super) fn unprimed(&mut self, period: u32) -> *mut Prepared<N> {
        let Some(p) = self.ring.second() else { return core::ptr::null_mut() };
        // SAFETY: a published slot; plain fields and an atomic.
        unsafe {
            if (*p).epoch != self.ctl_seen.epoch() {
                return core::ptr::null_mut();
            }
            if (*p).period.load(Relaxed) == 0 {
                (*p).period.store(period.max((*p).min_period.to_bits()), Relaxed);
            }
        }
        self.pend();
        p
    }
}
