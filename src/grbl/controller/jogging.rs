//! `$J=` lines and jog cancel (0x85, or `!` while jogging), as in Grbl 1.1: the cancel
//! decelerates with the engine's feed hold, then drops the running and queued jog moves, and
//! the planner takes the engine's exact position.

use super::{Controller, Jogging};
use crate::grbl::jog;
use crate::planning::planner::Planned;
use crate::error::Error;
use crate::grbl::reply::Out;
use crate::motion::shared::State;

impl<const N: usize> Controller<'_, N> {
    /// 0x85 arrived: cancel jogging (nothing happens unless jog moves are queued or running).
    #[inline(never)]
    pub fn jog_cancel(&mut self) {
        if self.jog == Jogging::On {
            self.jog = Jogging::Cancel;
        }
    }

    /// True while jog moves are queued, running or being cancelled.
    pub fn jogging(&self) -> bool {
        self.jog != Jogging::Off
    }

    /// `$J=…` (the text after `=`): only when idle or already jogging.
    #[inline(never)]
    pub(super) fn jog_line(&mut self, text: &[u8], out: &mut impl Out) -> Result<(), Error> {
        let idle = self.drained() && !self.shared.hold_requested();
        if self.alarm || self.check || !(idle || self.jog == Jogging::On) {
            return Err(Error::NotIdle);
        }
        let j = jog::plan(text, self.axes, &self.modal, self.planner.position_mm(), &self.offsets)?;
        if self.beyond_travel(&j.target) {
            return Err(Error::TravelExceeded);
        }
        let mut planner = self.planner;
        // Overrides never scale a jog (Grbl).
        let mv = planner.line_exact(&j.target, &j.exact, Some(j.feed), &self.limits)?.map(|p| Planned { mv: p.mv.fixed(), ..p });
        self.planner = planner;
        let job = self.new_job();
        job.mv = mv;
        job.jog = true;
        self.advance(false, out);
        Ok(())
    }

    /// Follows a jog through: a feed hold while jogging cancels it (Grbl), a cancel waits for
    /// the hold to complete, then flushes the queue and re-syncs the planner.
    pub(super) fn jog_poll(&mut self, out: &mut impl Out) {
        match self.jog {
            Jogging::Off => {}
            Jogging::On if self.shared.hold_requested() => self.jog = Jogging::Cancel,
            Jogging::On => {
                let queued = self.job.is_some_and(|j| j.jog && j.mv.is_some());
                if self.drained() && !queued {
                    self.jog = Jogging::Off;
                }
            }
            Jogging::Cancel => {
                self.shared.set_hold(true);
                if matches!(self.shared.state(), State::Run | State::Holding) {
                    return;
                }
                // Stopped (held, or not started): drop the rest; the position is the pulses made.
                self.feeder.abort();
                self.shared.set_hold(false);
                if self.job.is_some_and(|j| j.jog) {
                    // A jog line waiting for queue room is one of the queued jogs: flushed too.
                    self.job = None;
                    crate::grbl::reply::put_ok(out);
                }
                self.pushed = self.shared.moves_done();
                self.sync_planner();
                self.jog = Jogging::Stopping;
            }
            Jogging::Stopping => {
                if self.shared.state() == State::Idle {
                    self.jog = Jogging::Off;
                }
            }
        }
    }
}
