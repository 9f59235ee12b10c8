//! Step-path self-measurement: the step interrupt times its own body with the DWT cycle
//! counter and `$I` reports min / mean / max cycles per entry and the load, so a user with a
//! real Blue Pill gets the silicon figure to hold against the virtual bench's modeled one.
//!
//! Three writers, each the only writer of its fields, and no locks:
//! - the step interrupt ([`StepTime::record`], highest priority): entry count and busy cycles
//!   (both wrapping), and the min / max since the last tick;
//! - the 1 ms tick ([`StepTime::tick_ms`]): takes the interrupt's min / max (atomic swaps) and
//!   folds everything into 64-bit totals, the window's min / max and the busiest millisecond,
//!   under a sequence count (odd while it writes);
//! - the report ([`StepTime::take`], from `idle`): takes the window (atomic swaps, put back and
//!   retried if a tick ran meanwhile) and keeps its previous totals.
//!
//! So a report covers whole milliseconds: every entry a tick has seen, in exactly one report
//! (an entry that lands during the tick's few loads may set the min / max of the next one).
//!
//! Cost on the step path: two CYCCNT loads and a subtraction, then two load-add-stores and two
//! compare-and-store (about 12 instructions, ~20 cycles; `bench/README.md` gives the modeled
//! figure). The body measured runs from the first CYCCNT read to the second: exception entry
//! and return (12 + 10 cycles + flash refills on a Cortex-M3) and the few instructions before
//! the first read and after the second are outside it.

use core::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// The firmware's step-path timing (the step interrupt records, `$I` reports).
pub static STEP_TIME: StepTime = StepTime::new();

/// Cycle statistics of the step interrupt's body.
pub struct StepTime {
    count: AtomicU32,
    busy: AtomicU32,
    min: AtomicU32,
    max: AtomicU32,
    seq: AtomicU32,
    ms: AtomicU32,
    seen_count: AtomicU32,
    seen_busy: AtomicU32,
    total_count: [AtomicU32; 2],
    total_busy: [AtomicU32; 2],
    peak_ms: AtomicU32,
    win_min: AtomicU32,
    win_max: AtomicU32,
    read_ms: AtomicU32,
    read_count: [AtomicU32; 2],
    read_busy: [AtomicU32; 2],
    /// DMA burst mode: fills DMA may have read an entry of before they wrote it (the fill
    /// interrupt writes, wrapping), and the count the last report saw.
    late: AtomicU32,
    read_late: AtomicU32,
}

/// What one report covers: the step interrupt since the previous report.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepTimeReport {
    pub entries: u64,
    pub min: u32,
    pub mean: f32,
    pub max: u32,
    /// Busy cycles / elapsed cycles over the window.
    pub load: f32,
    /// Busiest whole millisecond of the window.
    pub peak_load: f32,
    /// DMA burst mode: late fills since the previous report (see [`StepTime::note_late`]).
    pub late: u32,
}

const CYCLES_PER_MS: u32 = crate::TIMER_HZ / 1000;

impl Default for StepTime {
    fn default() -> Self {
        Self::new()
    }
}

impl StepTime {
    pub const fn new() -> Self {
        const Z: AtomicU32 = AtomicU32::new(0);
        Self {
            count: Z,
            busy: Z,
            min: AtomicU32::new(u32::MAX),
            max: Z,
            seq: Z,
            ms: Z,
            seen_count: Z,
            seen_busy: Z,
            total_count: [Z, Z],
            total_busy: [Z, Z],
            peak_ms: Z,
            win_min: AtomicU32::new(u32::MAX),
            win_max: Z,
            read_ms: Z,
            read_count: [Z, Z],
            read_busy: [Z, Z],
            late: Z,
            read_late: Z,
        }
    }

    /// DMA burst mode: DMA may have read an entry before the fill wrote it (the fill interrupt
    /// only; `ddastep::motion::burst::Burst::fill_watched`): entries may have played stale.
    pub fn note_late(&self) {
        self.late.store(self.late.load(Relaxed).wrapping_add(1), Relaxed);
    }

    /// One step-interrupt body took `cycles` (step interrupt only: plain loads and stores).
    #[inline(always)]
    pub fn record(&self, cycles: u32) {
        self.count.store(self.count.load(Relaxed).wrapping_add(1), Relaxed);
        self.busy.store(self.busy.load(Relaxed).wrapping_add(cycles), Relaxed);
        if cycles > self.max.load(Relaxed) {
            self.max.store(cycles, Relaxed);
        }
        if cycles < self.min.load(Relaxed) {
            self.min.store(cycles, Relaxed);
        }
    }

    /// Step interrupt entries so far (wrapping): the watchdog's sign of engine life.
    pub fn entries(&self) -> u32 {
        self.count.load(Relaxed)
    }

