//! Exact step targets: a G-code decimal as written times steps/mm, rounded half away from zero
//! (Grbl's `lround`), in integers.
//!
//! Who uses it: the G-code reader ([`crate::grbl::gcode::number`]) keeps each axis word's
//! [`Decimal`]; the interpreter adds whole-millimetre offsets and converts inches exactly where
//! it can; the planner ([`crate::planning::planner::Planner::line_exact`]) turns it into steps.
//!
//! Why: a decimal read as the nearest `f32` can fall just below a half step (`Y4.595` is
//! 4.594999790…, ×100 = 459.499979… → 459), where Grbl 1.1h on its AVR and grbl-sim move 460.
//! Here `4595 / 10^3 × 100` is exactly 459.5 and rounds to 460.
//!
//! How: steps/mm is an `f32`, an exact binary rational `m · 2^e` (m < 2^24; e ≤ −1 for any
//! value below 2^23, which the `$100` range 0.001–100 000 keeps). The target is then
//! `sig · m / 5^f / 2^(f − e)`: the integer quotient `Q = ⌊sig · m / 5^f⌋` (5^22 < 2^52) and
//! a shift, where rounding half up needs only `Q` (the dropped remainder is below one unit of
//! `Q`, and the half is a whole number of units): `⌊Q / 2^t⌋` plus the bit below, t = f − e ≥ 1.
//! 64-bit integer operations only (no `f64`, no 128-bit division).

use crate::error::Error;

/// Largest significand of a [`Decimal`]: 15 decimal digits, as the G-code reader reads.
pub const MAX_SIG: u64 = 999_999_999_999_999;
/// Most digits after the point of a [`Decimal`] (as the G-code reader reads).
pub const MAX_FRAC: u32 = 22;
/// Largest significand [`Decimal::steps`] takes: 2^40 − 1 (12 significant digits; every
/// decimal within ±1 000 000 mm with 6 digits after the point). Larger ones stay `f32`.
pub const MAX_EXACT_SIG: u64 = (1 << 40) - 1;

/// A decimal number `sig / 10^frac` exactly as written (|sig| ≤ [`MAX_SIG`], frac ≤
/// [`MAX_FRAC`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Decimal {
    pub sig: i64,
    pub frac: u8,
}

impl Decimal {
    /// Zero.
    pub const ZERO: Decimal = Decimal { sig: 0, frac: 0 };

    /// Checked: `None` beyond [`MAX_SIG`] or [`MAX_FRAC`].
    fn new(sig: i64, frac: u32) -> Option<Decimal> {
        (sig.unsigned_abs() <= MAX_SIG && frac <= MAX_FRAC).then_some(Decimal { sig, frac: frac as u8 })
    }

    /// `self × 25.4` (inches to mm; 25.4 = 254/10 exactly), or `None` if it needs more digits
    /// than a [`Decimal`] holds.
    #[inline(never)]
    pub fn inches(self) -> Option<Decimal> {
        // |sig| ≤ MAX_SIG: no overflow.
        Decimal::new(self.sig * 254, self.frac as u32 + 1)
    }

    /// `self + o` exactly where the `f32` `o` is a whole number (below 2^24 in size) and `self`
    /// has at most 11 digits after the point; `None` otherwise, or if the sum needs more digits
    /// than a [`Decimal`] holds.
    #[inline(never)]
    pub fn plus(self, o: f32) -> Option<Decimal> {
        if o.to_bits() << 1 == 0 {
            return Some(self); // ±0, without a soft-float compare
        }
        let w = crate::num::i32_of(o);
        if w as f32 != o || w.unsigned_abs() >= 1 << 24 || self.frac > 11 {
            return None;
        }
        // |w · 10^frac| < 2^24 · 10^11 < 2^61: no overflow.
        let mut o = w as i64;
        for _ in 0..self.frac {
            o *= 10;
        }
        Decimal::new(self.sig + o, self.frac as u32)
    }

    /// Whether [`Self::steps`] takes it (|sig| ≤ [`MAX_EXACT_SIG`]).
    #[inline(never)]
    pub fn exact_steps(self) -> bool {
        self.sig.unsigned_abs() <= MAX_EXACT_SIG
    }

