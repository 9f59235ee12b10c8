//! The ramp table: one timer period per millisecond of acceleration and the distance walked
//! up to each entry, built once when settings change; the engine's lookups (interpolated
//! period, distance) on it.
//!
//! Who uses it: the settings build it; the engine's ramp walk reads it; the look-ahead's
//! searches (`ramp/search.rs`) map speeds and distances onto its indices.

use core::num::NonZeroU64;

use super::shape::{mean_millihz, RampConfig, Shape};
use crate::motion::rate::{period_of_millihz, Period, MAX_RATE_HZ, MIN_RATE_HZ};
use crate::num::div_rem_u64;
use crate::TIMER_HZ;

const THOUSAND: NonZeroU64 = NonZeroU64::new(1000).unwrap();

/// Entries (milliseconds) in the firmware's table.
pub const RAMP_LEN: usize = 512;
/// Fraction bits of a table index: the engine walks `walk_q / 2^20` entries per millisecond,
/// so one table (built for the fastest acceleration) serves every slower one.
pub const IDX_FRAC: u32 = 20;
/// One whole entry as a Q20 index.
pub const IDX_ONE: u32 = 1 << IDX_FRAC;
pub(super) const IDX_MASK: u32 = IDX_ONE - 1;
/// One step in the table's distance sums.
pub const SUM_ONE: u32 = 256;

/// Why a table cannot be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RampError {
    /// Acceleration of zero.
    ZeroAccel,
    /// `vmax < v0`.
    VmaxBelowV0,
    /// A rate outside [`MIN_RATE_HZ`]..=[`MAX_RATE_HZ`].
    RateOutOfRange,
    /// The ramp needs more milliseconds than the table has; `reachable_vmax` fits.
    TooLong { reachable_vmax: u32 },
}

/// A ramp table of up to `L` milliseconds.
pub struct RampTable<const L: usize = RAMP_LEN> {
    pub(super) periods: [Period; L],
    /// `sums[i]`: steps made walking entries `0..i` at one entry per ms, in 1/256 step
    /// ([`SUM_ONE`]): the distance scale of the look-ahead and of the engine's decel trigger.
    pub(super) sums: [u32; L],
    pub(super) len: u16,
    cfg: RampConfig,
}

impl<const L: usize> Default for RampTable<L> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const L: usize> RampTable<L> {
    /// An empty table (no entries: every move cruises at its own rate).
    pub const fn new() -> Self {
        RampTable {
            periods: [Period::ZERO; L],
            sums: [0; L],
            len: 0,
            cfg: RampConfig { v0: 0, vmax: 0, accel: 0, shape: Shape::Trapezoid },
        }
    }

    /// Milliseconds the ramp from `v0` to `vmax` takes with this shape (for a config that
    /// [`Self::build`] accepts: `accel > 0`, `v0 ≤ vmax ≤ MAX_RATE_HZ`).
    pub fn ramp_ms(cfg: &RampConfig) -> u64 {
        // 32-bit integers (`dv` · 1000 ≤ 10^9): the ceiling of the exact quotient, no float.
        let dv = cfg.vmax.saturating_sub(cfg.v0).min(MAX_RATE_HZ);
        (dv * 1000).div_ceil(cfg.accel.max(1)) as u64
    }

    /// Builds the table in place (no 4 KiB copy on the stack). On error the table is empty.
    /// Entry `i` is the mean rate of millisecond `i` (see [`Self::build_led`]).
    pub fn build(&mut self, cfg: RampConfig) -> Result<(), RampError> {
        self.build_led(cfg, IDX_ONE / 2)
    }

