//! The acceleration's shape: the ideal profile each table entry takes its mean rate from,
//! outside any interrupt. The table is the trapezoid's for both shapes: the S-curve
//! (`ramp/scurve.rs`) is each ramp leg mapped through the logistic by the engine's ramp half.
//!
//! Who uses it: the table build (`ramp/table.rs`), for its entries and its length.

use core::num::NonZeroU64;

use crate::num::div_rem_u64;

/// Shape of the acceleration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Constant acceleration `a` (the seed paper's trapezoid; triangle on short moves).
    Trapezoid,
    /// Per-move logistic S-curve (seeds 000 and 002): the table is the trapezoid's at
    /// `a / k` and the ramp half maps every leg through the curve (`ramp/scurve.rs`).
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

/// Mean rate in ms `i` of the ramp, in milli-steps/s, for a ramp led by `lead`
/// (Q20 fraction of a ms, at most ½): entry `i` is the ideal profile's rate at `i + lead` ms
/// (with `lead` = ½ the mean over millisecond `i`), so entry 0 is `v0` plus `lead` ms of
/// acceleration: the jump from rest above the start rate that a move walking the table at a
/// fraction `lead` (or more) of an entry per ms also makes in one millisecond.
pub(super) fn mean_millihz(cfg: &RampConfig, i: usize, lead: u32) -> u64 {
    let v0 = cfg.v0 as u64 * 1000;
    let vmax = cfg.vmax as u64 * 1000;
    let lead = lead.min(1 << 19) as u64;
    // Both shapes: the S-curve's table is the trapezoid's (see `ramp/scurve.rs`).
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
        // (⌈⌈x/a⌉/2⌉ = ⌈x/2a⌉; `a` ≥ 1 as `build` refuses a zero accel.)
        let d = (2 * vmax - start2).div_ceil(2).min(a);
        let (q, r) = div_rem_u64(d * d, NonZeroU64::new(a).unwrap_or(NonZeroU64::MIN));
        vmax - (q + (r != 0) as u64).div_ceil(2)
    }
}

#[cfg(test)]
mod props {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The trapezoid's means as with the runtime's 64-bit `div_ceil`, over the configs a
        /// table is built from (1 ≤ v0 ≤ vmax ≤ 10^6 steps/s, any nonzero accel), at every ms.
        #[test]
        fn trapezoid_means_match_u64_division(v0 in 1u32..=1_000_000, top in 0u32..=1_000_000, accel in 1u32.., ashift in 0u32..32, i in 0usize..2048) {
            let cfg = RampConfig { v0, vmax: v0.max(top), accel: (accel >> ashift).max(1), shape: Shape::Trapezoid };
            let (v0, vmax, a) = (cfg.v0 as u64 * 1000, cfg.vmax as u64 * 1000, cfg.accel as u64);
            let start = v0 + a * i as u64;
            let want = if v0 + a * (i as u64 + 1) <= vmax {
                v0 + a * (2 * i as u64 + 1) / 2
            } else if start >= vmax {
                vmax
            } else {
                vmax - ((vmax - start) * (vmax - start)).div_ceil(2 * a)
            };
            // (`lead` ½: the mean over each millisecond.)
            prop_assert_eq!(mean_millihz(&cfg, i, 1 << 19), want);
        }
    }
}