    /// `round(self × steps_per_mm)`, halves away from zero (Grbl's `lround`), computed
    /// exactly; `Error::InvalidTarget` beyond ±(2^31 − 1) steps, for |sig| beyond
    /// [`MAX_EXACT_SIG`], or for a steps/mm that is not a normal number from 2^-126 to below
    /// 2^23 (the `$100` range is 0.001–100 000).
    #[inline(never)]
    pub fn steps(self, steps_per_mm: f32) -> Result<i64, Error> {
        let bits = steps_per_mm.to_bits();
        let exp = (bits >> 23) as i32; // sign bit included: a negative setting is refused
        if exp == 0 || exp >= 150 {
            return Err(Error::InvalidTarget);
        }
        // steps/mm = m · 2^(exp − 150); the decimal is mag / (5^f · 2^f).
        let m = (bits & 0x7f_ffff | 1 << 23) as u64;
        let f = self.frac as u32;
        // 5^f < 2^52 (f ≤ 22): no overflow, never zero.
        let mut d = 1u64;
        for _ in 0..f.min(MAX_FRAC) {
            d *= 5;
        }
        let mag = self.sig.unsigned_abs();
        if mag > MAX_EXACT_SIG {
            return Err(Error::InvalidTarget);
        }
        // Q = ⌊mag · m / d⌋ (mag · m < 2^64); up to 6 digits after the point d is below 2^16,
        // and the M3's 32-bit divide does it (no 64-bit division routine).
        let p = mag * m;
        // NonZero: dividing by it has no panic path.
        let q = match core::num::NonZeroU64::new(d) {
            Some(d) if d.get() >= 1 << 16 => crate::num::div_rem_u64(p, d).0,
            _ => div_by_u16(p, d as u32),
        };
        // ÷ 2^t, rounded half up (t ≥ 1 as exp < 150).
        let t = (150 - exp) as u32 + f;
        let n = if t > 64 { 0 } else { (q >> (t - 1) >> 1) + (q >> (t - 1) & 1) };
        if n >= 1 << 31 {
            return Err(Error::InvalidTarget);
        }
        Ok(if self.sig < 0 { -(n as i64) } else { n as i64 })
    }
}

/// `⌊p / d⌋` for `0 < d < 2^16`, a 16-bit digit at a time (each step's dividend is below 2^32).
fn div_by_u16(p: u64, d: u32) -> u64 {
    let (mut q, mut r) = (0u64, 0u32);
    for k in (0..4).rev() {
        let cur = r << 16 | (p >> (16 * k)) as u32 & 0xffff;
        // (d is never 0: the caller's 5^f ≥ 1; `max` drops the panic path.)
        let dd = d.max(1);
        q = q << 16 | (cur / dd) as u64;
        r = cur % dd;
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dec(sig: i64, frac: u8) -> Decimal {
        Decimal { sig, frac }
    }

    #[test]
    fn ties_round_away_from_zero() {
        assert_eq!(dec(4595, 3).steps(100.0), Ok(460));
        assert_eq!(dec(95815, 3).steps(100.0), Ok(9582));
        assert_eq!(dec(-4595, 3).steps(100.0), Ok(-460));
        assert_eq!(dec(45949, 4).steps(100.0), Ok(459));
        assert_eq!(dec(5, 1).steps(1.0), Ok(1));
        assert_eq!(dec(-5, 1).steps(1.0), Ok(-1));
        assert_eq!(dec(0, 0).steps(250.0), Ok(0));
    }

    #[test]
    fn offsets_and_inches_are_exact() {
        assert_eq!(dec(4595, 3).plus(10.0), Some(dec(14595, 3)));
        assert_eq!(dec(4595, 3).plus(-2.0), Some(dec(2595, 3)));
        assert_eq!(dec(4595, 3).plus(0.5), None);
        assert_eq!(dec(1, 0).plus(0.1), None); // 0.1f32 has 27 fraction bits
        assert_eq!(dec(5, 1).inches(), Some(dec(1270, 2)));
    }
}
