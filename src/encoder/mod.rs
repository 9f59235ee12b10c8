//! Encoder feedback: a quadrature encoder on one motor (TIM3 in x4 encoder mode on PA6/PA7),
//! its position and speed, and step-loss detection against the step engine's position.
//!
//! Who uses it: the firmware shell samples TIM3 ([`count`]: every SysTick, and fresh in the
//! idle loop), the controller checks for step loss ([`loss::Monitor`]) and reports `|Enc:` in
//! status reports; the settings below are Grbl-numbered (`$87`–`$89`,
//! `$97`–`$99`: numbers neither Grbl 1.1 nor grblHAL gives a meaning).
//!
//! Everything is integer math but the reports (which reuse the status formatter).

pub mod count;
pub mod loss;

use crate::error::Error;

/// `$87`: the axis the encoder watches (0 none, 1 = X … 7 = U).
pub const AXIS: u16 = 87;
/// `$88`: encoder counts (x4: every edge of A and B) per motor step.
pub const COUNTS_PER_STEP: u16 = 88;
/// `$89`: the encoder counts down when the axis moves positive.
pub const INVERT: u16 = 89;
/// `$97`: step-loss threshold, steps (on top of the resolution and the lag allowance).
pub const THRESHOLD: u16 = 97;
/// `$98`: what a step loss does: 0 feed hold, 1 alarm (`ALARM:17`).
pub const ACTION: u16 = 98;
/// `$99`: motor lag allowance, ms: the threshold grows by the measured speed × this time.
pub const LAG: u16 = 99;
/// The encoder's setting numbers in `$$` order.
pub const IDS: [u16; 6] = [AXIS, COUNTS_PER_STEP, INVERT, THRESHOLD, ACTION, LAG];
/// Bytes of the settings' flash image.
pub const IMAGE_LEN: usize = 24;
/// Largest `$88`: at the engine's fastest 248 kHz this is 15.9 M counts/s, within what TIM3
/// counts through its input filter and what the 1 ms extension keeps.
pub const MAX_COUNTS_PER_STEP: f32 = 64.0;

/// Per setting, in [`IDS`] order: highest value (`$87`'s is the axis count), decimals in `$$`
/// (0: whole numbers, truncated as Grbl truncates masks and flags), the binary point of the
/// stored integer, default (stored). The lowest value is 0, but 1/2¹⁶ for `$88`.
const TABLE: [(u32, u8, u8, i32); 6] = [
    (7, 0, 0, 0),
    (MAX_COUNTS_PER_STEP as u32, 3, RATIO_SHIFT, 1 << RATIO_SHIFT),
    (1, 0, 0, 0),
    (1_000_000, 0, 0, 20),
    (1, 0, 0, 0),
    (1000, 3, LAG_SHIFT, 1 << LAG_SHIFT),
];
/// `$88` is kept as counts per step × 2¹⁶ (what the step-loss check computes with).
pub const RATIO_SHIFT: u8 = 16;
/// `$99` is kept as ms × 2¹³ = ms × 2¹⁶ / [`count::WINDOW_MS`]: the lag allowance per count of
/// the speed window, in counts × 2¹⁶.
pub const LAG_SHIFT: u8 = 13;
const _: () = assert!(1 << (RATIO_SHIFT - LAG_SHIFT) == count::WINDOW_MS);

/// The encoder's settings as fixed-point integers in [`IDS`] order (one table-driven path
/// for `$$`, `$N=` and flash, and no float math in the check: typed float fields cost ~1 KB
/// more firmware).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncoderSettings(pub [i32; 6]);

impl Default for EncoderSettings {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Index of setting `id` in [`IDS`].
fn index(id: u16) -> Option<usize> {
    match id {
        87..=89 => Some((id - 87) as usize),
        97..=99 => Some((id - 94) as usize),
        _ => None,
    }
}

impl EncoderSettings {
    /// Off; when turned on: one count per step, 20 steps, feed hold, 1 ms of lag.
    pub const DEFAULT: EncoderSettings =
        EncoderSettings([TABLE[0].3, TABLE[1].3, TABLE[2].3, TABLE[3].3, TABLE[4].3, TABLE[5].3]);

