//! Grbl-numbered settings (`$N=value`), their flash image, and what the engine derives from
//! them: the step [`Timing`] and the ramp table.
//!
//! Who uses it: the controller (`$$`, `$N=`), the firmware shell (flash load/save via
//! [`Settings::from_bytes`] / [`Settings::to_bytes`]).
//!
//! One ramp table serves every move. It is in path units: its rate is the path speed times the
//! largest `$100+i`, its acceleration twice the largest `$120+i` in those units, its top the
//! fastest path speed all axes allow together (capped by what fits in the table's 1.024 s).
//! Each move walks it at its own acceleration's fraction (from the axes it moves) and scales
//! it to its master's share of the path, so axes that do not move never slow a move down.

use crate::error::Error;
use crate::encoder::{self, EncoderSettings};
use crate::motion::ramp::{Profile, RampConfig, RampError, RampTable, Shape, MAX_RATE_HZ};
#[allow(unused_imports)]
use crate::motion::ramp::MAX_RATE_HZ as _;
use crate::num::{round_u32, sqrt, u32_of};
use crate::planning::planner::{Limits, JUNCTION_DEVIATION_MM};
use crate::motion::timing::{ns_to_ticks, Timing};
use crate::MAX_AXES;

/// Bytes of the flash image.
pub const SETTINGS_LEN: usize = 200;
const MAGIC: u8 = 0xD5;
const VERSION: u8 = 5;
/// Byte offset of the settings after the axis arrays: `$12`, `$30`, `$31`, `$33` (f32, u32),
/// `$32` (flag byte), the encoder's `$87`-`$99` from `TAIL + 20`, the homing `$24`, `$25`,
/// `$27` (f32) and `$26` (u32) from [`HOME`] (`$23` is byte 23); CRC last.
const TAIL: usize = 24 + 4 * 4 * MAX_AXES;
/// Byte offset of the homing settings, after the encoder's.
const HOME: usize = TAIL + 20 + crate::encoder::IMAGE_LEN;
const _: () = assert!(HOME + 16 <= SETTINGS_LEN - 4);
/// Byte offset of the flag bits (`$4`, `$5`, `$6`, `$20`, `$22`, `$21`, `$580`, `$581` as bits
/// 0..=7; an image from before `$580`/`$581` has their bits clear: single-edge, interrupt mode,
/// as it ran).
const FLAGS: usize = 19;
/// Absolute floor of the step period (ticks; 144 = 500 kHz, the engine's design limit). The
/// binding limits are the pulse rule and the step handler's measured cost, both applied by
/// `Timing::min_period_for`.
pub const ISR_FLOOR_TICKS: u32 = 144;

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

/// Grbl settings we report but do not implement, with the only value they accept.
/// (Their decimals for `$$` are in [`LOW`].)
const FIXED: [(u16, f32); 2] = [
    (11, 0.010), // junction deviation (the look-ahead's)
    (13, 0.0),   // report inches: no
];

/// How `$N=` checks one setting: the value range (an index into [`RANGES`]; bytes, flags and
/// the fixed settings have their own rules), the decimals `$$` shows, what a change redoes;
/// and where the flash image keeps it: byte `at`, and for a flag its bit (`WHOLE`: the byte is
/// 0 or 1).
#[derive(Clone, Copy)]
struct Spec {
    id: u16,
    range: u8,
    decimals: u8,
    change: Change,
    at: u8,
    bit: u8,
}

/// [`Spec::bit`] of a flag (or the shape) that has a byte of its own.
const WHOLE: u8 = 8;

