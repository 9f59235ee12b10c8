//! The `$N` table: each setting's range, decimals, what a change redoes and where the image
//! keeps it; the one read and write path of `$$` and `$N=` (Grbl's checks and error numbers).
//!
//! Who uses it: the controller (`$$`, `$N=`) and the image code ([`Settings::decode`] checks
//! every value with [`Settings::is_valid`]).

use super::layout::{FLAGS, HOME, TAIL};
use super::values::*;
use crate::encoder;
use crate::error::Error;
use crate::motion::ramp::{Shape, FLEX_MAX, FLEX_MIN, MAX_RATE_HZ};
use crate::num::u32_of;
use crate::MAX_AXES;

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
pub(super) struct Spec {
    id: u16,
    range: u8,
    decimals: u8,
    change: Change,
    pub(super) at: u8,
    pub(super) bit: u8,
}

/// [`Spec::bit`] of a flag (or the shape) that has a byte of its own.
pub(super) const WHOLE: u8 = 8;

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
const LOW: [Spec; 36] = {
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
        spec(S_FLEX, 0, 0, Profile, TAIL + 17, 0),
    ]
};

/// A setting's field, for the one read and write path of `$$` and `$N=`.
pub(super) enum Slot<'a> {
    Real(&'a mut f32),
    Whole(&'a mut u32),
    Byte(&'a mut u8),
    Flag(&'a mut bool),
    Shape(&'a mut Shape),
}

impl Settings {
    /// Setting number `i` of the `$$` listing for `axes` axes (`None` past the end).
    pub fn id(i: usize, axes: usize) -> Option<u16> {
        let axes = axes.min(MAX_AXES);
        // [`LOW`]'s last three entries, `$580` to `$582`, come after the axis settings: numeric
        // order.
        match i.checked_sub(LOW.len() - 3) {
            None => LOW.get(i).map(|s| s.id),
            Some(j) if j < 4 * axes => Some(100 + 10 * (j / axes) as u16 + (j % axes) as u16),
            Some(j) if j == 4 * axes => Some(DUAL_EDGE),
            Some(j) if j == 4 * axes + 1 => Some(DMA_BURST),
            Some(j) if j == 4 * axes + 2 => Some(S_FLEX),
            Some(_) => None,
        }
    }

    /// Setting numbers in `$$` order for `axes` axes.
    pub fn ids(axes: usize) -> impl Iterator<Item = u16> {
        (0..).map_while(move |i| Self::id(i, axes))
    }

    /// How setting `id` is checked and stored, if it exists for `axes` axes.
    pub(super) fn spec(id: u16, axes: usize) -> Option<Spec> {
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
    pub(super) fn slot(&mut self, id: u16) -> Option<Slot<'_>> {
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
            S_FLEX => Byte(&mut self.flexible),
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
        if id == S_FLEX && !(FLEX_MIN as f32..=FLEX_MAX as f32).contains(&int) {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn low_ids_are_ours_and_every_fixed_one() {
        let ours = [
            0, 1, 2, 3, 4, 5, 6, STATUS_MASK, 12, 20, 21, 22, 23, 24, 25, 26, 27, 30, 31, 32, SPINDLE_PWM_HZ, DIR_SETUP,
            RAMP_START, RAMP_SHAPE, AXIS_COUNT, 87, 88, 89, 97, 98, 99, DUAL_EDGE, DMA_BURST, S_FLEX,
        ];
        assert_eq!(LOW.len(), ours.len() + FIXED.len());
        assert!(ours.iter().chain(FIXED.iter().map(|f| &f.0)).all(|id| LOW.iter().any(|s| s.id == *id)));
    }
}
