//! Start-up and soft reset: the banner, Ctrl-X, and the alarm state after a watchdog reset, a
//! lost position or a failed chip check.
//!
//! Who uses it: the firmware shell (boot and Ctrl-X), the controller's own `$C`/`$RST`.

use super::{Controller, Door, Jogging, SoftLimit};
use crate::grbl::chip::{self, Chip};
use crate::grbl::coords::Offsets;
use crate::grbl::gcode::Modal;
use crate::grbl::reply::Out;
use crate::grbl::report;
use crate::grbl::store::STARTUP_LINES;
use crate::motion::moves::Overrides;
use crate::motion::shared::State;

impl<const N: usize> Controller<'_, N> {
    /// The start-up banner (also after a soft reset).
    pub fn welcome(&mut self, out: &mut impl Out) {
        out.put(report::BANNER);
        if core::mem::take(&mut self.watchdog_note) {
            out.put(report::WATCHDOG_RESET);
        }
        if self.chip.as_ref().is_some_and(|c| !c.fits()) {
            report::alarm(out, report::ALARM_SELF_TEST);
            self.refuse(out);
        } else if self.alarm {
            out.put(report::UNLOCK_HINT);
        }
    }

    /// The part's device registers (call before [`Self::welcome`]); `$I` reports them. A part
    /// that fails [`Chip::fits`] stays in the alarm state with the drivers off: every line that
    /// would move, unlock or write flash is refused with [`chip::refusal`]'s reason, until a
    /// part that fits runs the firmware.
    pub fn chip_check(&mut self, c: Chip) {
        self.chip = Some(c);
        if !c.fits() {
            self.drivers_on = false;
            self.position_lost();
        }
    }

    /// On a part that failed the chip check: writes why (a line is being refused), true.
    pub(super) fn refuse(&self, out: &mut impl Out) -> bool {
        match &self.chip {
            Some(c) if !c.fits() => {
                chip::refusal(out, c);
                true
            }
            _ => false,
        }
    }

    /// The MCU came up from a watchdog reset (call before [`Self::welcome`]): the banner is
    /// followed by `[MSG:Reset by watchdog]`, and the controller is in the alarm state (the
    /// position is not known to be right; no startup lines run).
    pub fn watchdog_reset(&mut self) {
        self.watchdog_note = true;
        self.position_lost();
    }

    /// The position is not known to be right (a hard limit stopped the steps mid-move, or the
    /// watchdog reset the MCU): the alarm state, and no startup lines (call before
    /// [`Self::welcome`]).
    pub fn position_lost(&mut self) {
        self.alarm = true;
        self.startup_next = STARTUP_LINES;
    }

    /// Ctrl-X: stop at once, drop queued moves and any partial or held line, reset the modal
    /// state, G92 and the tool length offset, take the engine's position, print the banner.
    /// During motion this is ALARM:3 (positions stay exact, but Grbl asks for `$X`); from idle,
    /// a completed feed hold (`Hold:0`) or the alarm state (a hard limit) it is not. Startup lines run again (not in alarm).
    pub fn soft_reset(&mut self, out: &mut impl Out) {
        let state = self.shared.state();
        let moving = state != State::Held && (self.feeder.pending() > 0 || state != State::Idle);
        self.feeder.abort();
        self.shared.set_hold(false);
        self.shared.set_overrides(Overrides::NONE);
        self.lines.clear();
        self.job = None;
        self.modal = Modal::RESET;
        // A probe cycle ends (its edge must not stop a later move); Grbl keeps the last probe
        // position, not its success flag.
        self.shared.probe_disarm();
        let prb = self.offsets.prb;
        self.offsets = Offsets::new(self.stored.coords);
        self.offsets.prb = prb;
        self.jog = Jogging::Off;
        self.check = false;
        self.soft_limit = SoftLimit::Off;
        self.door = Door::Off;
        self.door_event = false;
        self.pushed = self.shared.moves_done();
        // The engine stops at its next tick; its position is final only then (see `poll`).
        self.resync = true;
        self.take_position();
        self.wco_count = 0;
        self.ovr_count = 0;
        if self.homing.take().is_some() {
            // Grbl's ALARM:6: reset during the homing cycle.
            self.alarm = true;
            report::alarm(out, report::ALARM_HOMING_RESET);
        } else if moving && !self.alarm {
            // (Already in alarm, as after a hard limit cut the move: no ALARM:3, as Grbl.)
            self.alarm = true;
            report::alarm(out, report::ALARM_RESET);
        }
        // Grbl wakes from `$SLP` into the alarm state.
        self.alarm |= core::mem::take(&mut self.sleep);
        self.startup_next = if self.alarm { STARTUP_LINES } else { self.next_startup(0) };
        self.welcome(out);
    }
}
