//! Ramp tables: the master timer period for every millisecond of an acceleration.
//!
//! Who uses it: the firmware builds one table when settings change (outside any interrupt);
//! the step engine walks it at a move's own fraction of an entry per millisecond (so one table
//! built for the fastest acceleration serves every slower move), interpolating between
//! entries; the look-ahead maps path speeds and distances onto its indices.
//!
//! Invariant: entry `i` holds the period (timer ticks, 1/16 resolution, [`Period`]) of the mean
//! rate of the ideal profile during millisecond `i`: `v0 + a·(i+½) ms` for the trapezoid,
//! clamped at `vmax` in its last entry; the S-curve uses the same mean of a normalized logistic.
//! Entries strictly never rise in rate past `vmax` and never fall in rate along the table. The
//! engine decelerates by walking the same entries down, so one table serves every move that
//! shares the acceleration, and a move's step count never depends on the table. Beside each
//! period the table keeps the distance walked up to it (`sums`, 1/256 step), which is what
//! turns "decelerate from index a to b" into steps without a division. With
//! [`RAMP_LEN`] = 512 entries of 8 bytes the table is 4 KiB of RAM and covers 0.512 s of
//! acceleration; a longer one is refused with [`RampError::TooLong`] naming the highest `vmax`
//! that fits (the settings code then builds a steeper table instead, which slower moves walk at
//! a smaller fraction: see `Settings::build_profile`).

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, Ordering};

use fixed::types::U28F4;

use crate::num::{f32_of_u64, i32_of, u32_of, u64_of};
use crate::motion::timing::Timing;
use crate::TIMER_HZ;

/// A timer period in ticks with four fractional bits: the engine dithers the fraction so the
/// average rate is exact to 1/16 tick.
pub type Period = U28F4;

/// Lowest rate a table or move may use (steps/s): 1 step/s is 72 M ticks, well inside [`Period`].
pub const MIN_RATE_HZ: u32 = 1;
/// Highest rate a table or move may describe (steps/s); what the step interrupt sustains is
/// lower and is enforced by the engine's timing ([`crate::motion::timing::Timing`]).
pub const MAX_RATE_HZ: u32 = 1_000_000;
/// Entries (milliseconds) in the firmware's table.
pub const RAMP_LEN: usize = 512;
/// Fraction bits of a table index: the engine walks `walk_q / 2^20` entries per millisecond,
/// so one table (built for the fastest acceleration) serves every slower one.
pub const IDX_FRAC: u32 = 20;
/// One whole entry as a Q20 index.
pub const IDX_ONE: u32 = 1 << IDX_FRAC;
const IDX_MASK: u32 = IDX_ONE - 1;
/// One step in the table's distance sums.
pub const SUM_ONE: u32 = 256;

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

/// Logistic steepness: the S-curve spans the logistic on [-S_CURVE_SPAN, S_CURVE_SPAN].
const S_CURVE_SPAN: f32 = 4.0;