/// Value ranges of the `f32` and `u32` settings (inclusive).
const RANGES: [(f32, f32); 10] = [
    (0.0, 0.0),                  // 0: no range (bytes, flags, fixed)
    (0.2, 100.0),                // 1: $0 pulse (0.2 µs: TMC drivers need 100 ns; shorter no driver takes)
    (1e-4, 1000.0),              // 2: $12 arc tolerance (below 0.1 µm a chord is far below a step)
    (0.0, 1e6),                  // 3: $30/$31 spindle, $130+ travel
    (1.0, 100_000.0),            // 4: $33 PWM frequency
    (0.0, 1000.0),               // 5: $29 direction setup
    (1.0, MAX_RATE_HZ as f32),   // 6: $40 ramp start
    (1e-3, 1e5),                 // 7: $100+ steps per unit
    (1e-3, 1e8),                 // 8: $110+ max rate, $120+ acceleration, $24/$25 homing rates
    (0.0, 65_535.0),             // 9: $26 homing debounce, ms (Grbl's u16)
];

const fn spec(id: u16, range: u8, decimals: u8, change: Change, at: usize, bit: u8) -> Spec {
    Spec { id, range, decimals, change, at: at as u8, bit }
}

/// Settings below 100 in `$$` order: Grbl's, ours and the [`FIXED`] ones.
const LOW: [Spec; 35] = {
    use Change::{None as Fixed, Pins, Profile, Shell};
    [
        spec(0, 1, 3, Profile, 4, 0),
        spec(1, 0, 0, Shell, 16, 0),
        spec(2, 0, 0, Pins, 17, 0),
        spec(3, 0, 0, Pins, 18, 0),
        spec(4, 0, 0, Shell, FLAGS, 0),
        spec(5, 0, 0, Shell, FLAGS, 1),
        spec(6, 0, 0, Shell, FLAGS, 2),
        spec(STATUS_MASK, 0, 0, Shell, 22, 0),
        spec(11, 0, 3, Fixed, 0, 0),
        spec(12, 2, 3, Shell, TAIL, 0),
        spec(13, 0, 0, Fixed, 0, 0),
        spec(20, 0, 0, Shell, FLAGS, 3),
        spec(21, 0, 0, Shell, FLAGS, 5),
        spec(22, 0, 0, Shell, FLAGS, 4),
        spec(23, 0, 0, Shell, 23, 0),
        spec(24, 8, 3, Shell, HOME, 0),
        spec(25, 8, 3, Shell, HOME + 4, 0),
        spec(26, 9, 0, Shell, HOME + 12, 0),
        spec(27, 3, 3, Shell, HOME + 8, 0),
        spec(DIR_SETUP, 5, 3, Profile, 8, 0),
        spec(30, 3, 0, Shell, TAIL + 4, 0),
        spec(31, 3, 0, Shell, TAIL + 8, 0),
        spec(32, 0, 0, Shell, TAIL + 16, WHOLE),
        spec(SPINDLE_PWM_HZ, 4, 0, Shell, TAIL + 12, 0),
        spec(RAMP_START, 6, 0, Profile, 12, 0),
        spec(RAMP_SHAPE, 0, 0, Profile, 20, WHOLE),
        spec(AXIS_COUNT, 0, 0, Profile, 21, 0),
        // The encoder's (`encoder::IDS`): read, written and stored by `EncoderSettings`.
        spec(encoder::AXIS, 0, 0, Fixed, 0, 0),
        spec(encoder::COUNTS_PER_STEP, 0, 0, Fixed, 0, 0),
        spec(encoder::INVERT, 0, 0, Fixed, 0, 0),
        spec(encoder::THRESHOLD, 0, 0, Fixed, 0, 0),
        spec(encoder::ACTION, 0, 0, Fixed, 0, 0),
        spec(encoder::LAG, 0, 0, Fixed, 0, 0),
        // Listed after the axis settings (`Settings::id`).
        spec(DUAL_EDGE, 0, 0, Pins, FLAGS, 6),
        spec(DMA_BURST, 0, 0, Pins, FLAGS, 7),
    ]
};