    /// Builds the table with entry `i` at the ideal profile's rate `i + lead` ms into the ramp
    /// (`lead`: Q20 fraction of a ms, at most ½, which is [`Self::build`]'s mean of ms `i`).
    /// Entry 0, where every move starts from rest, is `v0` plus `lead` ms of the table's
    /// acceleration: a move that walks at least `lead` of an entry per ms jumps no higher
    /// above `v0` than one millisecond of its own acceleration (the settings pass the slowest
    /// move's walk rate).
    pub fn build_led(&mut self, cfg: RampConfig, lead: u32) -> Result<(), RampError> {
        self.len = 0;
        if cfg.accel == 0 {
            return Err(RampError::ZeroAccel);
        }
        if cfg.v0 < MIN_RATE_HZ || cfg.vmax > MAX_RATE_HZ {
            return Err(RampError::RateOutOfRange);
        }
        if cfg.vmax < cfg.v0 {
            return Err(RampError::VmaxBelowV0);
        }
        // (A lead below ½ reaches `vmax` up to half a ms later. Both shapes: the S-curve's
        // table is the trapezoid's.)
        let lead = lead.min(IDX_ONE / 2);
        let n = if lead < IDX_ONE / 2 {
            let dv = cfg.vmax.saturating_sub(cfg.v0).min(MAX_RATE_HZ) as u64;
            let a = cfg.accel as u64;
            // ⌈x / (a·2^IDX_FRAC)⌉ by the shift-and-subtract division (no runtime u64 division).
            let den = NonZeroU64::new(a << IDX_FRAC).unwrap_or(NonZeroU64::MIN);
            let (q, r) = div_rem_u64(((dv * 1000) << IDX_FRAC) + a * (IDX_ONE / 2 - lead) as u64, den);
            q + (r != 0) as u64
        } else {
            Self::ramp_ms(&cfg)
        }
        .max(1);
        if n > L as u64 {
            // 64-bit integers: the same whole part as the exact quotient.
            let reachable = cfg.v0 as u64 + div_rem_u64(cfg.accel as u64 * L as u64, THOUSAND).0;
            return Err(RampError::TooLong { reachable_vmax: reachable.saturating_sub(1) as u32 });
        }
        let n = n as usize;
        for (i, p) in self.periods[..n].iter_mut().enumerate() {
            *p = period_of_millihz(mean_millihz(&cfg, i, lead));
        }
        // Rates must never fall along the table (rounding at the top could otherwise wobble).
        for i in 1..n {
            if self.periods[i] > self.periods[i - 1] {
                self.periods[i] = self.periods[i - 1];
            }
        }
        // The last millisecond's mean is below `vmax` when the ramp ends inside it: one more
        // entry at `vmax` itself, so every cruise up to `vmax` has an index to walk to.
        let top = period_of_millihz(cfg.vmax as u64 * 1000);
        let mut n = n;
        if n < L && self.periods[n - 1] > top {
            self.periods[n] = top;
            n += 1;
        }
        // Distance walked: the rate is interpolated between entries, so integrate each
        // entry-to-entry stretch as a trapezoid (the last entry counts flat).
        let per_ms = |p: Period| (TIMER_HZ / 1000 * 16 * SUM_ONE) / p.to_bits().max(1);
        let mut sum = 0u32;
        for i in 0..n {
            self.sums[i] = sum;
            let a = per_ms(self.periods[i]);
            let b = if i + 1 < n { per_ms(self.periods[i + 1]) } else { a };
            // (72 MHz · 16 · 256 / 1000 fits in 32 bits: no 64-bit division in the firmware.)
            sum = sum.saturating_add((a + b) / 2);
        }
        self.len = n as u16;
        self.cfg = cfg;
        Ok(())
    }

    /// Highest index (Q20) the table can be walked to: its last entry.
    #[inline(always)]
    pub fn top_q(&self) -> u32 {
        (self.len.max(1) as u32 - 1) << IDX_FRAC
    }

    /// Period at a fractional index (Q20), interpolated between entries; `idx_q ≤ top_q()`.
    /// Integer only (the engine's ramp half calls it a few times per ms; never the step
    /// interrupt). The *rate* is interpolated linearly (as the distance sums assume), so a
    /// walk at a constant number of entries per ms changes the rate by the same amount every
    /// ms: a period interpolated linearly would be slow early in an entry and steep late in
    /// it, up to the entries' rate ratio (3× at the bottom of a steep table). Period
    /// `p1 + (1 − f)·Δ · p1 / (p1 + f·Δ)` (Δ = p0 − p1), the ratio from one 32-bit
    /// division (a few cycles: the 64-bit shift-subtract one cost the ramp half enough to make
    /// DMA fills late), rounded up (never faster than the line, to a 1/16-tick step).
    #[inline(never)]
    pub fn period_at(&self, idx_q: u32) -> Period {
        let i = (idx_q >> IDX_FRAC) as usize;
        let f = idx_q & IDX_MASK;
        let p = self.periods[i].to_bits();
        if f == 0 || i + 1 >= self.len as usize {
            return Period::from_bits(p);
        }
        let p1 = self.periods[i + 1].to_bits();
        let dlt = p - p1;
        let den = p1 + ((dlt as u64 * f as u64) >> IDX_FRAC) as u32;
        let x = ((dlt as u64 * (IDX_ONE - f) as u64 + IDX_MASK as u64) >> IDX_FRAC) as u32;
        // p1 / den (≤ 1) in Q(a + b) with 15 bits or more: p1 shifted to the top of 32 bits,
        // den down to 16 bits; the floors only make it larger (slower).
        let a = p1.leading_zeros().min(31);
        let b = (32 - den.leading_zeros()).saturating_sub(16);
        let ratio = (p1 << a) / (den >> b).max(1) + 1;
        let extra = ((x as u64 * ratio as u64) >> (a + b)).min(dlt as u64) as u32;
        Period::from_bits(p1 + extra + 1).min(Period::from_bits(p))
    }

