//! Per-move S-curves (`$41=1`): every ramp leg, from the index where it starts to the index
//! where it ends, follows the seeds' normalised logistic instead of a straight line.
//!
//! Who uses it: the settings build the shared curve ([`SCurve::build`], floats, outside any
//! interrupt); the engine's ramp half maps each leg's linear progress through it
//! ([`Leg::at`], integers, once per ramp millisecond) and finds a leg's peak ([`peak`]).
//!
//! Design. The table stays the trapezoid's (linear in rate) and every move is planned and
//! walked as a trapezoid at `a / k`, `a` its own acceleration and `k = s'(½)` the curve's
//! peak slope (≈ 2.075 for `Flexible` = 4). A leg from index `i₀` to `i₁` that the linear walk
//! covers in `T` ms is run at index `i₀ + (i₁ − i₀)·s(p)`, `p` the linear progress: the rate is
//! linear in the index, so the S's peak acceleration is `k · a/k = a`, and since the curve is
//! symmetric (`s(1−x) = 1 − s(x)`) the leg covers `(v₀ + v₁)/2 · T`, exactly what the linear
//! walk covers (even sampled once per ms: `Σ s(j/n) = Σ j/n` over `j = 1..n`). So distances,
//! deceleration triggers, exact counts and G93's closed-form times stay the trapezoid's, and
//! the step interrupt is untouched. A leg starts wherever the walk changes what it heads for
//! (a move entered, a trigger, a hold, a resume, an override, a successor queued late), from
//! the index actually in use, so the curve never jumps; an up leg heads for its move's peak
//! (its cruise, or lower where the way down to the exit must start first: [`peak`]).

use super::table::{RampTable, IDX_ONE};
use crate::num::i32_of;

/// Segments of the shared curve (linear interpolation between its 65 points).
pub const S_SEG: usize = 64;
/// `Flexible` range and default (`$582`): the seeds' logistic over `±Flexible`.
pub const FLEX_MIN: u8 = 1;
pub const FLEX_MAX: u8 = 12;
pub const FLEX_DEFAULT: u8 = 4;

/// The normalised logistic `s(p)` at `S_SEG + 1` points, Q16 (`s(0) = 0`, `s(1) = 1`); all
/// zero: off (trapezoid, legs are linear).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SCurve {
    s: [u32; S_SEG + 1],
}

impl Default for SCurve {
    fn default() -> Self {
        Self::OFF
    }
}

impl SCurve {
    /// Off: every leg is linear (the trapezoid).
    pub const OFF: SCurve = SCurve { s: [0; S_SEG + 1] };

    /// The curve for `flexible` (the seeds' logistic over `±flexible`, normalised).
    pub fn build(flexible: u8) -> SCurve {
        let f = flexible.clamp(FLEX_MIN, FLEX_MAX) as f32;
        let (lo, hi) = (logistic(-f), logistic(f));
        let mut c = SCurve::OFF;
        for (i, v) in c.s.iter_mut().enumerate() {
            let x = f * (2.0 * i as f32 / S_SEG as f32 - 1.0);
            *v = crate::num::u32_of((logistic(x) - lo) / (hi - lo) * 65536.0 + 0.5);
        }
        c.s[0] = 0;
        c.s[S_SEG] = 1 << 16;
        c
    }

    /// True when legs follow the curve.
    #[inline(always)]
    pub fn on(&self) -> bool {
        self.s[S_SEG] != 0
    }

    /// `s(p)` for `p` in Q16 (`0..=65536`), interpolated, Q16.
    #[inline(always)]
    pub fn s_q16(&self, p: u32) -> u32 {
        let i = (p >> 10) as usize;
        let f = p & 1023;
        match (self.s.get(i), self.s.get(i + 1)) {
            (Some(&a), Some(&b)) => a + (((b - a) * f) >> 10),
            _ => 1 << 16,
        }
    }
}

/// The curve's peak slope `k = s'(½)` for `flexible`: the S lasts `k` times the trapezoid with
/// the same peak acceleration (the planner's accelerations are divided by it).
pub fn peak_slope(flexible: u8) -> f32 {
    let f = flexible.clamp(FLEX_MIN, FLEX_MAX) as f32;
    f / (2.0 * (2.0 * logistic(f) - 1.0))
}

fn logistic(x: f32) -> f32 {
    1.0 / (1.0 + exp_small(-x))
}

/// e^x for |x| ≲ 87, relative error < 1e-6: 2^k · e^r with |r| ≤ ½·ln 2 (ln 2 in two parts,
/// the high one of 16 bits so k·HI is exact) and a degree-8 Taylor series (smaller in flash
/// than `libm::expf`).
fn exp_small(x: f32) -> f32 {
    const LN2: f32 = core::f32::consts::LN_2;
    let t = x / LN2;
    let k = i32_of(if t >= 0.0 { t + 0.5 } else { t - 0.5 });
    const LN2_HI: f32 = 0.693_145_751_953_125;
    const LN2_LO: f32 = 1.428_606_820_3e-6;
    let r = (x - k as f32 * LN2_HI) - k as f32 * LN2_LO;
    let mut term = 1.0;
    let mut sum = 1.0;
    for n in 1..=8 {
        term *= r / n as f32;
        sum += term;
    }
    sum * f32::from_bits(((127 + k.clamp(-126, 127)) as u32) << 23)
}

