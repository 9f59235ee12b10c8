//! The acceleration's shape: the ideal profile each table entry takes its mean rate from
//! (trapezoid, or a logistic S-curve), outside any interrupt.
//!
//! Who uses it: the table build (`ramp/table.rs`), for its entries and its length.

use crate::num::{f32_of_u64, i32_of, u64_of};

/// Shape of the acceleration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Constant acceleration `a` (the seed paper's trapezoid; triangle on short moves).
    Trapezoid,
    /// Logistic (sigmoid) S-curve whose steepest acceleration is `a` (seeds 000 and 002).
    SCurve,
}

/// What a table is built from (master steps/s and steps/s²).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RampConfig {
    pub v0: u32,
    pub vmax: u32,
    pub accel: u32,
    pub shape: Shape,
}


/// Logistic steepness: the S-curve spans the logistic on [-S_CURVE_SPAN, S_CURVE_SPAN].
const S_CURVE_SPAN: f32 = 4.0;

/// How much longer the S-curve takes than a trapezoid with the same peak acceleration.
pub(super) fn s_curve_stretch() -> f32 {
    let norm = logistic(S_CURVE_SPAN) - logistic(-S_CURVE_SPAN);
    S_CURVE_SPAN / 2.0 / norm
}

fn logistic(x: f32) -> f32 {
    1.0 / (1.0 + exp_small(-x))
}

/// e^x for |x| ≲ 87, relative error < 1e-6: 2^k · e^r with |r| ≤ ½·ln 2 (ln 2 in two parts,
/// the high one of 16 bits so k·HI is exact) and a degree-8 Taylor series. Smaller in flash than `libm::expf` (the firmware budget is 32 KiB), and the
/// table only needs entries good to far better than 0.5 %.
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

/// Ideal profile's normalized progress (0..=1) at fraction `u` (0..=1) of the ramp.
fn s_curve(u: f32) -> f32 {
    let lo = logistic(-S_CURVE_SPAN);
    let hi = logistic(S_CURVE_SPAN);
    (logistic(-S_CURVE_SPAN + 2.0 * S_CURVE_SPAN * u) - lo) / (hi - lo)
}

/// Mean rate in ms `i` of an `n`-entry ramp, in milli-steps/s, for a ramp led by `lead`
/// (Q20 fraction of a ms, at most ½): entry `i` is the ideal profile's rate at `i + lead` ms
/// (with `lead` = ½ the mean over millisecond `i`), so entry 0 is `v0` plus `lead` ms of
/// acceleration: the jump from rest above the start rate that a move walking the table at a
/// fraction `lead` (or more) of an entry per ms also makes in one millisecond.
pub(super) fn mean_millihz(cfg: &RampConfig, i: usize, n: usize, lead: u32) -> u64 {
    let v0 = cfg.v0 as u64 * 1000;
    let vmax = cfg.vmax as u64 * 1000;
    let lead = lead.min(1 << 19) as u64;
    match cfg.shape {
        Shape::Trapezoid => {
            // v(t) = v0 + a·(t − ½ + lead) up to vmax (so its mean over ms 0 is v0 + a·lead);
            // the mean over [i, i+1) ms of the clamped line.
            let a = cfg.accel as u64; // milli-steps/s per ms
            if lead < 1 << 19 {
                // The rate at `i + lead` ms itself (a mean over a millisecond that reaches
                // `vmax` would put entry 0 of a table that tops out within its first ms
                // further above `v0` than `lead` ms of acceleration).
                return (v0 + ((a * ((i as u64) << 20 | lead)) >> 20)).min(vmax);
            }
            // The line's value at t = 0, doubled (it may be below zero: an offset keeps it
            // unsigned): 2·v0 − a·(1 − 2·lead).
            let back = (a * ((1 << 20) - 2 * lead)) >> 20;
            let end2 = 2 * v0 + a * (2 * i as u64 + 2);
            if end2 <= 2 * vmax + back {
                (2 * v0 + a * (2 * i as u64 + 1)).saturating_sub(back) / 2
            } else {
                // (2·start, where the ms begins on the line.)
                let start2 = (2 * v0 + a * 2 * i as u64).saturating_sub(back);
                if start2 >= 2 * vmax {
                    return vmax;
                }
                // Ramp part of length f = (vmax-start)/a ms, then vmax for 1-f: the mean is
                // vmax - d²/(2a) with d = vmax - start < a, whose floor is taken in integers
                // (d² < 2^64 as d < a ≤ u32::MAX; f32 has too few bits for milli-steps/s).
                let d = (2 * vmax - start2).div_ceil(2).min(a);
                vmax - (d * d).div_ceil(2 * a)
            }
        }
        Shape::SCurve => {
            // The logistic stretched over n ms at `i + lead` (Simpson-free: the curve is
            // smooth enough that the midpoint is within 0.1 % of the mean here).
            let at = i as f32 + lead as f32 * (1.0 / (1u32 << 20) as f32);
            let u = (at / n as f32).min(1.0);
            let v = f32_of_u64(v0) + f32_of_u64(vmax - v0) * s_curve(u);
            // max/min, not clamp: its panic message would link integer formatting.
            u64_of(v).max(v0.max(1)).min(vmax.max(1))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_small_matches_libm() {
        let mut x = -30.0;
        while x < 30.0 {
            // 1e-8 when this ran in f64; in f32 a few ulps (2^-24 = 6e-8 each): the S-curve
            // table needs entries good to far better than 0.5 %.
            let (a, b) = (exp_small(x) as f64, libm::exp(x as f64));
            assert!(((a - b) / b).abs() < 1e-6, "exp({x}): {a} vs {b}");
            x += 0.01;
        }
    }
}
