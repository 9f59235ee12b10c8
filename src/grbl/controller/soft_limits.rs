//! Soft limits in the controller, as Grbl 1.1's `limits_soft_check`: a G-code target outside
//! the travel box (see [`crate::grbl::limits`]) feed-holds what is already moving, flushes the queue
//! once the machine has stopped (so the position stays exact), then reports ALARM:2 and
//! `[MSG:Reset to continue]` and reads nothing more until Ctrl-X, after which the controller
//! is in the alarm state (`$X` unlocks). The offending line gets no reply and moves nothing.
//! Jogs are checked separately (`error:15`, in `jogging.rs`).
//!
//! A hard limit (`$21`, [`Controller::hard_limit`]) takes the same locked state at once: the
//! firmware's limit interrupt has already stopped the step timer, so the queue is dropped
//! without a hold, ALARM:1 is reported, and the position is lost (the Ctrl-X that follows
//! leaves the alarm state on; the shell rebuilds the step output at it, no MCU reset).

use super::{Controller, SoftLimit};
use crate::grbl::limits;
use crate::grbl::reply::Out;
use crate::motion::shared::State;
use crate::grbl::report;

impl<const N: usize> Controller<'_, N> {
    /// True when soft limits are on and `target` (machine mm) leaves the travel box.
    pub(super) fn beyond_travel(&self, target: &[f32; N]) -> bool {
        self.settings.soft_limits && limits::outside(target, &self.settings.max_travel, self.axes)
    }

    /// A G-code line asked for a target outside the box: stop everything (see the module).
    pub(super) fn soft_limit_trip(&mut self) {
        self.trip(report::ALARM_SOFT_LIMIT);
    }

    /// Stops everything as a soft-limit trip does, reporting `alarm` (its `ALARM:N` and
    /// `[MSG:Reset to continue]`) once the machine has stopped.
    pub(super) fn trip(&mut self, alarm: u8) {
        self.job = None;
        self.lines.clear();
        self.alarm = true;
        self.shared.set_hold(true);
        self.soft_limit = SoftLimit::Stopping(alarm);
    }

    /// A limit switch stopped the step output (the shell already halted the step timer):
    /// drop everything, ALARM:1 and `[MSG:Reset to continue]`, read nothing until Ctrl-X.
    pub fn hard_limit(&mut self, out: &mut impl Out) {
        self.job = None;
        self.lines.clear();
        self.alarm = true;
        self.flush_to_engine();
        report::alarm(out, report::ALARM_HARD_LIMIT);
        self.soft_limit = SoftLimit::Locked;
    }

    /// True from a soft- or hard-limit trip until the reset.
    pub(super) fn tripped(&self) -> bool {
        self.soft_limit != SoftLimit::Off
    }

    /// Finishes a trip once the engine stands still: flush, re-sync, ALARM:2.
    pub(super) fn soft_limit_poll(&mut self, out: &mut impl Out) {
        let SoftLimit::Stopping(alarm) = self.soft_limit else { return };
        if matches!(self.shared.state(), State::Run | State::Holding) {
            return;
        }
        if out.room() < report::alarm_len(alarm) {
            return;
        }
        self.feeder.abort();
        self.shared.set_hold(false);
        self.pushed = self.shared.moves_done();
        self.sync_planner();
        report::alarm(out, alarm);
        self.soft_limit = SoftLimit::Locked;
    }
}
