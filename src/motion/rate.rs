//! Step rates and timer periods: the [`Period`] type, the rate limits every table and move
//! obeys, and the conversions between the two.
//!
//! Who uses it: the ramp tables, the driver timing, moves and the planner (a leaf: it imports
//! nothing from the library but the timer clock and the number helpers).

use core::num::NonZeroU64;

use fixed::types::U28F4;

use crate::num::div_rem_u64;
use crate::TIMER_HZ;

/// A timer period in ticks with four fractional bits: the engine dithers the fraction so the
/// average rate is exact to 1/16 tick.
pub type Period = U28F4;

/// Lowest rate a table or move may use (steps/s): 1 step/s is 72 M ticks, well inside [`Period`].
pub const MIN_RATE_HZ: u32 = 1;
/// Highest rate a table or move may describe (steps/s); what the step interrupt sustains is
/// lower and is enforced by the engine's timing (`motion::timing`).
pub const MAX_RATE_HZ: u32 = 1_000_000;

/// Period of a rate given in milli-steps per second (rounded to the nearest 1/16 tick).
/// (64-bit integers, exact: `f32` has too few bits for the tick count of a slow rate.)
#[inline(never)]
pub fn period_of_millihz(milli_hz: u64) -> Period {
    let m = NonZeroU64::new(milli_hz).unwrap_or(NonZeroU64::MIN);
    // (⌊⌊x/2⌋/m⌋ = ⌊x/2m⌋.)
    let q4 = div_rem_u64((TIMER_HZ as u64 * 32_000 + m.get()) / 2, m).0;
    Period::from_bits(q4.min(u32::MAX as u64) as u32)
}

/// Period of a whole rate in steps/s.
pub fn period_of_hz(hz: u32) -> Period {
    period_of_millihz(hz as u64 * 1000)
}

/// Rate in steps/s of a period (for reports and tests).
pub fn hz_of_period(p: Period) -> f32 {
    TIMER_HZ as f32 * 16.0 / p.to_bits().max(1) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The same periods as the runtime's 64-bit division, for every rate that cannot
        /// overflow the sum (rates from 1 mHz, every bit length).
        #[test]
        fn period_of_millihz_matches_u64_division(m in any::<u64>(), shift in 0u32..64) {
            let m = (m >> shift).min(u64::MAX / 2);
            let m1 = m.max(1);
            let q4 = (TIMER_HZ as u64 * 32_000 + m1) / 2 / m1;
            prop_assert_eq!(period_of_millihz(m).to_bits(), q4.min(u32::MAX as u64) as u32);
        }
    }
}