/// One ramp leg: the index (Q20) it started at and the one it ends at. The linear walk starts
/// the leg at `from` too; the index in use is [`Leg::at`] its linear index.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Leg {
    pub from: u32,
    pub to: u32,
}

impl Leg {
    /// A leg from `from` to `to`.
    pub const fn new(from: u32, to: u32) -> Leg {
        Leg { from, to }
    }

    /// True when the leg heads down.
    #[inline(always)]
    pub fn down(&self) -> bool {
        self.to < self.from
    }

    /// The index in use when the linear walk is at `lin`: `from + (to − from)·s(p)`, `p` the
    /// linear progress from `from` to `to` (clamped to the leg). Off, or an empty leg: `lin`.
    #[inline(never)]
    pub fn at(&self, lin: u32, c: &SCurve) -> u32 {
        let (from, to) = (self.from, self.to);
        if from == to || !c.on() {
            return lin;
        }
        let up = to > from;
        let span = if up { to - from } else { from - to };
        let d = if up { lin.saturating_sub(from) } else { from.saturating_sub(lin) }.min(span);
        // Both below 2^15 before the shift by 16: a 32-bit division (no 64-bit libcall).
        let sh = (32 - span.leading_zeros()).saturating_sub(15);
        let p = ((d >> sh) << 16) / (span >> sh).max(1);
        let off = ((span as u64 * c.s_q16(p) as u64) >> 16) as u32;
        if up {
            from + off
        } else {
            from - off
        }
    }
}

/// The highest index in `from..=cap` (within 1/64 entry) whose way up from `from` and down to
/// `exit` fit in `left` master steps at the move's walk (`walk_q` entries per ms, Q20; `dist_q`
/// master steps per table distance, Q24: `RampPlan`'s): where an up leg must end for the
/// deceleration to start on time (the cruise when it fits). Binary search on the distance
/// sums, at a leg's start only.
pub fn peak<const L: usize>(from: u32, cap: u32, exit: u32, left: u32, (walk_q, dist_q): (u32, u32), table: &RampTable<L>) -> u32 {
    if cap <= from || table.is_empty() {
        return from;
    }
    let top = table.top_q();
    let base = table.sum_at(from.min(top));
    let xs = table.sum_at(exit.min(top));
    let fits = |p: u32| {
        let sp = table.sum_at(p.min(top));
        // (Two milliseconds at the peak to spare: the walk's samples and its trigger are a
        // millisecond apart, and a leg cut short before its end would leave the way down short.)
        let spare = 2 * ((table.per_ms_at(p.min(top)) as u64 * walk_q as u64) >> 20);
        let d = (sp - base.min(sp)) as u64 + sp.saturating_sub(xs) as u64 + spare;
        (d * dist_q as u64) >> 24 <= left as u64
    };
    if fits(cap) {
        return cap;
    }
    let (mut lo, mut hi) = (from, cap);
    while hi - lo > IDX_ONE >> 6 {
        let mid = lo + (hi - lo) / 2;
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_small_matches_libm() {
        let mut x = -30.0;
        while x < 30.0 {
            let (a, b) = (exp_small(x) as f64, libm::exp(x as f64));
            assert!(((a - b) / b).abs() < 1e-6, "exp({x}): {a} vs {b}");
            x += 0.01;
        }
    }

    #[test]
    fn curve_is_symmetric_and_its_peak_slope_is_k() {
        for f in FLEX_MIN..=FLEX_MAX {
            let c = SCurve::build(f);
            for i in 0..=S_SEG {
                let (a, b) = (c.s[i], c.s[S_SEG - i]);
                assert!((a + b).abs_diff(1 << 16) <= 1, "flexible {f}: s({i}) + s(1-) = {}", a + b);
            }
            let k = peak_slope(f) as f64;
            let mid = (c.s[S_SEG / 2 + 1] - c.s[S_SEG / 2 - 1]) as f64 / 65536.0 * S_SEG as f64 / 2.0;
            assert!((mid - k).abs() / k < 0.02, "flexible {f}: slope {mid} vs k {k}");
        }
        assert!((peak_slope(4) - 2.0746).abs() < 1e-3);
    }

    #[test]
    fn leg_maps_its_ends_exactly() {
        let c = SCurve::build(4);
        let up = Leg::new(3 << 20, 40 << 20);
        assert_eq!(up.at(3 << 20, &c), 3 << 20);
        assert_eq!(up.at(40 << 20, &c), 40 << 20);
        assert_eq!(up.at(50 << 20, &c), 40 << 20);
        let down = Leg::new(40 << 20, 0);
        assert_eq!(down.at(0, &c), 0);
        assert_eq!(down.at(40 << 20, &c), 40 << 20);
        // Off: the linear index.
        assert_eq!(up.at(7 << 20, &SCurve::OFF), 7 << 20);
    }
}
