//! Spindle and laser output (M3/M4/M5, S, `$30`–`$33`) and coolant (M7/M8/M9), as Grbl 1.1
//! drives them; the numbers the firmware writes to TIM1 (PWM on PA8) and the output pins.
//!
//! Who uses it: the controller, which calls [`duty`] at every poll (each millisecond) with the
//! speed in force: the programmed S times the spindle override, and in laser mode with `M4`
//! also times the engine's rate over the running move's cruise rate ([`Power`]), so the laser
//! power follows the ramps.
//!
//! PWM mapping (Grbl's `spindle_compute_pwm_value`): S ≤ 0 is off (duty 0); S at or above `$30`,
//! or `$31 ≥ $30`, is full duty; S at or below `$31` is the lowest non-zero duty (one count);
//! between, the duty is linear from `$31` to `$30`.

use crate::TIMER_HZ;

/// M3 / M4 / M5.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpindleDir {
    Off,
    /// M3: clockwise (laser: constant power).
    Cw,
    /// M4: counter-clockwise (laser: power scaled with speed).
    Ccw,
}

/// Coolant bits of [`crate::grbl::gcode::Modal::coolant`].
pub const MIST: u8 = 1;
pub const FLOOD: u8 = 2;

/// Laser power of one queued move (laser mode): what the poll uses while that move runs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Power {
    /// S, or 0 where the laser stays off (G0, M5).
    pub speed: f32,
    /// M4: scale by the engine's rate over `cruise_hz`.
    pub dynamic: bool,
    /// The move's master cruise rate, steps/s.
    pub cruise_hz: f32,
}

impl Power {
    /// The speed to output at master rate `rate_hz`.
    pub fn at(&self, rate_hz: u32) -> f32 {
        if self.dynamic {
            let ratio = rate_hz as f32 / self.cruise_hz.max(1.0);
            self.speed * ratio.min(1.0)
        } else {
            self.speed
        }
    }
}

/// What the firmware drives: TIM1 CCR1 and the enable, direction and coolant pins.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpindleOut {
    /// Compare value; the period is `arr + 1` counts of [`PwmTiming`] (0: off).
    pub ccr: u16,
    pub enable: bool,
    /// M4 (direction pin high).
    pub ccw: bool,
    pub mist: bool,
    pub flood: bool,
}

/// TIM1's prescaler and auto-reload for a PWM frequency (72 MHz timer clock).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PwmTiming {
    pub psc: u16,
    pub arr: u16,
}

impl PwmTiming {
    /// The finest resolution that reaches `hz` (1 ..= 100 000 Hz, `$33`).
    pub fn new(hz: u32) -> Self {
        let ticks = TIMER_HZ / hz.max(1);
        let psc = (ticks - 1) >> 16;
        let arr = ticks / (psc + 1) - 1;
        PwmTiming { psc: psc as u16, arr: arr.min(0xFFFF) as u16 }
    }
}

/// Compare value for `speed` (S after override and laser scaling) between `min` (`$31`) and
/// `max` (`$30`), for a period of `arr + 1` counts (a compare above ARR is full duty).
pub fn duty(speed: f32, min: f32, max: f32, arr: u16) -> u16 {
    let top = arr as u32 + 1;
    let ccr = if !(speed > 0.0) {
        0
    } else if min >= max || speed >= max {
        top
    } else if speed <= min {
        1
    } else {
        crate::num::round_u32((speed - min) / (max - min) * top as f32).max(1).min(top)
    };
    ccr.min(0xFFFF) as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pwm_timing_reaches_the_frequency() {
        for hz in [1, 50, 1000, 1099, 1100, 5000, 20_000, 100_000] {
            let t = PwmTiming::new(hz);
            let f = TIMER_HZ as f32 / ((t.psc as f32 + 1.0) * (t.arr as f32 + 1.0));
            assert!((f - hz as f32).abs() / (hz as f32) < 2e-3, "{hz} Hz: {t:?} gives {f}");
        }
        assert_eq!(PwmTiming::new(1000), PwmTiming { psc: 1, arr: 35_999 });
        assert_eq!(PwmTiming::new(5000), PwmTiming { psc: 0, arr: 14_399 });
    }

    #[test]
    fn duty_follows_grbls_mapping() {
        assert_eq!(duty(0.0, 0.0, 1000.0, 999), 0);
        assert_eq!(duty(-5.0, 0.0, 1000.0, 999), 0);
        assert_eq!(duty(f32::NAN, 0.0, 1000.0, 999), 0);
        assert_eq!(duty(500.0, 0.0, 1000.0, 999), 500);
        assert_eq!(duty(1000.0, 0.0, 1000.0, 999), 1000);
        assert_eq!(duty(5000.0, 0.0, 1000.0, 999), 1000);
        assert_eq!(duty(100.0, 200.0, 1000.0, 999), 1);
        assert_eq!(duty(600.0, 200.0, 1000.0, 999), 500);
        assert_eq!(duty(10.0, 1000.0, 1000.0, 999), 1000);
        assert_eq!(duty(0.0001, 0.0, 1000.0, 999), 1);
        assert_eq!(duty(1.0, 0.0, 1.0, 0xFFFF), 0xFFFF);
    }

    #[test]
    fn m4_power_scales_with_rate() {
        let p = Power { speed: 800.0, dynamic: true, cruise_hz: 20_000.0 };
        assert_eq!(p.at(10_000), 400.0);
        assert_eq!(p.at(0), 0.0);
        assert_eq!(p.at(30_000), 800.0);
        assert_eq!(Power { dynamic: false, ..p }.at(0), 800.0);
    }
}
