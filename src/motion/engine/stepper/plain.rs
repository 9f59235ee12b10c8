//! The DMA burst fill's fast path: runs of plain entries, entry by entry what
//! [`Stepper::tick`] gives, without its per-tick checks.
//!
//! A plain entry is a filler (a piece of a period longer than one entry, word 0) or a plain
//! step: the move is running, the control word has not changed (it cannot change during a
//! fill: the fill interrupt preempts every context that writes it), and neither the
//! deceleration trigger nor the move's last step is reached. No plain entry ends a ramp
//! millisecond (that asks for the ramp half), but the last of a slave-major run may: the fill
//! then runs the ramp half before the next entry. Within a run the period is the one the ramp half
//! last published (only the ramp half writes it, and in DMA mode it runs inside the fill,
//! between runs), so a run needs no shared load per entry. The first entry that is not plain
//! is left to [`Stepper::tick`].
//!
//! One axis runs entry by entry ([`Stepper::lane`]; in dual-edge mode its words alternate
//! between setting and resetting the pin). Moves with slaves run slave-major
//! ([`Stepper::slave_lane`]): the
//! master's pass writes the periods and the master's bit, then each group of slaves walks the
//! same steps with its accumulators in registers and ORs its bits in. The slaves' [`Slave`]
//! state is read at a walk's start and written back at its end, so between fills it is
//! exactly what [`Stepper::tick`] would have left.

use core::sync::atomic::Ordering::Relaxed;

use super::extend::piece;
use super::state::{bump, Phase, Stepper};
use super::word::{slave_bits, toggle};
use crate::TICKS_PER_MS;
use crate::motion::prepared::Slave;

impl<const N: usize, const L: usize> Stepper<'_, N, L> {
    /// Fills the front of `words` and `periods` with plain entries; returns how many (0 when
    /// the next one needs a whole tick). Not inlined: the fill's own loop stays small.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.quick_entries")]
    pub(crate) fn quick_entries(&mut self, words: &mut [u32], periods: &mut [u16]) -> usize {
        if self.extend == 0 {
            return self.plain(words, periods);
        }
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
    #[cfg_attr(target_os = "none", link_section = ".fill.plain")]
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
        // Gaps that never need a second entry take the lanes without the split; one axis the
        // lanes without slaves (in dual-edge mode flipping its words).
        let made = match (n == 0, self.dual, (period + 15) >> 4 <= max) {
            (true, false, true) => self.lane::<false, false, false>(words, periods, period, master_on, room),
            (true, false, false) => self.lane::<true, false, false>(words, periods, period, master_on, room),
            // One axis in dual-edge mode: entry by entry (each word whole as it is written).
            (true, true, true) => self.lane::<false, false, true>(words, periods, period, master_on, room),
            (false, _, true) => {
                // (Its words are whole only once the lane ends: the slaves' passes come after
                // the master's.)
                self.slave_major = true;
                self.slave_lane(words, periods, period, master_on, room)
            }
            _ => self.lane::<true, true, false>(words, periods, period, master_on, room),
        };
        if self.left != left {
            self.shared.mv_done.store(total - self.left, Relaxed);
        }
        made
    }

    /// Plain steps at `period`, each gap at most two entries (one unless `SPLIT`): at most
    /// `room` of them, until a ramp millisecond would end; counted off `left`. `SLAVES`: the
    /// move has slaves, or runs dual-edge with split gaps (without, one axis, the loop keeps
    /// fewer values). `FLIP`: one axis in dual-edge mode, its words alternating between
    /// setting and resetting the pin.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.lane")]
    fn lane<const SPLIT: bool, const SLAVES: bool, const FLIP: bool>(&mut self, words: &mut [u32], periods: &mut [u16], period: u32, on: u32, room: u32) -> usize {
        let p = self.cur;
        let (mut frac, mut ms_left, mut word, mut level, mut gap_in) = (self.frac, self.ms_left, self.word, self.level, self.gap_in);
        let (dual, max) = (self.dual, self.max_tick);
        // One axis: the step after `word` sets the pin; with `FLIP` it resets it when `word`
        // leaves it high, and each step after flips between the two (`toggle`'s words).
        let flip = on | on << 16;
        let mut one = if FLIP && level & on != 0 { on << 16 } else { on };
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
            let mut next = one;
            if FLIP {
                one ^= flip;
            }
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
        if FLIP && steps & 1 != 0 {
            // (An odd number of toggles of the pin.)
            level ^= on;
        }
        (self.frac, self.ms_left, self.word, self.level, self.gap_in) = (frac, ms_left, word, level, gap_in);
        self.left -= steps;
        made
    }

    /// [`Self::lane`] without the split, for a move with slaves, in either edge mode (the hot
    /// path of 2 to 7 axes), slave-major: the master walks the steps (the periods, and its own
    /// bit in the words); then the slaves, three or two at a time with their accumulators in
    /// registers, walk the same steps and OR their bits into the words; in dual-edge mode a
    /// last pass toggles them. The run takes the step that ends a ramp millisecond too, last
    /// (as `elapse` would: a new millisecond, the ramp half asked for; the fill runs it
    /// before the next entry).
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".data.ramfunc.slave_lane")]
    fn slave_lane(&mut self, words: &mut [u32], periods: &mut [u16], period: u32, on: u32, room: u32) -> usize {
        let len = words.len().min(periods.len()).min(room as usize);
        // (Buffers are halves, at most HALF_MAX entries: `k·period` below stays far from 2^32.)
        debug_assert!(len <= 1 << 11);
        let (frac, ms_left) = (self.frac, self.ms_left);
        // As many steps as the ramp millisecond leaves room for: the gaps of `k` steps add up
        // to `(frac + k·period) >> 4` (`period` < 2^20: its gaps fit one entry).
        let mut k = len;
        while k > 0 && ((frac + k as u32 * period) >> 4) as i32 >= ms_left {
            k -= 1;
        }
        // And the step whose gap ends the millisecond, last (`elapse`'s work on it below: the
        // fill runs the ramp half before the next entry), rather than a whole tick for it.
        let ms_end = k < len;
        k += ms_end as usize;
        if k == 0 {
            return 0;
        }
        let made = k;
        let sum = frac + made as u32 * period;
        let (w, mut per) = (words.as_mut_ptr(), periods.as_mut_ptr());
        let (mut acc, mut ws) = (frac, w);
        // SAFETY: made ≤ len ≤ both lengths.
        unsafe {
            macro_rules! step {
                () => {
                    acc = (acc & 15) + period;
                    *per = ((acc >> 4) - 1) as u16;
                    *ws = on;
                    (per, ws) = (per.add(1), ws.add(1));
                };
            }
            // Two at a time (the loop's branch costs as much as a step's work).
            if k & 1 != 0 {
                step!();
            }
            k >>= 1;
            while k != 0 {
                step!();
                step!();
                k -= 1;
            }
        }
        let mut ms = ms_left - (sum >> 4) as i32;
        if ms_end {
            // (At most 0 here: a new millisecond, which the ramp half walks.)
            ms += TICKS_PER_MS as i32;
            bump(&self.shared.link.ms);
            self.pend();
        }
        (self.frac, self.ms_left, self.gap_in) = (sum & 15, ms, acc >> 4);
        self.left -= made as u32;
        let mut last = on;
        // Entry 0 is the edge that was about to happen; the steps' words but the last are
        // entries 1..made, the last becomes the edge about to happen.
        // SAFETY: 0 < made ≤ words.len(); the running move's slot: plain fields and its
        // slaves, which only the step half touches (see `step`).
        unsafe {
            *w = self.word;
            let (first, end) = (w.add(1), w.add(made));
            let p = self.cur;
            let (n, t, s) = ((*p).n_slaves as usize, (*p).total, (*p).slaves.as_mut_ptr());
            // Threes, then twos: the last two may take slot `n`, unused (its count 0: it never
            // steps; `n < N`, the master is no slave).
            let mut i = 0;
            while n - i >= 3 && n - i != 4 {
                walk3(first, end, &mut last, s.add(i), t);
                i += 3;
            }
            while i < n {
                walk2(first, end, &mut last, s.add(i), t);
                i += 2;
            }
            if self.dual {
                // Each word toggles its pins, in step order (entry 0 already did).
                let (mut w, mut level) = (first, self.level);
                while w != end {
                    *w = toggle(*w, &mut level);
                    w = w.add(1);
                }
                last = toggle(last, &mut level);
                self.level = level;
            }
        }
        self.word = last;
        made
    }
}

