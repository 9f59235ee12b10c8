//! The DDA (Bresenham) interpolator: one master axis, slaves that follow in exact ratio.
//!
//! Who uses it: the step engine (per tick) and anyone who wants the reference step pattern.
//!
//! Invariant: for a move of `M` master steps and a slave of `c ≤ M` steps, the slave's
//! accumulator starts at the midpoint `⌊M/2⌋`; every master step adds `c` and the slave steps
//! whenever the sum reaches `M` (then subtracts `M`). After `k` master steps the slave has made
//! `⌊(k·c + ⌊M/2⌋)/M⌋` steps, which is within ½ step of the ideal `k·c/M`, and exactly `c`
//! after the last master step. 5000:3000:2000 repeats the pattern Y at master steps 1,3,5 and
//! Z at 2,4 of every five (the seed paper's 5:3:2).

/// One slave axis's accumulator. `count ≤ master` always.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Dda {
    acc: u32,
    count: u32,
}

impl Dda {
    /// Starts a slave of `count` steps against a master of `master` steps (`count ≤ master`).
    pub const fn new(count: u32, master: u32) -> Self {
        Dda { acc: master / 2, count }
    }

    /// Steps made after `k` master steps of `master`, recovered from the accumulator:
    /// `k·count + ⌊master/2⌋ − acc` is an exact multiple of `master`, divided here by a
    /// multiplication with the inverse of its odd part (mod 2^32), so the step interrupt's
    /// stop path needs no division instruction.
    pub fn made(&self, k: u32, master: u32) -> u32 {
        let num = k as u64 * self.count as u64 + (master / 2) as u64 - self.acc as u64;
        let t = master.trailing_zeros();
        exact_div_odd((num >> t) as u32, master >> t)
    }

    /// Advances by one master step without a branch: all ones when the slave steps, else 0
    /// (the step engine ANDs it with the pin bits).
    #[inline(always)]
    pub fn step_mask(&mut self, master: u32) -> u32 {
        let a = self.acc + self.count;
        let mask = ((a >= master) as u32).wrapping_neg();
        self.acc = a - (master & mask);
        mask
    }

    /// The accumulator (the DMA burst's slave-major lane runs it in registers).
    #[inline(always)]
    pub(crate) fn acc(&self) -> u32 {
        self.acc
    }

    /// Steps per move.
    #[inline(always)]
    pub(crate) fn count(&self) -> u32 {
        self.count
    }

    /// Sets the accumulator the lane ran (in `0..master`, as [`Self::step`] leaves it).
    #[inline(always)]
    pub(crate) fn set_acc(&mut self, acc: u32) {
        self.acc = acc;
    }

    /// Advances by one master step; true when the slave steps too.
    #[inline(always)]
    pub fn step(&mut self, master: u32) -> bool {
        // acc < master and count ≤ master, so the sum fits in u32 for master < 2^31.
        self.acc += self.count;
        if self.acc >= master {
            self.acc -= master;
            true
        } else {
            false
        }
    }
}

/// `n / d` for odd `d` when `d` divides `n`: `n · d⁻¹ mod 2^32`, the inverse by Newton's
/// iteration (each round doubles the correct low bits: 3 → 6 → 12 → 24 → 48).
fn exact_div_odd(n: u32, d: u32) -> u32 {
    let mut inv = d;
    for _ in 0..4 {
        inv = inv.wrapping_mul(2u32.wrapping_sub(d.wrapping_mul(inv)));
    }
    n.wrapping_mul(inv)
}

/// Picks the master axis: the one with the most steps, ties to the lowest index.
pub fn master_axis(counts: &[u32]) -> usize {
    // (The best count carried along, not indexed: no bounds-check panic path.)
    let (mut best, mut most) = (0, 0);
    for (i, &c) in counts.iter().enumerate() {
        if c > most {
            (best, most) = (i, c);
        }
    }
    best
}

/// Reference walker over a whole line: yields, per master step, the bit mask of axes that step.
/// Used by tests and tools; the engine runs the same [`Dda`] per tick.
#[derive(Clone, Debug)]
pub struct Line<const N: usize> {
    master: usize,
    total: u32,
    done: u32,
    dda: [Dda; N],
}

impl<const N: usize> Line<N> {
    /// A line with the given absolute step counts per axis.
    pub fn new(counts: [u32; N]) -> Self {
        let master = master_axis(&counts);
        let total = counts[master];
        let mut dda = [Dda::default(); N];
        for (d, &c) in dda.iter_mut().zip(counts.iter()) {
            *d = Dda::new(c, total);
        }
        Line { master, total, done: 0, dda }
    }

    /// Index of the master axis.
    pub fn master(&self) -> usize {
        self.master
    }
}

impl<const N: usize> Iterator for Line<N> {
    type Item = u32;

    fn next(&mut self) -> Option<u32> {
        if self.done == self.total {
            return None;
        }
        self.done += 1;
        let mut mask = 0;
        for (i, d) in self.dda.iter_mut().enumerate() {
            if d.step(self.total) {
                mask |= 1 << i;
            }
        }
        debug_assert!(mask & (1 << self.master) != 0);
        Some(mask)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_532_pattern_repeats_every_five() {
        let masks: [u32; 10] = {
            let mut l = Line::new([5000u32, 3000, 2000]);
            core::array::from_fn(|_| l.next().unwrap())
        };
        // X every step; Y at 1,3,5; Z at 2,4 (1-based) — and the same again.
        assert_eq!(masks, [0b011, 0b101, 0b011, 0b101, 0b011, 0b011, 0b101, 0b011, 0b101, 0b011]);
        let mut totals = [0u32; 3];
        for m in Line::new([5000u32, 3000, 2000]) {
            for (a, t) in totals.iter_mut().enumerate() {
                *t += (m >> a) & 1;
            }
        }
        assert_eq!(totals, [5000, 3000, 2000]);
    }

    #[test]
    fn made_matches_the_steps_counted() {
        for (c, m) in [(3000u32, 5000u32), (1, 1), (7, 7), (1, 2), (999_999, 1_000_000), (12, 4096), (5, 1 << 30)] {
            let mut d = Dda::new(c, m);
            let mut n = 0;
            for k in 1..=m.min(20_000) {
                n += d.step(m) as u32;
                assert_eq!(d.made(k, m), n, "c={c} m={m} k={k}");
            }
        }
    }

    #[test]
    fn master_ties_go_to_lowest_index() {
        assert_eq!(master_axis(&[3, 7, 7, 1]), 1);
        assert_eq!(master_axis(&[0, 0]), 0);
    }
}
