//! Hold and stop: the control word's changes (feed hold on or off, immediate stop), a hold
//! coming to rest and its resume, and going idle with the positions each axis made.
//!
//! Who uses it: the step path (on a control change, a rest, a held tick) and a move change
//! that finds nothing queued.
//!
//! Each function has a section of its own (in flash's `.text`): the machine outliner leaves
//! functions with an explicit section alone, so no step-path code becomes a call.

use core::sync::atomic::Ordering::Relaxed;

use super::state::{Phase, Stepper, CLEARED};
use crate::motion::control::Ctl;
use crate::motion::engine::ticks::{IDLE_TICKS, PRIME_TICKS};
use crate::motion::prepared::Prepared;
use crate::motion::shared::State;
use crate::TICKS_PER_MS;

impl<'a, const N: usize, const L: usize> Stepper<'a, N, L> {
    /// The control word changed: an immediate stop, or a feed hold on or off.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".text.step.control")]
    pub(super) fn control(&mut self, ctl: Ctl) {
        let old = core::mem::replace(&mut self.ctl_seen, ctl);
        if ctl.stopped_since(old) && self.phase != Phase::Idle {
            self.stop_move();
        }
        let hold = ctl.hold();
        if hold == self.hold {
            return;
        }
        self.hold = hold;
        self.link().hold.store(hold, Relaxed);
        self.pend();
        match self.phase {
            Phase::Run | Phase::Enter | Phase::Dir if hold => {
                // The ramp half walks down from here, on a fresh millisecond.
                self.ms_left = TICKS_PER_MS as i32;
                self.publish(State::Holding);
            }
            Phase::Run | Phase::Enter | Phase::Dir => self.publish(State::Run),
            // A resume from rest waits in `held` for the ramp half's period.
            Phase::Held | Phase::Idle => {}
        }
    }

    /// A hold came to rest: no more steps until it is released.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".text.step.halt")]
    pub(super) fn halt(&mut self) -> (u32, u32) {
        self.phase = Phase::Held;
        self.publish(State::Held);
        (0, IDLE_TICKS)
    }

    /// Held: waits for the release and the ramp half's resume period; `None` once it resumes
    /// (the next edge is a step).
    pub(super) fn held(&mut self) -> Option<(u32, u32)> {
        // SAFETY: as in `step`; an atomic field.
        if self.hold || unsafe { (*self.cur).period.load(Relaxed) } == 0 {
            return Some((0, if self.hold { IDLE_TICKS } else { PRIME_TICKS }));
        }
        // Resume: the ramp half restarted the walk from the bottom of the table.
        self.ms_left = TICKS_PER_MS as i32;
        self.publish(State::Run);
        self.phase = Phase::Run;
        None
    }

    /// An immediate stop: the running move ends where it is, each axis at the steps it made.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".text.step.stop_move")]
    pub(super) fn stop_move(&mut self) {
        // SAFETY: the running slot; a plain field.
        let total = unsafe { (*self.cur).total };
        let done = total - self.left;
        self.ring.pop();
        self.go_idle(|p, i| {
            let made = if i == p.master as usize {
                done
            } else {
                // (`get`: `n_slaves < N`, and no panic path.)
                p.slaves.get(..p.n_slaves as usize).unwrap_or_default().iter().find(|s| s.axis as usize == i).map_or(0, |s| s.dda.made(done, total))
            };
            if p.steps[i] < 0 {
                -(made as i32)
            } else {
                made as i32
            }
        });
    }

    /// Publishes the positions after the running move (`made(move, axis)`) and goes idle.
    pub(super) fn go_idle(&mut self, made: impl Fn(&Prepared<N>, usize) -> i32) {
        // SAFETY: the slot was just popped but is not reused before the producer sees the pop
        // and pushes again, which cannot happen inside this interrupt.
        let p = unsafe { &*self.cur };
        self.shared.idle_at(|i| p.start[i].wrapping_add(made(p, i)));
        self.cur = core::ptr::null_mut();
        self.left = 0;
        self.phase = Phase::Idle;
        self.shared.period_bits.store(0, Relaxed);
        self.link().next.store(0, Relaxed);
        self.link().succ.store(CLEARED, Relaxed);
        self.publish(State::Idle);
    }
}
