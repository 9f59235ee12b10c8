//! The look-ahead's searches on a ramp table: the index of a rate, of a distance, of a
//! cruise (binary searches, planner side only: never in an interrupt).
//!
//! Who uses it: the look-ahead and the feeder, to place moves on the table.

use super::table::{RampTable, IDX_FRAC, IDX_MASK, IDX_ONE};
use crate::motion::rate::Period;
use crate::num::u32_of;
use crate::TIMER_HZ;

impl<const L: usize> RampTable<L> {
    /// The fractional index (Q20) whose interpolated rate is `hz` (clamped to the table; 0
    /// below its start). Binary search: planner side only.
    pub fn index_of_hz(&self, hz: f32) -> u32 {
        // (The entries in use as one slice: the searches below index it without panic paths.)
        let periods = self.periods.get(..self.len as usize).unwrap_or_default();
        let (Some(first), Some(last)) = (periods.first(), periods.last()) else { return 0 };
        if !(hz > 0.0) {
            return 0;
        }
        let p = TIMER_HZ as f32 * 16.0 / hz;
        if p >= first.to_bits() as f32 {
            return 0;
        }
        if p <= last.to_bits() as f32 {
            return self.top_q();
        }
        // Last entry i with periods[i] > p (periods never rise along the table).
        let bits = |i: usize| periods.get(i).map_or(0.0, |q| q.to_bits() as f32);
        let (mut lo, mut hi) = (0usize, periods.len() - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if bits(mid) > p {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (a, b) = (bits(lo), bits(hi));
        // The rate is interpolated linearly between entries (`period_at`): the fraction of
        // the way from rate 1/a to 1/b that 1/p is.
        let f = if a > b { (a - p) * b / ((a - b) * p) } else { 0.0 };
        ((lo as u32) << IDX_FRAC) + u32_of(f.max(0.0).min(1.0) * IDX_ONE as f32).min(IDX_MASK)
    }

    /// The highest fractional index (Q20) whose [`Self::sum_at`] is at most `sum` (clamped to
    /// the table). Integer binary search: planner side only.
    pub fn index_of_sum(&self, sum: u32) -> u32 {
        // (One slice of the entries in use, read with `get`: no panic paths.)
        let sums = self.sums.get(..self.len as usize).unwrap_or_default();
        let n = sums.len();
        if n <= 1 || sum == 0 {
            return 0;
        }
        let at = |i: usize| sums.get(i).copied().unwrap_or(0);
        if sum >= at(n - 1) {
            return self.top_q();
        }
        let (mut lo, mut hi) = (0usize, n - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if at(mid) <= sum {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (a, b) = (at(lo), at(hi));
        // 12 fraction bits are plenty (an entry's sum is < 2^20, so this fits in 32 bits);
        // rounded down: the index never promises more distance than there is.
        let f = if b > a { ((sum - a) << 12) / (b - a) } else { 0 };
        ((lo as u32) << IDX_FRAC) + (f.min(4095) << (IDX_FRAC - 12))
    }

    /// First entry at least as fast as `cruise` (binary search, ≤ 11 steps), or `len`.
    pub fn cruise_index(&self, cruise: Period) -> u16 {
        let (mut lo, mut hi) = (0usize, self.len as usize);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if self.periods[mid] <= cruise {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        lo as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::ramp::shape::{RampConfig, Shape};
    use crate::motion::ramp::table::tests::xorshift;
    use crate::motion::rate::MIN_RATE_HZ;

    /// The former searches (indexing the arrays), as the reference.
    fn index_of_hz_ref<const L: usize>(t: &RampTable<L>, hz: f32) -> u32 {
        if t.len == 0 || !(hz > 0.0) {
            return 0;
        }
        let p = TIMER_HZ as f32 * 16.0 / hz;
        let n = t.len as usize;
        if p >= t.periods[0].to_bits() as f32 {
            return 0;
        }
        if p <= t.periods[n - 1].to_bits() as f32 {
            return t.top_q();
        }
        let (mut lo, mut hi) = (0usize, n - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if t.periods[mid].to_bits() as f32 > p {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (a, b) = (t.periods[lo].to_bits() as f32, t.periods[hi].to_bits() as f32);
        let f = if a > b { (a - p) * b / ((a - b) * p) } else { 0.0 };
        ((lo as u32) << IDX_FRAC) + u32_of(f.max(0.0).min(1.0) * IDX_ONE as f32).min(IDX_MASK)
    }

    fn index_of_sum_ref<const L: usize>(t: &RampTable<L>, sum: u32) -> u32 {
        let n = t.len as usize;
        if n <= 1 || sum == 0 {
            return 0;
        }
        if sum >= t.sums[n - 1] {
            return t.top_q();
        }
        let (mut lo, mut hi) = (0usize, n - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if t.sums[mid] <= sum {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (a, b) = (t.sums[lo], t.sums[hi]);
        let f = if b > a { ((sum - a) << 12) / (b - a) } else { 0 };
        ((lo as u32) << IDX_FRAC) + (f.min(4095) << (IDX_FRAC - 12))
    }

    #[test]
    fn searches_match_the_former_ones() {
        let mut next = xorshift();
        let mut table = RampTable::<256>::new();
        assert_eq!((table.index_of_hz(1000.0), table.index_of_sum(5)), (0, 0));
        for _ in 0..300 {
            let v0 = MIN_RATE_HZ + next(3_000);
            let vmax = v0 + next(100_000);
            let shape = if next(2) == 0 { Shape::Trapezoid } else { Shape::SCurve };
            if table.build(RampConfig { v0, vmax, accel: 100_000 + next(50_000_000), shape }).is_err() {
                continue;
            }
            let top = *table.sums.get(table.len as usize - 1).unwrap_or(&0);
            for _ in 0..200 {
                let hz = next(vmax + 2_000) as f32 + next(1000) as f32 / 1000.0;
                assert_eq!(table.index_of_hz(hz), index_of_hz_ref(&table, hz), "{hz}");
                let sum = next(top.saturating_add(100).max(1));
                assert_eq!(table.index_of_sum(sum), index_of_sum_ref(&table, sum), "{sum}");
            }
        }
    }
}