/// Period of a rate given in milli-steps per second (rounded to the nearest 1/16 tick).
/// (64-bit integers, exact: `f32` has too few bits for the tick count of a slow rate.)
pub fn period_of_millihz(milli_hz: u64) -> Period {
    let m = milli_hz.max(1);
    let q4 = (TIMER_HZ as u64 * 32_000 + m) / (2 * m);
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

/// A ramp table of up to `L` milliseconds.
pub struct RampTable<const L: usize = RAMP_LEN> {
    periods: [Period; L],
    /// `sums[i]`: steps made walking entries `0..i` at one entry per ms, in 1/256 step
    /// ([`SUM_ONE`]): the distance scale of the look-ahead and of the engine's decel trigger.
    sums: [u32; L],
    len: u16,
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
        let ms = (dv * 1000).div_ceil(cfg.accel.max(1)) as u64;
        match cfg.shape {
            Shape::Trapezoid => ms,
            // The logistic's steepest slope is span/2 / norm of the mean slope.
            Shape::SCurve => u64_of(f32_of_u64(ms) * s_curve_stretch()) + 1,
        }
    }

    /// Builds the table in place (no 4 KiB copy on the stack). On error the table is empty.
    pub fn build(&mut self, cfg: RampConfig) -> Result<(), RampError> {
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
        let n = Self::ramp_ms(&cfg).max(1);
        if n > L as u64 {
            let reachable = match cfg.shape {
                // 64-bit integers: the same whole part as the exact quotient.
                Shape::Trapezoid => cfg.v0 as u64 + cfg.accel as u64 * L as u64 / 1000,
                Shape::SCurve => {
                    cfg.v0 as u64 + u64_of(cfg.accel as f32 * L as f32 / 1000.0 / s_curve_stretch())
                }
            };
            return Err(RampError::TooLong { reachable_vmax: reachable.saturating_sub(1) as u32 });
        }
        let n = n as usize;
        for (i, p) in self.periods[..n].iter_mut().enumerate() {
            *p = period_of_millihz(mean_millihz(&cfg, i, n));
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
    /// Integer only (the engine calls it once per ms).
    #[inline(always)]
    pub fn period_at(&self, idx_q: u32) -> Period {
        let i = (idx_q >> IDX_FRAC) as usize;
        let f = idx_q & IDX_MASK;
        let p = self.periods[i].to_bits();
        if f == 0 || i + 1 >= self.len as usize {
            return Period::from_bits(p);
        }
        let d = p - self.periods[i + 1].to_bits();
        Period::from_bits(p - ((d as u64 * f as u64) >> IDX_FRAC) as u32)
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
        let f = if a > b { (a - p) / (a - b) } else { 0.0 };
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

    /// Bytes of RAM the table takes.
    pub const fn size_bytes() -> usize {
        core::mem::size_of::<Self>()
    }
}

/// How much longer the S-curve takes than a trapezoid with the same peak acceleration.
fn s_curve_stretch() -> f32 {
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

/// Mean rate in ms `i` of an `n`-entry ramp, in milli-steps/s.
fn mean_millihz(cfg: &RampConfig, i: usize, n: usize) -> u64 {
    let v0 = cfg.v0 as u64 * 1000;
    let vmax = cfg.vmax as u64 * 1000;
    match cfg.shape {
        Shape::Trapezoid => {
            // v(t) = v0 + a·t up to vmax; the mean over [i, i+1) ms of the clamped line.
            let a = cfg.accel as u64; // milli-steps/s per ms
            let end = v0 + a * (i as u64 + 1);
            if end <= vmax {
                v0 + a * (2 * i as u64 + 1) / 2
            } else {
                let start = v0 + a * i as u64;
                if start >= vmax {
                    return vmax;
                }
                // Ramp part of length f = (vmax-start)/a ms, then vmax for 1-f: the mean is
                // vmax - d²/(2a) with d = vmax - start < a, whose floor is taken in integers
                // (d² < 2^64 as d < a ≤ u32::MAX; f32 has too few bits for milli-steps/s).
                let d = vmax - start;
                vmax - (d * d).div_ceil(2 * a)
            }
        }
        Shape::SCurve => {
            // Midpoint of the millisecond on the logistic stretched over n ms (Simpson-free:
            // the curve is smooth enough that the midpoint is within 0.1 % of the mean here).
            let u = ((i as f32 + 0.5) / n as f32).min(1.0);
            let v = f32_of_u64(v0) + f32_of_u64(vmax - v0) * s_curve(u);
            // max/min, not clamp: its panic message would link integer formatting.
            u64_of(v).max(v0.max(1)).min(vmax.max(1))
        }
    }
}

/// What the engine reads from settings: the ramp table and the step timing.
pub struct Profile<const L: usize = RAMP_LEN> {
    pub ramp: RampTable<L>,
    pub timing: Timing,
    /// Table rate per mm/s of path speed (steps/mm of the finest axis): a move whose master
    /// makes `share` steps per mm of path runs at `share / per_mm` of the table's rate. Zero
    /// (not set) means table rates are master rates.
    pub per_mm: f32,
}

/// The profile shared between the step interrupt (reader) and the settings code (writer)
/// without locks: the writer asks, the engine parks between moves, the writer rebuilds.
///
/// Protocol: [`RampSlot::try_write`] raises `writer`; the engine, which reads the table only
/// while a move runs, sees the flag when it would load the next move, clears `reading` and
/// loads nothing; once it is not reading the writer gets the table, and dropping the guard
/// lowers `writer`. (Both flags start false, so the slot lives in .bss, not 4 KiB of .data.)
pub struct RampSlot<const L: usize = RAMP_LEN> {
    table: UnsafeCell<Profile<L>>,
    writer: AtomicBool,
    reading: AtomicBool,
}

// SAFETY: the table is read only by the engine while `writer` is low (checked before each
// move starts) and written only through a guard that exists only while the engine is parked.
unsafe impl<const L: usize> Sync for RampSlot<L> {}

impl<const L: usize> Default for RampSlot<L> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const L: usize> RampSlot<L> {
    /// An empty slot; the engine starts parked, so the first write needs no handshake.
    pub const fn new() -> Self {
        RampSlot {
            // Zero timing keeps the slot in .bss; the engine reads it as `Timing::DEFAULT`.
            table: UnsafeCell::new(Profile { ramp: RampTable::new(), timing: Timing::UNSET, per_mm: 0.0 }),
            writer: AtomicBool::new(false),
            reading: AtomicBool::new(false),
        }
    }

    /// Writer side: the table, if the engine is parked; otherwise asks it to park and returns
    /// `None` (try again after the running move ends).
    pub fn try_write(&self) -> Option<RampWriteGuard<'_, L>> {
        self.writer.store(true, Ordering::SeqCst);
        if !self.reading.load(Ordering::SeqCst) {
            Some(RampWriteGuard { slot: self })
        } else {
            None
        }
    }

    /// Engine side: may a move start now? Parks (and says no) while a writer waits.
    #[inline]
    pub(crate) fn enter(&self) -> bool {
        if self.writer.load(Ordering::SeqCst) {
            self.reading.store(false, Ordering::SeqCst);
            false
        } else {
            self.reading.store(true, Ordering::SeqCst);
            true
        }
    }

    /// Producer side (the feeder that prepares moves): the table, read in the same context
    /// that holds the writer, so never while a write guard lives.
    pub(crate) fn producer_view(&self) -> &Profile<L> {
        // SAFETY: the feeder and the settings writer run in one context (the controller), so
        // no guard exists while this reference is used; the engine only reads.
        unsafe { &*self.table.get() }
    }

    /// Engine side: the table, valid from a successful [`Self::enter`] to the move's end.
    #[inline(always)]
    pub(crate) fn profile(&self) -> &Profile<L> {
        // SAFETY: called only by the engine between `enter() == true` and the next `enter`,
        // during which no write guard can exist (see the type's protocol).
        unsafe { &*self.table.get() }
    }
}

/// Exclusive access to the table while the engine is parked.
pub struct RampWriteGuard<'a, const L: usize> {
    slot: &'a RampSlot<L>,
}

impl<const L: usize> core::ops::Deref for RampWriteGuard<'_, L> {
    type Target = Profile<L>;
    fn deref(&self) -> &Profile<L> {
        // SAFETY: the guard exists only while the engine is parked (no reader).
        unsafe { &*self.slot.table.get() }
    }
}

impl<const L: usize> core::ops::DerefMut for RampWriteGuard<'_, L> {
    fn deref_mut(&mut self) -> &mut Profile<L> {
        // SAFETY: as above, and `&mut self` makes this the only writer.
        unsafe { &mut *self.slot.table.get() }
    }
}

impl<const L: usize> Drop for RampWriteGuard<'_, L> {
    fn drop(&mut self) {
        self.slot.writer.store(false, Ordering::SeqCst);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let f = if a > b { (a - p) / (a - b) } else { 0.0 };
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

    /// A fixed xorshift stream: `next(n)` is in `0..n`.
    fn xorshift() -> impl FnMut(u32) -> u32 {
        let mut r = 0x2545_F491_4F6C_DD1Du64;
        move |n| {
            r ^= r << 13;
            r ^= r >> 7;
            r ^= r << 17;
            (r % n as u64) as u32
        }
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
