//! Probing, G38.2–G38.5, as Grbl 1.1's `mc_probe_cycle`: the line waits for the queue to run
//! out; a probe already in the state the cycle looks for is ALARM:4 (nothing moves). Otherwise
//! the probe input is armed ([`Shared::probe_arm`]) and the move is queued alone. The input's
//! edge stops the engine at its next tick ([`Shared::probe_input`]); the controller then flushes
//! the rest of the move, takes the engine's position (the pulses made) as the planner's and as
//! `[PRB:]`, with the success flag. A move that ends without contact is ALARM:5 for G38.2 and
//! G38.4 (the last `[PRB:]` position stays), while G38.3/G38.5 take the end position with
//! flag 0. `[PRB:x,y,z:f]` is reported after every cycle that moved, then the line's `ok`.
//!
//! [`Shared::probe_arm`]: crate::motion::shared::Shared::probe_arm
//! [`Shared::probe_input`]: crate::motion::shared::Shared::probe_input

use super::{Controller, Job};
use crate::grbl::reply::Out;
use crate::motion::shared::{State, PROBE_TRIPPED};
use crate::grbl::report;

/// A probe cycle in a job: the G38 digit (2–5) plus [`ARMED`] once its move is queued.
pub(super) const ARMED: u8 = 0x10;

impl<const N: usize> Controller<'_, N> {
    /// The probe input level as the shell read it (`low`: pin pulled to ground; `$6` applies).
    pub fn set_probe_input(&mut self, low: bool) {
        self.probe_pin = low != self.settings.probe_invert;
    }

    /// Carries a probe cycle on: false while it waits. `probe` is the job's cycle state.
    pub(super) fn probe_step(&mut self, job: &mut Job<N>, out: &mut impl Out) -> bool {
        let probe = &mut job.probe;
        let kind = *probe & 0xF;
        let away = kind >= 4;
        if *probe & ARMED == 0 {
            if !self.drained() {
                return false;
            }
            if self.probe_pin != away {
                // Already in contact (or, away, already clear): ALARM:4, nothing moves.
                report::alarm(out, report::ALARM_PROBE_INITIAL);
                self.alarm = true;
                self.probe_done();
                *probe = 0;
                job.mv = None;
                return true;
            }
            self.shared.probe_arm(away);
            *probe |= ARMED;
            return true; // the move is pushed next
        }
        let tripped = self.shared.probe_bits() & PROBE_TRIPPED != 0;
        if (!tripped && !self.drained()) || self.shared.state() != State::Idle {
            return false;
        }
        let hit = self.shared.probe_disarm();
        self.probe_done();
        let at = *self.planner.position_mm();
        if hit || kind & 1 == 1 {
            self.offsets.prb = at;
        }
        self.offsets.prb_ok = hit;
        if !hit && kind & 1 == 0 {
            report::alarm(out, report::ALARM_PROBE_CONTACT);
            self.alarm = true;
        }
        report::param(out, report::PARAM_LINES - 1, &self.offsets, self.axes);
        *probe = 0;
        true
    }

    /// The cycle is over: the rest of the move is dropped and the planner takes the position
    /// the engine reached; a failure is Grbl's (non-critical) alarm state.
    fn probe_done(&mut self) {
        self.flush_to_engine();
    }
}
