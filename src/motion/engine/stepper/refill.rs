//! Refill: while idle, the next move from rest, once the ramp table is free and the ramp
//! half has primed the move's period (never on the step path).
//!
//! Who uses it: the step path, on an idle tick.

use core::sync::atomic::Ordering::Relaxed;

use super::state::{bump, Phase, Stepper};
use crate::motion::engine::ticks::{IDLE_TICKS, PRIME_TICKS};
use crate::motion::shared::State;
use crate::TICKS_PER_MS;

impl<'a, const N: usize, const L: usize> Stepper<'a, N, L> {
    /// Loads the next move from rest, if any, once the ramp half has primed it (queue refill;
    /// never in the step path); `None` when the next edge is its first step.
    pub(super) fn refill(&mut self) -> Option<(u32, u32)> {
        const WAIT: Option<(u32, u32)> = Some((0, IDLE_TICKS));
        if self.hold {
            self.publish(State::Held);
            return WAIT;
        }
        if !self.ramp.enter() {
            return WAIT;
        }
        let Some(p) = self.ring.front() else {
            self.publish(State::Idle);
            return WAIT;
        };
        // SAFETY: a published slot; plain fields and an atomic.
        let (epoch, dir, setup, primed) = unsafe { ((*p).epoch, (*p).dir_word, (*p).dir_setup, (*p).period.load(Relaxed)) };
        if epoch != self.ctl_seen.epoch() {
            self.ring.pop(); // dropped by an immediate stop
            return WAIT;
        }
        if primed == 0 {
            bump(&self.link().primes);
            self.pend();
            return Some((0, PRIME_TICKS));
        }
        self.enter(p);
        self.phase = Phase::Run;
        self.publish(State::Run);
        // The ramp's milliseconds start at the move's first step.
        self.ms_left = TICKS_PER_MS as i32;
        if dir != 0 {
            self.ms_left += setup as i32;
            Some((dir, setup))
        } else {
            None
        }
    }
}