/// `s[i..]` without the call the slice index makes at `opt-level = "z"` (the fill runs it per
/// half; the DMA fill uses it too).
#[inline(always)]
pub(crate) fn tail<T>(s: &mut [T], i: usize) -> &mut [T] {
    let i = i.min(s.len());
    // SAFETY: `i ≤ s.len()`: the rest of the slice, borrowed from `s`.
    unsafe { core::slice::from_raw_parts_mut(s.as_mut_ptr().add(i), s.len() - i) }
}

/// Slave-major walks: `walkK` runs the K slaves from `s` on over the steps whose words are
/// `first..end` and then `last`, ORing their bits in. In registers each accumulator runs as
/// `total − 1 − acc` (in `0..total`, `total` < 2^31), counted down: the slave steps when it
/// goes below 0 (one subtraction and its sign, where [`crate::motion::interp::Dda::step_mask`] adds
/// and compares). Out of line: each gets all the registers (a walk of three keeps 13 values).
macro_rules! walks {
    ($($name:ident: $($j:literal $s:ident $d:ident $c:ident $o:ident),*;)*) => {$(
        #[inline(never)]
        #[cfg_attr(target_os = "none", link_section = ".data.ramfunc.walk")]
        unsafe fn $name(first: *mut u32, end: *mut u32, last: &mut u32, s: *mut Slave, total: u32) {
            let t = total as i32;
            // SAFETY: the caller's slaves, from `s` on.
            $(let $s = unsafe { &mut *s.add($j) };
            let ($c, $o) = ($s.dda.count() as i32, $s.on);
            let mut $d = (total - 1 - $s.dda.acc()) as i32;)*
            macro_rules! step {
                ($x:expr) => {{
                    let mut x: u32 = $x;
                    $($d -= $c;
                    if $d < 0 {
                        $d += t;
                        x |= $o;
                    })*
                    x
                }};
            }
            let (mut w, mut k) = (first, end as usize - first as usize);
            // (Counted down and tested at the bottom: at opt-level "z" a loop tested at the top
            // keeps fewer values in registers.)
            if k != 0 {
                loop {
                    // SAFETY: first..end lies in the caller's words.
                    unsafe {
                        *w = step!(*w);
                        w = w.add(1);
                    }
                    k -= 4;
                    if k == 0 {
                        break;
                    }
                }
            }
            *last = step!(*last);
            $($s.dda.set_acc(total - 1 - $d as u32);)*
        }
    )*};
}

walks! {
    walk2: 0 s0 d0 c0 o0, 1 s1 d1 c1 o1;
    walk3: 0 s0 d0 c0 o0, 1 s1 d1 c1 o1, 2 s2 d2 c2 o2;
}
