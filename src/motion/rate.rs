//! Step rates and timer periods: the [`Period`] type, the rate limits every table and move
//! obeys, and the conversions between the two.
//!
//! Who uses it: the ramp tables, the driver timing, moves and the planner (a leaf: it imports
//! nothing from the library but the timer clock).

use fixed::types::U28F4;

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
    let m = milli_hz.max(1);
    // (⌊⌊x/2⌋/m⌋ = ⌊x/2m⌋, and `m` ≥ 1: no divide-by-zero panic path, whose location
    // string would cost flash.)
    let q4 = (TIMER_HZ as u64 * 32_000 + m) / 2 / m;
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