    /// `$87`: the watched axis (0 = X), if any.
    pub fn axis(&self) -> Option<usize> {
        (self.0[0] as usize).checked_sub(1)
    }
    /// `$88` counts per step × 2¹⁶.
    pub fn ratio(&self) -> i32 {
        self.0[1]
    }
    /// `$89` direction invert.
    pub fn invert(&self) -> bool {
        self.0[2] != 0
    }
    /// `$97` threshold, steps.
    pub fn threshold(&self) -> i32 {
        self.0[3]
    }
    /// `$98`: alarm (else feed hold).
    pub fn alarm(&self) -> bool {
        self.0[4] != 0
    }
    /// `$99` lag allowance, ms × 2¹³.
    pub fn lag(&self) -> i32 {
        self.0[5]
    }

    /// Value and decimals of setting `id` (one of [`IDS`]) for `$$`.
    pub fn get(&self, id: u16) -> Option<(f32, u32)> {
        // `get`, not indexing: no panic path in the firmware.
        let i = index(id)?;
        let (&v, &(_, decimals, shift, _)) = (self.0.get(i)?, TABLE.get(i)?);
        Some((v as f32 / (1u32 << shift) as f32, decimals as u32))
    }

    /// `$id=value` for one of [`IDS`] (`value` must be finite and not negative, as
    /// `Settings::set` checks first), on a machine with `axes` axes.
    pub fn set(&mut self, id: u16, value: f32, axes: usize) -> Result<(), Error> {
        let i = index(id).ok_or(Error::InvalidStatement)?;
        let (Some(slot), Some(&(hi, decimals, shift, _))) = (self.0.get_mut(i), TABLE.get(i)) else {
            return Err(Error::InvalidStatement);
        };
        let hi = if i == 0 { axes as u32 } else { hi };
        let v = if decimals == 0 { libm::truncf(value) } else { value };
        let scaled = v * (1u32 << shift) as f32 + 0.5;
        // `$88` must be at least one step of its fixed point: a ratio of 0 watches nothing.
        if !(value <= hi as f32 && scaled >= (i == 1) as u8 as f32) {
            return Err(Error::InvalidStatement);
        }
        // SAFETY: finite, not negative and within the table's range, so below 2^23 once
        // scaled (the unchecked conversion spares the saturating one's compare chain in flash).
        *slot = unsafe { scaled.to_int_unchecked::<i32>() };
        Ok(())
    }

    /// The flash image: the six integers, little-endian (range checks are
    /// `Settings::is_valid`'s).
    pub fn to_bytes(&self) -> [u8; IMAGE_LEN] {
        let mut b = [0u8; IMAGE_LEN];
        for (w, v) in b.chunks_exact_mut(4).zip(self.0) {
            w.copy_from_slice(&v.to_le_bytes());
        }
        b
    }

    /// Settings from [`Self::to_bytes`].
    pub fn from_bytes(b: &[u8]) -> Self {
        let mut s = Self::DEFAULT;
        for (w, v) in b.chunks_exact(4).zip(&mut s.0) {
            *v = i32::from_le_bytes([w[0], w[1], w[2], w[3]]);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_get_and_image_round_trip() {
        let mut s = EncoderSettings::DEFAULT;
        assert_eq!(s.axis(), None);
        s.set(AXIS, 2.0, 3).unwrap();
        s.set(COUNTS_PER_STEP, 0.25, 3).unwrap();
        s.set(INVERT, 1.0, 3).unwrap();
        s.set(THRESHOLD, 40.0, 3).unwrap();
        s.set(ACTION, 1.0, 3).unwrap();
        s.set(LAG, 2.5, 3).unwrap();
        assert_eq!(s.get(COUNTS_PER_STEP), Some((0.25, 3)));
        assert_eq!((s.axis(), s.ratio(), s.invert(), s.threshold(), s.alarm(), s.lag()), (Some(1), 16_384, true, 40, true, 20_480));
        assert_eq!(s.get(LAG), Some((2.5, 3)));
        s.set(THRESHOLD, 12.7, 3).unwrap();
        assert_eq!(s.threshold(), 12);
        assert_eq!(EncoderSettings::from_bytes(&s.to_bytes()), s);
        assert_eq!(s.set(AXIS, 4.0, 3), Err(Error::InvalidStatement));
        assert_eq!(s.set(COUNTS_PER_STEP, 0.0, 3), Err(Error::InvalidStatement));
        assert_eq!(s.set(COUNTS_PER_STEP, 65.0, 3), Err(Error::InvalidStatement));
        assert_eq!(s.set(LAG, 1000.5, 3), Err(Error::InvalidStatement));
        assert_eq!(s.set(12, 1.0, 3), Err(Error::InvalidStatement));
    }
}
