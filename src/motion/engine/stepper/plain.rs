//! The DMA burst fill's fast path: runs of fillers and of plain steps, entry by entry what
//! [`Stepper::tick`] gives, without its per-tick checks.
//!
//! A filler is a piece of a period longer than one entry (word 0). A plain step is one where
//! nothing but the step happens: the move is running, the control word has not changed (it
//! cannot change during a fill: the fill interrupt preempts every context that writes it), the
//! deceleration trigger and the move's last step are not reached, and the gap fits one entry.
//! Neither may end a ramp millisecond (that asks for the ramp half). Within a run the period is
//! the one the ramp half last published (only the ramp half writes it, and in DMA mode it runs
//! inside the fill, between runs), so a run needs no shared load per entry. The first entry
//! that is neither is left to [`Stepper::tick`].

use core::sync::atomic::Ordering::Relaxed;

use super::{Phase, Stepper};

impl<const N: usize, const L: usize> Stepper<'_, N, L> {
    /// Fills the front of `words` and `periods` with fillers and plain steps; returns how many
    /// entries (0 when the next one needs a whole tick).
    pub(crate) fn quick_entries(&mut self, words: &mut [u32], periods: &mut [u16]) -> usize {
        let len = words.len().min(periods.len());
        let mut made = 0;
        loop {
            let n = if self.extend != 0 {
                self.fillers(&mut words[made..len], &mut periods[made..len])
            } else {
                self.plain_steps(&mut words[made..len], &mut periods[made..len])
            };
            if n == 0 {
                return made;
            }
            made += n;
        }
    }

    /// Fillers of the period being split, up to its end or a ramp millisecond's.
    fn fillers(&mut self, words: &mut [u32], periods: &mut [u16]) -> usize {
        let max = self.max_tick;
        let mut made = 0;
        for (w, per) in words.iter_mut().zip(periods.iter_mut()) {
            let rem = self.extend;
            // (As `filler_piece`.)
            let chunk = if rem <= max {
                rem
            } else if rem >= max + max / 2 {
                max
            } else {
                max / 2
            };
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

    /// Plain steps of the running move.
    fn plain_steps(&mut self, words: &mut [u32], periods: &mut [u16]) -> usize {
        if self.phase != Phase::Run || self.shared.ctl.load() != self.ctl_seen {
            return 0;
        }
        let p = self.cur;
        // SAFETY: the running move's slot (see `step`); atomics.
        let (period, at) = unsafe { ((*p).period.load(Relaxed), (*p).decel_at.load(Relaxed)) };
        // A step is plain while the steps left after it stay above the trigger and above 0.
        let room = self.left.saturating_sub(at + 1) as usize;
        if period == 0 || (period + 15) >> 4 > self.max_tick || room == 0 {
            return 0;
        }
        let n = words.len().min(periods.len()).min(room);
        let (words, periods) = (&mut words[..n], &mut periods[..n]);
        let made = self.run(words, periods, period);
        // SAFETY: as above; a plain field.
        let total = unsafe { (*p).total };
        self.left -= made as u32;
        self.shared.mv_done.store(total - self.left, Relaxed);
        made
    }

    /// The loop of [`Self::plain_steps`]: at most `words.len()` steps at `period`, until a ramp
    /// millisecond would end. Not inlined: in a function of its own everything the loop uses
    /// stays in registers (no stack load per step).
    #[inline(never)]
    fn run(&mut self, words: &mut [u32], periods: &mut [u16], period: u32) -> usize {
        let p = self.cur;
        // SAFETY: the running move's slot; plain fields, and its slaves, which only the step
        // half touches (see `step`).
        let (total, master_on, slaves) = unsafe {
            let n = ((*p).n_slaves as usize).min(N.saturating_sub(1));
            ((*p).total, (*p).master_on, (*p).slaves.get_mut(..n).unwrap_or_default())
        };
        let (mut frac, mut ms_left, mut word, mut level) = (self.frac, self.ms_left, self.word, self.level);
        let dual = self.dual;
        let mut made = 0usize;
        let mut gap = self.gap_in;
        for (w, per) in words.iter_mut().zip(periods.iter_mut()) {
            let acc = frac + period;
            gap = acc >> 4;
            if ms_left <= gap as i32 {
                break; // the ramp millisecond ends here: a whole tick
            }
            ms_left -= gap as i32;
            frac = acc & 15;
            let mut next = master_on;
            for s in slaves.iter_mut() {
                next |= s.on & s.dda.step_mask(total);
            }
            if dual {
                let old = level;
                level ^= next;
                next = (next & !old) | (next & old) << 16;
            }
            *w = word;
            *per = (gap - 1) as u16;
            word = next;
            made += 1;
        }
        if made > 0 {
            self.gap_in = gap;
        }
        (self.frac, self.ms_left, self.word, self.level) = (frac, ms_left, word, level);
        made
    }
}
