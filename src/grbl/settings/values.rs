//! The settings themselves: the [`Settings`] struct, its defaults, the setting numbers of our
//! own, and what a change asks the caller to redo.
//!
//! Who uses it: every other settings file, the controller, the firmware shell and the tests.

use crate::encoder::EncoderSettings;
use crate::motion::ramp::Shape;
use crate::MAX_AXES;

/// Setting numbers of our own (free in Grbl 1.1, which uses 0-6, 10-13, 20-27, 30-32, 100+).
pub const DIR_SETUP: u16 = 29; // grblHAL's number for the direction-to-step delay
pub const RAMP_START: u16 = 40;
pub const RAMP_SHAPE: u16 = 41;
/// Axes the machine has (3 = XYZ gantry … 7 = X Y Z A B C U): reports, `$#`, `$$` and G-code
/// follow it.
pub const AXIS_COUNT: u16 = 42;
/// Grbl's status report mask: bit 0 MPos (else WPos), bit 1 `Bf:`.
pub const STATUS_MASK: u16 = 10;
pub const SPINDLE_PWM_HZ: u16 = 33; // grblHAL's number for the spindle PWM frequency
/// Dual-edge step mode (each step toggles its pin): free in Grbl 1.1 and in grblHAL (between
/// its panel settings, 540-579, and button actions, 590-599).
pub const DUAL_EDGE: u16 = 580;
/// DMA burst step output (TIM2 paces every edge, DMA stores the precomputed words; no interrupt
/// per edge): next to `$580`.
pub const DMA_BURST: u16 = 581;
/// The S-curve's `Flexible` (`$41=1`: the seeds' logistic over `±Flexible`, 1..=12): next to
/// `$581`, also free in grblHAL (whose 580-589 are unused).
pub const S_FLEX: u16 = 582;

/// Persistent settings. Axis arrays are indexed X Y Z A B C U; only the firmware's first N
/// axes are reported and used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// `$0` step pulse width, µs (1..=100).
    pub pulse_us: f32,
    /// `$1` step idle delay, ms: drivers are disabled this long after motion stops; 255 keeps
    /// them enabled.
    pub idle_delay_ms: u8,
    /// `$2` step pulse invert mask (bit i = axis i).
    pub step_invert: u8,
    /// `$3` direction invert mask.
    pub dir_invert: u8,
    /// `$4` enable pin invert (the board's enable is active low).
    pub enable_invert: bool,
    /// `$5` limit pins invert (stored only: no limit inputs yet).
    pub limit_invert: bool,
    /// `$6` probe pin invert (stored only).
    pub probe_invert: bool,
    /// `$20` soft limits: moves outside the travel box (`$130+i`) are refused. Needs `$22`.
    pub soft_limits: bool,
    /// `$21` hard limits: a limit input going active stops all step output (ALARM:1).
    pub hard_limits: bool,
    /// `$22` homing enabled: the controller boots in the alarm state (Grbl's homing lock).
    pub homing: bool,
    /// `$23` homing direction mask: bit i set homes axis i toward its min end (negative).
    pub homing_dir: u8,
    /// `$24` homing locate feed, `$25` seek rate, mm/min.
    pub homing_feed: f32,
    pub homing_seek: f32,
    /// `$26` homing debounce: pause after each homing pass, ms (0..=65 535).
    pub homing_debounce_ms: u32,
    /// `$27` homing pull-off, mm.
    pub homing_pulloff: f32,
    /// `$12` arc tolerance: largest distance of a chord from its arc, mm.
    pub arc_tolerance: f32,
    /// `$30` spindle speed at full PWM duty (rpm, or laser power units).
    pub spindle_max: f32,
    /// `$31` spindle speed at the lowest non-zero duty.
    pub spindle_min: f32,
    /// `$32` laser mode: S changes do not stop motion, M4 scales power with speed.
    pub laser_mode: bool,
    /// `$33` spindle PWM frequency, Hz.
    pub spindle_pwm_hz: u32,
    /// `$29` direction setup before the next step edge, µs (0..=1000).
    pub dir_setup_us: f32,
    /// `$40` ramp start rate v0, master steps/s.
    pub ramp_start_hz: u32,
    /// `$41` ramp shape: 0 trapezoid, 1 S-curve.
    pub shape: Shape,
    /// `$100+i` steps per unit (mm, or degree on rotary axes).
    pub steps_per_mm: [f32; MAX_AXES],
    /// `$110+i` max rate, unit/min.
    pub max_rate: [f32; MAX_AXES],
    /// `$120+i` acceleration, unit/s².
    pub accel: [f32; MAX_AXES],
    /// `$130+i` max travel, unit: the machine box is `-$130+i ..= 0` (soft limits, `$20`).
    pub max_travel: [f32; MAX_AXES],
    /// `$10` status report mask: bit 0 MPos (else WPos), bit 1 buffer state.
    pub status_mask: u8,
    /// `$42` axes the machine has, 3..=7.
    pub axes: u8,
    /// `$87`-`$89`, `$97`-`$99`: encoder feedback.
    pub encoder: EncoderSettings,
    /// `$580` dual-edge step mode: each step toggles its pin (drivers stepping on both edges,
    /// TMC22xx `dedge`); `$2` does not apply then.
    pub dual_edge: bool,
    /// `$581` DMA burst step output: TIM2's events have DMA store the step words and periods
    /// the engine buffered (`crate::motion::burst`); a change rebuilds the step output at rest.
    pub dma_burst: bool,
    /// `$582` the S-curve's `Flexible` (1..=12): its steepness; the S lasts
    /// `ramp::peak_slope(flexible)` times the trapezoid with the same peak acceleration.
    pub flexible: u8,
}