    /// Steps per ms at entry `idx_q >> 20` (1/256 step): the slope of [`Self::sum_at`].
    #[inline(always)]
    pub fn per_ms_at(&self, idx_q: u32) -> u32 {
        let i = (idx_q >> IDX_FRAC) as usize;
        if i + 1 < self.len as usize {
            self.sums[i + 1] - self.sums[i]
        } else if i > 0 && i < self.len as usize {
            self.sums[i] - self.sums[i - 1]
        } else {
            0
        }
    }

    /// Distance walked from index 0 to `idx_q` at one entry per ms, in 1/256 step.
    #[inline(always)]
    pub fn sum_at(&self, idx_q: u32) -> u32 {
        let i = (idx_q >> IDX_FRAC) as usize;
        let f = idx_q & IDX_MASK;
        let s = self.sums[i];
        if f == 0 || i + 1 >= self.len as usize {
            return s;
        }
        let d = self.sums[i + 1] - s;
        s + ((d as u64 * f as u64) >> IDX_FRAC) as u32
    }


    /// Number of entries (milliseconds of ramp).
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// True when the table has no entries.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// What the table was built from.
    pub fn config(&self) -> RampConfig {
        self.cfg
    }

    /// Period of entry `i` (the caller keeps `i < len`).
    #[inline(always)]
    pub fn period(&self, i: usize) -> Period {
        self.periods[i]
    }

    /// The entries in use.
    pub fn periods(&self) -> &[Period] {
        &self.periods[..self.len as usize]
    }


    /// Bytes of RAM the table takes.
    pub const fn size_bytes() -> usize {
        core::mem::size_of::<Self>()
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A fixed xorshift stream: `next(n)` is in `0..n`.
    pub(in crate::motion::ramp) fn xorshift() -> impl FnMut(u32) -> u32 {
        let mut rng = crate::num::xorshift(0x2545_F491_4F6C_DD1D);
        move |n| (rng() % n as u64) as u32
    }

    /// The rate is linear between entries (to the quotient's rounding, a 1/16-tick period step,
    /// and the fraction's, relative to the faster entry's period), never above the
    /// line, and entry 0 is `v0` plus `lead` ms of the acceleration.
    #[test]
    fn rate_is_interpolated_linearly_and_led() {
        let mut next = xorshift();
        let mut t = RampTable::<RAMP_LEN>::new();
        for _ in 0..200 {
            let v0 = MIN_RATE_HZ + next(3_000);
            let accel = 1_000 + next(50_000_000);
            let lead = next(IDX_ONE / 2 + 1);
            let cfg = RampConfig { v0, vmax: v0 + next(100_000), accel, shape: Shape::Trapezoid };
            if t.build_led(cfg, lead).is_err() {
                continue;
            }
            let hz = |p: Period| TIMER_HZ as f64 * 16.0 / p.to_bits() as f64;
            let e0 = v0 as f64 + accel as f64 * lead as f64 / IDX_ONE as f64 / 1000.0;
            assert!((hz(t.period(0)) - e0.min(cfg.vmax as f64)).abs() <= 1e-3 * e0 + 0.01, "{cfg:?} {lead}: {}", hz(t.period(0)));
            for _ in 0..50 {
                let q = next(t.top_q() + 1);
                let (i, f) = ((q >> IDX_FRAC) as usize, (q & IDX_MASK) as f64 / IDX_ONE as f64);
                let (r0, r1) = (hz(t.period(i)), hz(t.period((i + 1).min(t.len() - 1))));
                let line = r0 + f * (r1 - r0);
                let got = hz(t.period_at(q));
                let p1b = t.period((i + 1).min(t.len() - 1)).to_bits() as f64;
                let step = got * got / (TIMER_HZ as f64 * 16.0);
                assert!(got <= line * (1.0 + 1e-9) && got >= line - line * (2.0 / p1b + 4e-5) - 2.0 * step - 1e-6, "{cfg:?} q {q}: {got} vs {line}");
            }
        }
    }

    #[test]
    fn ramp_ms_is_the_ceiling_of_the_exact_quotient() {
        let mut next = xorshift();
        for i in 0..100_000 {
            let v0 = 1 + next(MAX_RATE_HZ);
            let vmax = v0 + next(MAX_RATE_HZ - v0 + 1);
            let accel = 1 + if i % 2 == 0 { next(u32::MAX) } else { next(10_000) };
            let cfg = RampConfig { v0, vmax, accel, shape: Shape::Trapezoid };
            let f64_ceil = libm::ceil((vmax - v0) as f64 * 1000.0 / accel as f64) as u64;
            assert_eq!(RampTable::<RAMP_LEN>::ramp_ms(&cfg), f64_ceil, "{cfg:?}");
        }
    }
}
