//! Period extension: a period longer than one timer event holds (over 65 536 ticks, below
//! 1.1 kHz; less in DMA burst mode) is split into filler events whose word is 0, the prescaler
//! unchanged (so pulse width and resolution never change).
//!
//! Who uses it: the step path (a whole tick), and the DMA fill's lanes ([`piece`]).

use super::state::Stepper;

impl<'a, const N: usize, const L: usize> Stepper<'a, N, L> {
    /// A period longer than the timer holds: its first piece now, fillers for the rest.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.extended")]
    pub(super) fn extended(&mut self, ticks: u32) -> u16 {
        self.extend = ticks;
        self.whole = ticks;
        self.filler_piece()
    }

    /// A filler event of an extended period: an empty word and the next piece.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".fill.filler")]
    pub(super) fn filler(&mut self) -> u16 {
        self.word = 0;
        self.filler_piece()
    }

    /// The next piece of an extended period, at most the longest period (65 536 ticks, less in
    /// DMA burst mode) and at least half of it: with the timer's 16 bits a filler never gets
    /// shorter than a real period, and a step's own first piece always holds its pulse.
    #[cfg_attr(target_os = "none", link_section = ".fill.filler_piece")]
    pub(super) fn filler_piece(&mut self) -> u16 {
        let rem = self.extend;
        let chunk = piece(rem, self.max_tick);
        self.extend = rem - chunk;
        let arr = self.elapse(chunk);
        if self.extend == 0 {
            self.gap_in = self.whole;
        }
        arr
    }
}

/// The piece of a `rem`-tick period an event takes when events are at most `max` ticks: all
/// of it, else `max`, else half of `max` (so the last piece is at least half of `max`).
#[inline(always)]
pub(super) fn piece(rem: u32, max: u32) -> u32 {
    if rem <= max {
        rem
    } else if rem >= max + max / 2 {
        max
    } else {
        max / 2
    }
}
