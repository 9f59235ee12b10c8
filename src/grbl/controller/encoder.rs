//! Encoder feedback in the controller: the step-loss check each turn of the idle loop, the
//! `|Enc:` status field and `$ENC` (see [`crate::encoder`]).
//!
//! A loss prints `[MSG:Step loss X 37]` (axis, commanded − measured steps) at once, then per
//! `$98`: a feed hold (the check re-arms, accepting the position, when the hold is released
//! with `~`), or an alarm taken like a soft-limit trip: hold, flush once stopped, `ALARM:17`
//! (grblHAL's "motor fault") and `[MSG:Reset to continue]`. In the alarm state the check
//! follows the position without judging it.

use super::Controller;
use crate::encoder::loss::Reading;
use crate::error::Error;
use crate::grbl::reply::Out;
use crate::grbl::report;

impl<const N: usize> Controller<'_, N> {
    /// One encoder reading (call each idle-loop turn, before the poll): `counts` the extended count read
    /// now, `window` the counts of the last [`crate::encoder::count::WINDOW_MS`] ms. Checks for
    /// step loss and acts on it.
    #[inline(never)]
    pub fn encoder(&mut self, counts: i32, window: i32, out: &mut impl Out) {
        let Some(axis) = self.enc.axis() else { return };
        let hold_trip = self.enc.tripped() && !self.settings.encoder.alarm();
        if self.alarm || self.sleep || (hold_trip && !self.shared.hold_requested()) {
            self.enc.rearm();
        }
        let Some(&commanded) = self.shared.positions().get(axis) else { return };
        let Some(loss) = self.enc.update(Reading { commanded, counts, window }) else { return };
        report::step_loss(out, loss.axis, loss.steps);
        if loss.alarm {
            self.trip(report::ALARM_STEP_LOSS);
        } else {
            self.shared.set_hold(true);
        }
    }

    /// Takes the encoder settings in force (at start-up and after every settings change).
    pub(super) fn enc_configure(&mut self) {
        self.enc.configure(&self.settings.encoder, self.axes);
    }

    /// `|Enc:` fields: measured position (mm, machine) and speed (mm/min), if an encoder
    /// watches an axis in use.
    #[inline(never)]
    pub(super) fn encoder_status(&self) -> Option<(f32, f32)> {
        let spm = *self.limits.steps_per_mm.get(self.enc.axis()?)?;
        Some((self.enc.measured_steps() / spm, self.enc.speed_steps_per_s() * 60.0 / spm))
    }

    /// `$ENC`: `[ENC:X,commanded mm,measured mm,commanded - measured steps]`.
    pub(super) fn encoder_report(&self, out: &mut impl Out) -> Result<(), Error> {
        let axis = self.enc.axis().ok_or(Error::SettingDisabled)?;
        let spm = *self.limits.steps_per_mm.get(axis).ok_or(Error::SettingDisabled)?;
        let e = &self.enc;
        report::encoder(out, axis, e.commanded_steps() as f32 / spm, e.measured_steps() / spm, e.error_steps());
        Ok(())
    }

    /// Commanded − measured position of the watched axis at the last reading, steps (what a
    /// step-loss report prints; for tests and tools).
    pub fn encoder_error_steps(&self) -> Option<f32> {
        self.enc.axis().map(|_| self.enc.error_steps())
    }
}