impl Default for Settings {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What one accepted `$N=value` changed, so the caller knows what to redo.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// Nothing (a fixed setting written with its own value).
    None,
    /// Only the firmware shell's view (idle delay, enable invert, stored-only settings).
    Shell,
    /// Timing or ramp: the profile must be rebuilt.
    Profile,
    /// `$2`/`$3`/`$580`/`$581`: the pin map or the step output's mode, which the firmware
    /// shell rebuilds at rest.
    Pins,
}

impl Settings {
    /// Safe defaults for a small gantry, Grbl's own: 250 steps/mm, 500 mm/min, 10 mm/s²,
    /// 200 mm travel on an XYZ machine; 3 µs pulses and 5 µs direction setup (TB6600-safe);
    /// trapezoid from 1 kHz; MPos in reports.
    pub const DEFAULT: Settings = Settings {
        pulse_us: 3.0,
        idle_delay_ms: 25,
        step_invert: 0,
        dir_invert: 0,
        enable_invert: false,
        limit_invert: false,
        probe_invert: false,
        soft_limits: false,
        hard_limits: false,
        homing: false,
        homing_dir: 0,
        homing_feed: 25.0,
        homing_seek: 500.0,
        homing_debounce_ms: 250,
        homing_pulloff: 1.0,
        arc_tolerance: 0.002,
        spindle_max: 1000.0,
        spindle_min: 0.0,
        laser_mode: false,
        spindle_pwm_hz: 1000,
        dir_setup_us: 5.0,
        ramp_start_hz: 1000,
        shape: Shape::Trapezoid,
        steps_per_mm: [250.0; MAX_AXES],
        max_rate: [500.0; MAX_AXES],
        accel: [10.0; MAX_AXES],
        max_travel: [200.0; MAX_AXES],
        status_mask: 1,
        axes: 3,
        encoder: EncoderSettings::DEFAULT,
        dual_edge: false,
        dma_burst: false,
        flexible: crate::motion::ramp::FLEX_DEFAULT,
    };

    /// The seed paper's bench (the settings before the safe defaults, which the demos and
    /// the tests that measure rates set explicitly): 100 steps/mm, 36 000 mm/min (60 kHz),
    /// 10 000 mm/s² (10⁶ steps/s²) on seven axes.
    pub const BENCH: Settings = Settings {
        steps_per_mm: [100.0; MAX_AXES],
        max_rate: [36_000.0; MAX_AXES],
        accel: [10_000.0; MAX_AXES],
        max_travel: [1000.0; MAX_AXES],
        axes: MAX_AXES as u8,
        ..Settings::DEFAULT
    };

    /// Axes in use on a firmware built for `n`.
    pub fn axis_count(&self, n: usize) -> usize {
        (self.axes as usize).clamp(1, n.max(1))
    }
}