    /// Every millisecond (one context only): extend the counters to 64 bits, fold the min /
    /// max into the window, track the busiest millisecond.
    pub fn tick_ms(&self) {
        let count = self.count.load(Relaxed);
        let busy = self.busy.load(Relaxed);
        let min = self.min.swap(u32::MAX, Relaxed);
        let max = self.max.swap(0, Relaxed);
        let d_count = count.wrapping_sub(self.seen_count.load(Relaxed));
        let d_busy = busy.wrapping_sub(self.seen_busy.load(Relaxed));
        self.seen_count.store(count, Relaxed);
        self.seen_busy.store(busy, Relaxed);
        self.seq.store(self.seq.load(Relaxed).wrapping_add(1), Relaxed);
        fence();
        add64(&self.total_count, d_count);
        add64(&self.total_busy, d_busy);
        self.ms.store(self.ms.load(Relaxed).wrapping_add(1), Relaxed);
        self.win_min.store(self.win_min.load(Relaxed).min(min), Relaxed);
        self.win_max.store(self.win_max.load(Relaxed).max(max), Relaxed);
        self.peak_ms.store(self.peak_ms.load(Relaxed).max(d_busy), Relaxed);
        fence();
        self.seq.store(self.seq.load(Relaxed).wrapping_add(1), Relaxed);
    }

    /// The figures since the previous call (one caller only), `None` if no entry was timed.
    pub fn take(&self) -> Option<StepTimeReport> {
        let (ms, count, busy, min, max, peak) = loop {
            let s = self.seq.load(Relaxed);
            if s % 2 == 1 {
                continue;
            }
            fence();
            let count = load64(&self.total_count);
            if count == load64(&self.read_count) {
                return None;
            }
            let (min, max, peak) = (self.win_min.swap(u32::MAX, Relaxed), self.win_max.swap(0, Relaxed), self.peak_ms.swap(0, Relaxed));
            let v = (self.ms.load(Relaxed), count, load64(&self.total_busy), min, max, peak);
            fence();
            if self.seq.load(Relaxed) == s {
                break v;
            }
            // A tick ran meanwhile: give the window back and read it again.
            self.win_min.fetch_min(min, Relaxed);
            self.win_max.fetch_max(max, Relaxed);
            self.peak_ms.fetch_max(peak, Relaxed);
        };
        let d_ms = ms.wrapping_sub(self.read_ms.swap(ms, Relaxed));
        let d_count = count - swap64(&self.read_count, count);
        let d_busy = busy - swap64(&self.read_busy, busy);
        // f32 like the rest of the firmware's float math.
        let elapsed = crate::num::f32_of_u64(d_ms.max(1) as u64 * CYCLES_PER_MS as u64);
        Some(StepTimeReport {
            entries: d_count,
            min,
            mean: (crate::num::f32_of_u64(d_busy) / crate::num::f32_of_u64(d_count)),
            max,
            load: (crate::num::f32_of_u64(d_busy) / elapsed),
            peak_load: (peak as f32 / CYCLES_PER_MS as f32),
            late: {
                let late = self.late.load(Relaxed);
                late.wrapping_sub(self.read_late.swap(late, Relaxed))
            },
        })
    }
}

// keep the compiler from moving loads and stores across a sequence-count update
fn fence() {
    core::sync::atomic::compiler_fence(core::sync::atomic::Ordering::SeqCst);
}

// add `d` to the 64-bit number held as [low, high] (single writer)
fn add64(v: &[AtomicU32; 2], d: u32) {
    let (lo, carry) = v[0].load(Relaxed).overflowing_add(d);
    v[0].store(lo, Relaxed);
    if carry {
        v[1].store(v[1].load(Relaxed).wrapping_add(1), Relaxed);
    }
}

fn load64(v: &[AtomicU32; 2]) -> u64 {
    (v[1].load(Relaxed) as u64) << 32 | v[0].load(Relaxed) as u64
}

// store `x` (single writer), return the previous value
fn swap64(v: &[AtomicU32; 2], x: u64) -> u64 {
    let old = load64(v);
    v[0].store(x as u32, Relaxed);
    v[1].store((x >> 32) as u32, Relaxed);
    old
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_window_reports_its_entries_and_restarts() {
        let t = StepTime::new();
        assert_eq!(t.take(), None);
        for c in [200, 250, 300] {
            t.record(c);
        }
        t.tick_ms();
        t.record(400);
        t.tick_ms();
        let r = t.take().unwrap();
        assert_eq!((r.entries, r.min, r.max), (4, 200, 400));
        assert_eq!(r.mean, 287.5);
        assert_eq!(r.load, 1150.0 / 144_000.0);
        assert_eq!(r.peak_load, 750.0 / 72_000.0);
        // The next window starts empty; entries not yet seen by a tick wait for it.
        t.record(100);
        assert_eq!(t.take(), None);
        t.record(120);
        t.tick_ms();
        let r = t.take().unwrap();
        assert_eq!((r.entries, r.min, r.max, r.mean), (2, 100, 120, 110.0));
        assert_eq!(t.take(), None);
    }

    #[test]
    fn counters_wrap_and_totals_extend() {
        let t = StepTime::new();
        t.busy.store(u32::MAX - 10, Relaxed);
        t.seen_busy.store(u32::MAX - 10, Relaxed);
        t.record(100);
        t.tick_ms();
        let r = t.take().unwrap();
        assert_eq!((r.entries, r.mean), (1, 100.0));
    }
}
