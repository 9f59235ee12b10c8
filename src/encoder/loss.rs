//! Step-loss detection: the engine's step count of one axis against the encoder.
//!
//! Who uses it: the controller, once per idle-loop turn (every millisecond or sooner), with a
//! [`Reading`] taken there: the extended count read fresh from TIM3 and the axis's position
//! from the engine.
//!
//! Fixed point: the ratio is counts per step × 2¹⁶ (signed: negative with `$89`); positions
//! are compared in whole counts with wrapping 32-bit arithmetic (the count wraps too, and only
//! differences matter). The deviation `commanded × ratio − measured` trips when its size exceeds
//! `(threshold + 1 step) × ratio + 1 count + |speed| × lag`: one count is the encoder's
//! resolution, one step the engine's position counter running one edge ahead of the pins, and
//! the lag allowance the motor's rotor trailing its field while it moves (`$99`).

use super::count::WINDOW_MS;
use super::EncoderSettings;

/// One step = 1 << 16 in the fixed-point ratio.
const ONE: i64 = 1 << 16;

/// What the controller reads each turn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Reading {
    /// The watched axis's position in steps (the engine's).
    pub commanded: i32,
    /// The extended encoder count.
    pub counts: i32,
    /// Counts over the last [`WINDOW_MS`] ms.
    pub window: i32,
}

/// A detected step loss.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Loss {
    /// The axis (0 = X).
    pub axis: usize,
    /// Commanded minus measured position, steps (positive: the motor is behind; whole
    /// encoder counts).
    pub steps: f32,
    /// Alarm (`$98=1`) rather than feed hold.
    pub alarm: bool,
}

/// Where the check stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Armed {
    /// The next reading sets the zero (measured = commanded) and arms.
    Unsynced,
    Armed,
    /// A loss was reported: no more checks until [`Monitor::rearm`].
    Tripped,
}

/// The step-loss check of the watched axis.
#[derive(Clone, Copy, Debug)]
pub struct Monitor {
    axis: Option<usize>,
    /// Counts per step × 2¹⁶, negative when inverted; never 0 while `axis` is set.
    ratio: i32,
    /// The deviation allowed standing still, counts: (threshold + 1 step) × ratio rounded up,
    /// + 1 count.
    base: i32,
    /// Lag allowance per count of the speed window, counts × 2¹⁶ (lag / window × 2¹⁶).
    lag_per_count: i32,
    alarm: bool,
    /// Expected count minus encoder count at the last sync.
    zero: i32,
    last: Reading,
    armed: Armed,
}

impl Default for Monitor {
    fn default() -> Self {
        Self::OFF
    }
}

impl Monitor {
    pub const OFF: Monitor = Monitor {
        axis: None,
        ratio: ONE as i32,
        base: 0,
        lag_per_count: 0,
        alarm: false,
        zero: 0,
        last: Reading { commanded: 0, counts: 0, window: 0 },
        armed: Armed::Unsynced,
    };

    /// Takes `s` for a machine with `axes` axes (an axis beyond them: off); re-synced at the
    /// next reading.
    pub fn configure(&mut self, s: &EncoderSettings, axes: usize) {
        let ratio = s.ratio();
        *self = Monitor {
            axis: s.axis().filter(|&a| a < axes && ratio > 0),
            ratio: if s.invert() { -ratio } else { ratio },
            base: (((s.threshold() as i64 + 1) * ratio as i64 + 0xFFFF) >> 16) as i32 + 1,
            // ms × 2¹³ = ms × 2¹⁶ / WINDOW_MS: counts × 2¹⁶ per count of the window.
            lag_per_count: s.lag(),
            alarm: s.alarm(),
            ..Monitor::OFF
        };
    }

    /// The watched axis (0 = X), if any.
    pub fn axis(&self) -> Option<usize> {
        self.axis
    }

    /// True after a reported loss, until [`Self::rearm`].
    pub fn tripped(&self) -> bool {
        self.armed == Armed::Tripped
    }

    /// Accept the position as it is: the next reading becomes the new zero.
    pub fn rearm(&mut self) {
        self.armed = Armed::Unsynced;
    }

    /// Takes a reading and checks it: the loss, once, when the deviation passes the limit.
    pub fn update(&mut self, r: Reading) -> Option<Loss> {
        self.last = r;
        let axis = self.axis?;
        match self.armed {
            Armed::Unsynced => {
                self.zero = self.expected().wrapping_sub(r.counts);
                self.armed = Armed::Armed;
                None
            }
            Armed::Tripped => None,
            Armed::Armed => {
                // The lag allowance rounded up to a count.
                let lag = mul_q16(r.window.unsigned_abs() as i32, self.lag_per_count) + 1;
                if self.deviation().unsigned_abs() <= self.base.wrapping_add(lag) as u32 {
                    return None;
                }
                self.armed = Armed::Tripped;
                Some(Loss { axis, steps: self.error_steps(), alarm: self.alarm })
            }
        }
    }

