//! The DMA burst fill's fast path: runs of plain entries, entry by entry what
//! [`Stepper::tick`] gives, without its per-tick checks.
//!
//! A plain entry is a filler (a piece of a period longer than one entry, word 0) or a plain
//! step: the move is running, the control word has not changed (it cannot change during a
//! fill: the fill interrupt preempts every context that writes it), and neither the
//! deceleration trigger nor the move's last step is reached. No plain entry ends a ramp
//! millisecond (that asks for the ramp half). Within a run the period is the one the ramp half
//! last published (only the ramp half writes it, and in DMA mode it runs inside the fill,
//! between runs), so a run needs no shared load per entry. The first entry that is not plain
//! is left to [`Stepper::tick`].

use core::sync::atomic::Ordering::Relaxed;

use super::{piece, slave_bits, toggle, Phase, Stepper};
use crate::prepared::Slave;
use crate::burst::tail;

impl<const N: usize, const L: usize> Stepper<'_, N, L> {
    /// Fills the front of `words` and `periods` with plain entries; returns how many (0 when
    /// the next one needs a whole tick). Not inlined: the fill's own loop stays small.
    #[inline(never)]
    pub(crate) fn quick_entries(&mut self, words: &mut [u32], periods: &mut [u16]) -> usize {
        // The rest of a period a whole tick split, first: then the lanes may take over.
        let first = self.fillers(words, periods);
        if self.extend != 0 {
            return first;
        }
        first + self.plain(tail(words, first), tail(periods, first))
    }

    /// Fillers of the period being split, up to its end or a ramp millisecond's.
    fn fillers(&mut self, words: &mut [u32], periods: &mut [u16]) -> usize {
        let max = self.max_tick;
        let mut made = 0;
        for (w, per) in words.iter_mut().zip(periods.iter_mut()) {
            let rem = self.extend;
            let chunk = piece(rem, max);
            if rem == 0 || self.ms_left <= chunk as i32 {
                break;
            }
            *w = self.word;
            self.word = 0;
            self.extend = rem - chunk;
            self.ms_left -= chunk as i32;
            self.gap_in = if self.extend == 0 { self.whole } else { chunk };
            *per = (chunk - 1) as u16;
            made += 1;
        }
        made
    }

    /// Plain steps from a period boundary on (`extend` is 0), each gap at most two entries (from
    /// 24 kHz up; slower steps are whole ticks, their fillers plain).
    fn plain(&mut self, words: &mut [u32], periods: &mut [u16]) -> usize {
        // Steps may be plain: running, no control change.
        if self.phase != Phase::Run || self.shared.ctl.load() != self.ctl_seen {
            return 0;
        }
        let p = self.cur;
        // SAFETY: the running move's slot (see `step`): atomics and plain fields.
        let (period, at, master_on, n, total) =
            unsafe { ((*p).period.load(Relaxed), (*p).decel_at.load(Relaxed), (*p).master_on, (*p).n_slaves, (*p).total) };
        // A step is plain while the steps left after it stay above the trigger and 0.
        let room = self.left.saturating_sub(at + 1);
        let max = self.max_tick;
        if period == 0 || room == 0 || (period + 15) >> 4 > 2 * max {
            return 0;
        }
        let left = self.left;
        // Gaps that never need a second entry take the lanes without the split; one axis with
        // full pulses the lanes without slaves.
        let made = match (n == 0 && !self.dual, (period + 15) >> 4 <= max) {
            (true, true) => self.lane::<false, false>(words, periods, period, master_on, room),
            (true, false) => self.lane::<true, false>(words, periods, period, master_on, room),
            // Dual-edge toggles each word as a whole: the step-major lane (its split never splits).
            (false, true) if self.dual => self.lane::<true, true>(words, periods, period, master_on, room),
            (false, true) => self.slave_lane(words, periods, period, master_on, room),
            (false, false) => self.lane::<true, true>(words, periods, period, master_on, room),
        };
        if self.left != left {
            self.shared.mv_done.store(total - self.left, Relaxed);
        }
        made
    }

    /// Plain steps at `period`, each gap at most two entries (one unless `SPLIT`): at most
    /// `room` of them, until a ramp millisecond would end; counted off `left`. `SLAVES`: the
    /// move has slaves or runs dual-edge (without, one axis with full pulses, the loop keeps
    /// fewer values).
    #[inline(never)]
    fn lane<const SPLIT: bool, const SLAVES: bool>(&mut self, words: &mut [u32], periods: &mut [u16], period: u32, on: u32, room: u32) -> usize {
        let p = self.cur;
        let (mut frac, mut ms_left, mut word, mut level, mut gap_in) = (self.frac, self.ms_left, self.word, self.level, self.gap_in);
        let (dual, max) = (self.dual, self.max_tick);
        let mut it = words.iter_mut().zip(periods.iter_mut());
        let (mut made, mut steps) = (0usize, 0u32);
        while steps < room {
            let Some((w, per)) = it.next() else { break };
            let acc = frac + period;
            let gap = acc >> 4;
            if ms_left <= gap as i32 {
                break;
            }
            let first = if SPLIT { piece(gap, max) } else { gap };
            if SPLIT && first < gap && it.len() == 0 {
                break; // its second piece would not fit: a whole tick splits it
            }
            ms_left -= gap as i32;
            frac = acc & 15;
            let mut next = on;
            if SLAVES {
                // SAFETY: the running move's slot; plain fields and its slaves (see `step`).
                next |= unsafe { slave_bits(&mut (*p).slaves, (*p).n_slaves as usize, (*p).total) };
                if dual {
                    next = toggle(next, &mut level);
                }
            }
            *w = word;
            *per = (first - 1) as u16;
            word = next;
            made += 1;
            if SPLIT && first < gap {
                // Split as `extended` and `filler` would: the step's edge is the filler's word.
                if let Some((w, per)) = it.next() {
                    *w = word;
                    *per = (gap - first - 1) as u16;
                    word = 0;
                    made += 1;
                }
            }
            gap_in = gap;
            steps += 1;
        }
        (self.frac, self.ms_left, self.word, self.level, self.gap_in) = (frac, ms_left, word, level, gap_in);
        self.left -= steps;
        made
    }

    /// [`Self::lane`] without the split, single-edge, for a move with slaves, slave-major: the
    /// master's pass writes the periods; then the slaves, two at a time with their
    /// accumulators in registers, walk the steps and write the words (the first pair stores,
    /// the others OR in). The step made last stays the edge about to happen (`word`), as in
    /// the lane.
    #[inline(never)]
    fn slave_lane(&mut self, words: &mut [u32], periods: &mut [u16], period: u32, on: u32, room: u32) -> usize {
        let len = words.len().min(periods.len()).min(room as usize);
        let (mut frac, mut ms_left, mut gap_in) = (self.frac, self.ms_left, self.gap_in);
        let per = periods.as_mut_ptr();
        let mut made = 0;
        while made < len {
            let acc = frac + period;
            let gap = acc >> 4;
            if ms_left <= gap as i32 {
                break;
            }
            ms_left -= gap as i32;
            frac = acc & 15;
            // SAFETY: made < len ≤ periods.len().
            unsafe { *per.add(made) = (gap - 1) as u16 };
            gap_in = gap;
            made += 1;
        }
        if made == 0 {
            return 0;
        }
        (self.frac, self.ms_left, self.gap_in) = (frac, ms_left, gap_in);
        self.left -= made as u32;
        let w = words.as_mut_ptr();
        // SAFETY: 0 < made ≤ words.len(): entry 0 takes the edge that was about to happen,
        // entries 1..made the steps but the last, which becomes the edge about to happen.
        // The running move's slot: plain fields and its slaves, which only the step half
        // touches (see `step`).
        unsafe {
            *w = self.word;
            let (first, end) = (w.add(1), w.add(made));
            let p = self.cur;
            let (n, total) = ((*p).n_slaves as usize, (*p).total);
            let s = (*p).slaves.as_mut_ptr();
            let mut last = on;
            let mut none = Slave { dda: crate::interp::Dda::new(0, 0), on: 0, axis: 0 };
            let none: *mut Slave = &mut none;
            let pair = |i: usize| if i + 1 < n { s.add(i + 1) } else { none };
            walk::<true>(first, end, &mut last, on, s, pair(0), total);
            let mut i = 2;
            while i < n {
                walk::<false>(first, end, &mut last, 0, s.add(i), pair(i), total);
                i += 2;
            }
            self.word = last;
        }
        made
    }
}