/// A setting's field, for the one read and write path of `$$` and `$N=`.
enum Slot<'a> {
    Real(&'a mut f32),
    Whole(&'a mut u32),
    Byte(&'a mut u8),
    Flag(&'a mut bool),
    Shape(&'a mut Shape),
}

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
    /// the engine buffered (`crate::motion::burst`); a change restarts the MCU.
    pub dma_burst: bool,
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
    /// `$2`/`$3`: the engine's pin map, fixed when the engine is built.
    Pins,
}

/// The ramp the profile was built with, for `$I` and the planner's clamp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ramped {
    pub cfg: RampConfig,
    /// Fastest master rate the timing allows.
    pub max_rate_hz: u32,
    /// The axis limits asked for a faster top than fits in the table.
    pub table_limited: bool,
    /// The cap is dual-edge mode's (`$580`).
    pub dual: bool,
    /// The cap is DMA burst mode's (`$581`).
    pub dma: bool,
    /// DMA burst mode: the fastest master rate at a junction joined at speed (one axis;
    /// `Timing::max_junction_rate_for`); 0 in the other modes (no junction limit of their own).
    pub junction_hz: u32,
}

impl Ramped {
    /// What `s` asks for on `axes` axes, before the table is built.
    pub fn wanted(s: &Settings, axes: usize) -> Ramped {
        let timing = s.timing();
        Ramped::of(s.ramp_config(axes, &timing), &timing, false)
    }

    /// The report of `cfg` under `timing`.
    fn of(cfg: RampConfig, timing: &Timing, table_limited: bool) -> Ramped {
        let junction_hz = if timing.dma { timing.max_junction_rate_for(0) } else { 0 };
        Ramped { cfg, max_rate_hz: timing.max_rate_hz(), table_limited, dual: timing.dual, dma: timing.dma, junction_hz }
    }
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

    /// Setting number `i` of the `$$` listing for `axes` axes (`None` past the end).
    pub fn id(i: usize, axes: usize) -> Option<u16> {
        let axes = axes.min(MAX_AXES);
        // [`LOW`]'s last two entries, `$580` and `$581`, come after the axis settings: numeric
        // order.
        match i.checked_sub(LOW.len() - 2) {
            None => LOW.get(i).map(|s| s.id),
            Some(j) if j < 4 * axes => Some(100 + 10 * (j / axes) as u16 + (j % axes) as u16),
            Some(j) if j == 4 * axes => Some(DUAL_EDGE),
            Some(j) if j == 4 * axes + 1 => Some(DMA_BURST),
            Some(_) => None,
        }
    }

    /// Setting numbers in `$$` order for `axes` axes.
    pub fn ids(axes: usize) -> impl Iterator<Item = u16> {
        (0..).map_while(move |i| Self::id(i, axes))
    }

    /// How setting `id` is checked and stored, if it exists for `axes` axes.
    fn spec(id: u16, axes: usize) -> Option<Spec> {
        use Change::{Profile, Shell};
        match id {
            100..=139 => {
                let (g, i) = ((id - 100) / 10, (id % 10) as usize);
                if i >= axes.min(MAX_AXES) {
                    return None;
                }
                // $100+ steps/unit, $110+ max rate, $120+ acceleration, $130+ travel: from
                // byte 24, in that order.
                let at = 24 + 4 * (g as usize * MAX_AXES + i);
                Some(match g {
                    0 => spec(id, 7, 3, Profile, at, 0),
                    1 | 2 => spec(id, 8, 3, Profile, at, 0),
                    _ => spec(id, 3, 3, Shell, at, 0),
                })
            }
            _ => LOW.iter().find(|s| s.id == id).copied(),
        }
    }

    /// The field of setting `id` (`None` for the fixed ones and unknown numbers).
    fn slot(&mut self, id: u16) -> Option<Slot<'_>> {
        use Slot::*;
        Some(match id {
            0 => Real(&mut self.pulse_us),
            1 => Byte(&mut self.idle_delay_ms),
            2 => Byte(&mut self.step_invert),
            3 => Byte(&mut self.dir_invert),
            4 => Flag(&mut self.enable_invert),
            5 => Flag(&mut self.limit_invert),
            6 => Flag(&mut self.probe_invert),
            STATUS_MASK => Byte(&mut self.status_mask),
            12 => Real(&mut self.arc_tolerance),
            20 => Flag(&mut self.soft_limits),
            21 => Flag(&mut self.hard_limits),
            22 => Flag(&mut self.homing),
            23 => Byte(&mut self.homing_dir),
            24 => Real(&mut self.homing_feed),
            25 => Real(&mut self.homing_seek),
            26 => Whole(&mut self.homing_debounce_ms),
            27 => Real(&mut self.homing_pulloff),
            DIR_SETUP => Real(&mut self.dir_setup_us),
            30 => Real(&mut self.spindle_max),
            31 => Real(&mut self.spindle_min),
            32 => Flag(&mut self.laser_mode),
            DUAL_EDGE => Flag(&mut self.dual_edge),
            DMA_BURST => Flag(&mut self.dma_burst),
            SPINDLE_PWM_HZ => Whole(&mut self.spindle_pwm_hz),
            RAMP_START => Whole(&mut self.ramp_start_hz),
            RAMP_SHAPE => Shape(&mut self.shape),
            AXIS_COUNT => Byte(&mut self.axes),
            100..=139 => {
                let arr = match (id - 100) / 10 {
                    0 => &mut self.steps_per_mm,
                    1 => &mut self.max_rate,
                    2 => &mut self.accel,
                    _ => &mut self.max_travel,
                };
                Real(arr.get_mut((id % 10) as usize)?)
            }
            _ => return None,
        })
    }

    /// Value of setting `id` and its decimals for `$$`, if it exists for `axes` axes.
    pub fn get(&self, id: u16, axes: usize) -> Option<(f32, u32)> {
        // The encoder's first: `EncoderSettings` keeps their values and decimals.
        if let Some(v) = self.encoder.get(id) {
            return Some(v);
        }
        let spec = Self::spec(id, axes.min(self.axes as usize))?;
        let mut s = *self;
        let v = match s.slot(id) {
            Some(Slot::Real(v)) => *v,
            Some(Slot::Whole(v)) => *v as f32,
            Some(Slot::Byte(v)) => *v as f32,
            Some(Slot::Flag(v)) => *v as u8 as f32,
            Some(Slot::Shape(v)) => (*v == Shape::SCurve) as u8 as f32,
            None => FIXED.iter().find(|f| f.0 == id)?.1,
        };
        Some((v, spec.decimals as u32))
    }

    /// `$id=value`: checks and stores one setting (Grbl's rules: negative values refused,
    /// masks and flags truncated to integers).
    pub fn set(&mut self, id: u16, value: f32, axes: usize) -> Result<Change, Error> {
        if !value.is_finite() {
            return Err(Error::BadNumberFormat);
        }
        if value < 0.0 {
            return Err(Error::NegativeValue);
        }
        if encoder::IDS.contains(&id) {
            self.encoder.set(id, value, axes.min(self.axes as usize))?;
            return Ok(Change::Shell);
        }
        let int = libm::truncf(value);
        let spec = Self::spec(id, axes.min(self.axes as usize)).ok_or(Error::InvalidStatement)?;
        let bad = Err(Error::InvalidStatement);
        if id == 0 && value < 0.2 {
            return Err(Error::StepPulseMin);
        }
        // Grbl's rule: soft limits need homing (a known machine position).
        if id == 20 && int != 0.0 && !self.homing {
            return Err(Error::SoftLimitNeedsHoming);
        }
        if id == AXIS_COUNT && !(3.0..=axes.min(MAX_AXES) as f32).contains(&int) {
            return bad;
        }
        let (lo, hi) = RANGES.get(spec.range as usize).copied().unwrap_or_default();
        let in_range = (lo..=hi).contains(&value);
        match self.slot(id) {
            Some(Slot::Real(v)) if in_range => *v = value,
            Some(Slot::Whole(v)) if in_range => *v = u32_of(value),
            Some(Slot::Byte(v)) if int <= 255.0 => *v = u32_of(int) as u8,
            Some(Slot::Flag(v)) => *v = int != 0.0,
            Some(Slot::Shape(v)) if int <= 1.0 => *v = if int == 0.0 { Shape::Trapezoid } else { Shape::SCurve },
            Some(_) => return bad,
            None => {
                let f = FIXED.iter().find(|f| f.0 == id).ok_or(Error::InvalidStatement)?;
                return if libm::fabsf(value - f.1) < 1e-6 { Ok(Change::None) } else { bad };
            }
        }
        if id == STATUS_MASK {
            self.status_mask &= 3;
        }
        // Turning homing off turns soft limits off too (Grbl).
        if id == 22 {
            self.soft_limits &= self.homing;
        }
        Ok(spec.change)
    }

    /// True when every field is in the range [`Self::set`] accepts.
    pub fn is_valid(&self) -> bool {
        // Every axis is checked, also those beyond the axis count. Each value must come back
        // unchanged from `set` (compared as bits: integer compares, no calls).
        // (A copy and one store, not `Settings { axes, ..*self }`: that copies field by field.)
        let mut full = *self;
        full.axes = MAX_AXES as u8;
        let mut probe = full;
        let mut ok = (3..=MAX_AXES as u8).contains(&self.axes);
        for id in Self::ids(MAX_AXES).filter(|&id| id != AXIS_COUNT) {
            if let Some((v, _)) = full.get(id, MAX_AXES) {
                ok &= probe.set(id, v, MAX_AXES).is_ok()
                    && probe.get(id, MAX_AXES).map(|g| g.0.to_bits()) == Some(v.to_bits());
            }
        }
        ok
    }

    /// Step timing in timer ticks.
    pub fn timing(&self) -> Timing {
        // f32 like the rest of the settings math.
        let pulse = ns_to_ticks(round_u32(self.pulse_us * 1000.0));
        let dir = ns_to_ticks(round_u32(self.dir_setup_us * 1000.0));
        let t = Timing::new(pulse, dir, ISR_FLOOR_TICKS);
        if self.dma_burst {
            t.burst(self.dual_edge)
        } else if self.dual_edge {
            t.dual_edge(0)
        } else {
            t
        }
    }

    /// Table rate per mm/s of path speed on the first `axes` axes: the largest `$100+i`, so a
    /// move's master never runs faster than the table.
    pub fn per_mm(&self, axes: usize) -> f32 {
        self.steps_per_mm.iter().take(axes.max(1)).fold(0.0f32, |a, &b| a.max(b))
    }

    /// What the planner takes from the settings for `N` axes, with the ramp table's top rate.
    pub fn planner_limits<const N: usize>(&self, vmax_hz: u32) -> Limits<N> {
        Limits {
            steps_per_mm: core::array::from_fn(|i| self.steps_per_mm[i]),
            max_rate: core::array::from_fn(|i| self.max_rate[i]),
            accel: core::array::from_fn(|i| self.accel[i]),
            vmax_hz: vmax_hz.max(1),
            // The table's own path units: the axes in use ($42), as `Settings::build_profile`.
            per_mm: self.per_mm(self.axis_count(N)),
            junction_dev: JUNCTION_DEVIATION_MM,
            timing: self.timing(),
        }
    }

    /// The ramp table's top on `axes` axes once built (what the planner's limits take).
    pub fn wanted_vmax(s: &Settings, axes: usize) -> u32 {
        let mut p: Profile = Profile { ramp: crate::motion::ramp::RampTable::new(), timing: Timing::UNSET, per_mm: 0.0 };
        s.build_profile(axes, &mut p).cfg.vmax
    }

    /// The ramp asked for by the first `axes` axes (before the table's length is considered).
    /// The table is in path units (rate = path speed × [`Self::per_mm`]): its acceleration is
    /// twice the largest `$120+i` (a diagonal may accelerate faster than one axis; each move
    /// walks it at its own fraction), its top the fastest path speed the axes allow together.
    pub fn ramp_config(&self, axes: usize, timing: &Timing) -> RampConfig {
        let _ = timing;
        // max/min, not clamp, here and below: clamp's panic message would link integer
        // formatting into the firmware.
        #[allow(clippy::manual_clamp, reason = "clamp's panic path costs flash")]
        let axes = axes.max(1).min(MAX_AXES);
        let c = self.per_mm(axes);
        let mut accel = 0.0f32;
        let mut top2 = 0.0f32;
        for i in 0..axes {
            accel = accel.max(self.accel[i] * 2.0);
            let v = self.max_rate[i] / 60.0;
            top2 += v * v;
        }
        let accel = accel * c;
        let vmax = u32_of(sqrt(top2) * c).max(1).min(crate::motion::ramp::MAX_RATE_HZ);
        RampConfig {
            v0: self.ramp_start_hz.max(1).min(vmax),
            vmax,
            accel: u32_of(accel.min(u32::MAX as f32)).max(1),
            shape: self.shape,
        }
    }

    /// Rebuilds `profile` (table and timing) for `axes` axes. A ramp too long for the table is
    /// built steeper (moves walk it at their own fraction), so the top stays the axes' max rate.
    pub fn build_profile<const L: usize>(&self, axes: usize, profile: &mut Profile<L>) -> Ramped {
        let timing = self.timing();
        let mut cfg = self.ramp_config(axes, &timing);
        let mut table_limited = false;
        profile.timing = timing;
        profile.per_mm = self.per_mm(axes);
        for attempt in 0..6 {
            match profile.ramp.build(cfg) {
                // Too long for the table: a steeper table (every move walks it at its own
                // fraction, so no move runs faster), down to a lower top only as a last resort.
                Err(RampError::TooLong { .. }) if attempt < 4 => {
                    let ms = crate::num::f32_of_u64(RampTable::<L>::ramp_ms(&cfg));
                    cfg.accel = u32_of((cfg.accel as f32 * ms / (L as f32 - 2.0).max(1.0)).min(u32::MAX as f32 / 2.0)) + 1;
                }
                Err(RampError::TooLong { reachable_vmax }) => {
                    table_limited = true;
                    cfg.vmax = reachable_vmax.max(cfg.v0);
                }
                // Unreachable with the ranges `set` enforces; an empty table means every move
                // cruises at its own (clamped) rate, so the clamp falls to the start rate.
                Err(_) => cfg.vmax = cfg.v0,
                Ok(()) => break,
            }
        }
        Ramped::of(cfg, &timing, table_limited)
    }

    /// The flash image: magic, version, fields (little-endian, where [`LOW`] and
    /// [`Self::spec`] put them), CRC-32.
    pub fn to_bytes(&self) -> [u8; SETTINGS_LEN] {
        let mut b = [0u8; SETTINGS_LEN];
        copy_bytes(&mut b, &[MAGIC, VERSION, SETTINGS_LEN as u8, (SETTINGS_LEN >> 8) as u8]);
        let mut s = *self;
        for id in Self::ids(MAX_AXES) {
            let (Some(spec), Some(slot)) = (Self::spec(id, MAX_AXES), s.slot(id)) else { continue };
            let at = spec.at as usize;
            // Bytes and flags share their word with their neighbours: OR them in.
            let (word, own) = match slot {
                Slot::Real(v) => (v.to_bits(), true),
                Slot::Whole(v) => (*v, true),
                Slot::Byte(v) => (*v as u32, false),
                Slot::Flag(v) => ((*v as u32) << (spec.bit & 7), false),
                Slot::Shape(v) => ((*v == Shape::SCurve) as u32, false),
            };
            if let Some(w) = b.get_mut(at..at + 4) {
                let old = u32::from_le_bytes([w[0], w[1], w[2], w[3]]);
                w.copy_from_slice(&(if own { word } else { old | word }).to_le_bytes());
            }
        }
        for (k, v) in self.encoder.0.into_iter().enumerate() {
            put4(&mut b, TAIL + 20 + 4 * k, v.to_le_bytes());
        }
        let crc = crc32(&b[..SETTINGS_LEN - 4]);
        put4(&mut b, SETTINGS_LEN - 4, crc.to_le_bytes());
        b
    }

    /// Settings from a flash image, or `None` if it is not one (erased, other version, bad
    /// checksum, a value out of range).
    pub fn decode(b: &[u8]) -> Option<Settings> {
        let b: &[u8; SETTINGS_LEN] = b.get(..SETTINGS_LEN)?.try_into().ok()?;
        let word = |at: usize| u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
        if word(0) != u32::from_le_bytes([MAGIC, VERSION, SETTINGS_LEN as u8, (SETTINGS_LEN >> 8) as u8]) {
            return None;
        }
        if crc32(&b[..SETTINGS_LEN - 4]) != word(SETTINGS_LEN - 4) {
            return None;
        }
        let mut s = Settings::DEFAULT;
        for id in Self::ids(MAX_AXES) {
            let (Some(spec), Some(slot)) = (Self::spec(id, MAX_AXES), s.slot(id)) else { continue };
            let at = (spec.at as usize).min(SETTINGS_LEN - 8);
            let byte = b[at];
            let flag = match spec.bit {
                WHOLE if byte > 1 => return None,
                WHOLE => byte != 0,
                bit => byte >> (bit & 7) & 1 != 0,
            };
            match slot {
                Slot::Real(v) => *v = f32::from_bits(word(at)),
                Slot::Whole(v) => *v = word(at),
                Slot::Byte(v) => *v = byte,
                Slot::Flag(v) => *v = flag,
                Slot::Shape(v) => *v = if flag { Shape::SCurve } else { Shape::Trapezoid },
            }
        }
        s.encoder = EncoderSettings::from_bytes(&b[TAIL + 20..]);
        s.is_valid().then_some(s)
    }

    /// Settings from a flash image, or the defaults if it is not a valid one.
    pub fn from_bytes(b: &[u8]) -> Settings {
        Self::decode(b).unwrap_or(Settings::DEFAULT)
    }
}

/// Stores 4 bytes at `at`, if they fit. (Inlined: the callers' offsets are mostly constants,
/// so the check and the copy fold to plain stores.)
pub(crate) fn put4(b: &mut [u8], at: usize, v: [u8; 4]) {
    if let Some(w) = b.get_mut(at..at + 4) {
        w.copy_from_slice(&v);
    }
}

/// Copies `src` to the start of `dst`, as many bytes as both hold: the callers' lengths are
/// equal, and this has no length-mismatch panic path (`copy_from_slice`'s costs flash).
#[inline(never)]
pub(crate) fn copy_bytes(dst: &mut [u8], src: &[u8]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}

/// CRC-32 (IEEE 802.3, reflected), bitwise: small code, run only on load and save.
pub fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn low_ids_are_ours_and_every_fixed_one() {
        let ours = [
            0, 1, 2, 3, 4, 5, 6, STATUS_MASK, 12, 20, 21, 22, 23, 24, 25, 26, 27, 30, 31, 32, SPINDLE_PWM_HZ, DIR_SETUP,
            RAMP_START, RAMP_SHAPE, AXIS_COUNT, 87, 88, 89, 97, 98, 99, DUAL_EDGE, DMA_BURST,
        ];
        assert_eq!(LOW.len(), ours.len() + FIXED.len());
        assert!(ours.iter().chain(FIXED.iter().map(|f| &f.0)).all(|id| LOW.iter().any(|s| s.id == *id)));
    }
}