    /// The count the commanded position should show (wrapping like the count itself).
    fn expected(&self) -> i32 {
        mul_q16(self.last.commanded, self.ratio)
    }

    /// Commanded − measured position at the last reading, counts (sign of steps × ratio;
    /// wrapping arithmetic: only the difference matters).
    fn deviation(&self) -> i32 {
        self.expected().wrapping_sub(self.last.counts).wrapping_sub(self.zero)
    }

    /// Commanded − measured position at the last reading, steps (to the encoder's count).
    pub fn error_steps(&self) -> f32 {
        self.deviation() as f32 * ONE as f32 / self.ratio as f32
    }

    /// The commanded position at the last reading, steps.
    pub fn commanded_steps(&self) -> i32 {
        self.last.commanded
    }

    /// The measured position at the last reading, steps.
    pub fn measured_steps(&self) -> f32 {
        self.last.commanded as f32 - self.error_steps()
    }

    /// The measured speed over the last window, steps/s.
    pub fn speed_steps_per_s(&self) -> f32 {
        self.last.window as f32 * (1000 * ONE / WINDOW_MS as i64) as f32 / self.ratio as f32
    }
}

/// `a × b / 2¹⁶`, floored, truncated to 32 bits (one long multiply).
fn mul_q16(a: i32, b: i32) -> i32 {
    ((a as i64 * b as i64) >> 16) as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn monitor(cps: f32, invert: bool, threshold: u32, lag_ms: f32) -> Monitor {
        let mut s = EncoderSettings::DEFAULT;
        for (id, v) in [(87, 1.0), (88, cps as f32), (89, invert as u8 as f32), (97, threshold as f32), (98, 1.0), (99, lag_ms as f32)] {
            s.set(id, v, 3).unwrap();
        }
        let mut m = Monitor::OFF;
        m.configure(&s, 3);
        m
    }

    #[test]
    fn syncs_then_trips_once_past_the_threshold() {
        let mut m = monitor(4.0, false, 10, 0.0);
        // Power-up at an arbitrary count: the first reading is the zero.
        assert_eq!(m.update(Reading { commanded: 100, counts: -7, window: 0 }), None);
        // 11 steps behind: within (10 + 1) steps + 1 count.
        assert_eq!(m.update(Reading { commanded: 200, counts: -7 + 89 * 4, window: 0 }), None);
        assert_eq!(m.error_steps(), 11.0);
        let loss = m.update(Reading { commanded: 200, counts: -7 + 88 * 4 - 1, window: 0 });
        assert_eq!(loss, Some(Loss { axis: 0, steps: 12.25, alarm: true }));
        assert!(m.tripped());
        assert_eq!(m.update(Reading { commanded: 300, counts: 0, window: 0 }), None);
        m.rearm();
        assert_eq!(m.update(Reading { commanded: 300, counts: 0, window: 0 }), None);
        assert_eq!(m.error_steps(), 0.0);
        assert_eq!(m.measured_steps(), 300.0);
    }

    #[test]
    fn inverted_fractional_ratio_and_lag() {
        // 0.25 counts/step, counting down: 400 steps forward = -100 counts.
        let mut m = monitor(0.25, true, 8, 2.0);
        m.update(Reading { commanded: 0, counts: 0, window: 0 });
        assert_eq!(m.update(Reading { commanded: 400, counts: -100, window: -25 }), None);
        assert_eq!(m.measured_steps(), 400.0);
        // 25 counts in 8 ms = 100 steps per 8 ms = 12 500 steps/s.
        assert_eq!(m.speed_steps_per_s(), 12_500.0);
        // Limit in whole counts: (8 + 1) steps × 0.25 = 2.25 → 3, + 1 count, + lag 2 ms at
        // 25 counts per 8 ms = 6.25 → 7 (rounded up, + 1): 11 counts = 44 steps.
        assert_eq!(m.update(Reading { commanded: 443, counts: -100, window: -25 }), None);
        assert_eq!(m.error_steps(), 44.0);
        assert!(m.update(Reading { commanded: 445, counts: -100, window: -25 }).is_some());
    }

    #[test]
    fn off_without_an_axis() {
        let mut m = Monitor::OFF;
        m.configure(&EncoderSettings::DEFAULT, 3);
        assert_eq!(m.axis(), None);
        assert_eq!(m.update(Reading { commanded: 1000, counts: 0, window: 0 }), None);
    }
}