/// Walks slaves `a` and `b` over the steps whose words are `first..end` and then `last`
/// (the words the steps put on the pins after `on`; `FIRST`: stores them, else ORs into
/// them). In registers each accumulator runs less `total` (so its sign is the step test).
#[inline(always)]
unsafe fn walk<const FIRST: bool>(first: *mut u32, end: *mut u32, last: &mut u32, on: u32, a: *mut Slave, b: *mut Slave, total: u32) {
    // SAFETY: the caller's slaves, distinct.
    let (a, b) = unsafe { (&mut *a, &mut *b) };
    let t = total as i32;
    let (ca, oa, cb, ob) = (a.dda.count() as i32, a.on, b.dda.count() as i32, b.on);
    let (mut da, mut db) = (a.dda.acc() as i32 - t, b.dda.acc() as i32 - t);
    // One step: the word `x` with the pair's bits.
    macro_rules! step {
        ($x:expr) => {{
            let mut x = $x;
            da += ca;
            if da >= 0 {
                da -= t;
                x |= oa;
            }
            db += cb;
            if db >= 0 {
                db -= t;
                x |= ob;
            }
            x
        }};
    }
    let mut w = first;
    while w != end {
        // SAFETY: first..end lies in the caller's words.
        unsafe { *w = step!(if FIRST { on } else { *w }) };
        w = unsafe { w.add(1) };
    }
    *last = step!(if FIRST { on } else { *last });
    a.dda.set_acc((da + t) as u32);
    b.dda.set_acc((db + t) as u32);
}

