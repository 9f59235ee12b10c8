//! DMA burst output: the step engine fills buffers that DMA plays out at TIM2's events.
//!
//! Who uses it: the firmware in DMA mode (`$581=1`), from the DMA half-transfer and
//! transfer-complete interrupt; host tests, which compare the buffers with the interrupt engine.
//!
//! The mode. TIM2 still paces every edge, but no interrupt runs per edge: at each update event
//! DMA stores the next word of [`Burst`]'s word buffer into the step port's BSRR, and at a
//! compare event just after it DMA stores the next entry of the period buffer into TIM2's
//! (preloaded) ARR; with full pulses a second compare event `pulse` after each update has DMA
//! store the constant falling-edge word. Entry `k` of the two buffers is exactly what the
//! interrupt handler stores at update event `k`: the word ([`crate::motion::engine::Stepper::word`])
//! and the ARR the tick returns ([`crate::motion::engine::Stepper::tick`]). Both buffers are circular;
//! when DMA has played one half, its interrupt fills that half again ([`Burst::fill`]).
//!
//! The same engine. [`Burst`] holds both halves of the engine and runs them as the host's
//! [`crate::motion::engine::Engine`] does, the ramp half's work right after the tick that asked for
//! it, so the buffers carry the same edges at the same times as the interrupt engine: the
//! property tests check it entry by entry. Counts and ratios are the engine's.
//!
//! Latency. A feed hold, a stop or anything else the engine reacts to reaches the pins after
//! the entries already buffered: at most two halves. Each entry is at most the layout's
//! `max_tick` ticks long (longer periods are split into filler entries, word 0), so the
//! buffered time is at most `2 × half × max_tick` ticks; [`Layout::for_pulse`] keeps that
//! ≤ 1.33 ms. (A hard limit does not wait: its interrupt stops TIM2, and with it the DMA
//! requests, at once.)
//!
//! Costs. Entries where nothing but a step (or a filler) happens take a fast path, the
//! step half's lanes (`engine/stepper/plain.rs`: no per-tick checks, no shared load per step);
//! every other entry is a whole tick plus the ramp half's work, as above. No interrupt entry or
//! register access per entry; DMA moves two or three words per entry on the bus. Halves of 32
//! entries balance the fill's cost per half against splitting: entries up to 1500 ticks keep a
//! step one entry from 48 kHz up, and a half lasts long enough (≈ 5.7k cycles at the 7-axis cap)
//! for a fill that runs the ramp half's work twice (a millisecond and the deceleration's start
//! in the same half); with 24 entries such fills came late at some move lengths and sender
//! timings on 7 axes. Modeled figures: bench/RESULTS.md, "DMA burst mode".

use crate::motion::engine::stepper::plain::tail;
use crate::motion::engine::{Engine, Ramper, Stepper};
use crate::motion::shared::Shared;
use crate::motion::ramp::RAMP_LEN;
use crate::TICKS_PER_MS;

/// Entries per buffer half, at most: 32 (both buffers 384 bytes; entries up to 1500 ticks: one
/// entry per step from 48 kHz up).
pub const HALF_MAX: usize = 32;

/// Longest entry at the full half length: 1/48 ms, 1500 ticks (one entry per step from 48 kHz up).
pub const ENTRY_TICKS: u32 = TICKS_PER_MS / 48;

/// Buffered time, at most (ticks): both halves of full-length entries, 1.33 ms.
pub const HORIZON_TICKS: u32 = 2 * HALF_MAX as u32 * ENTRY_TICKS;

/// Buffer geometry for a pulse width: entries per half and the longest entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Entries per half (2..=[`HALF_MAX`]).
    pub half: usize,
    /// Longest entry, timer ticks.
    pub max_tick: u32,
}

impl Layout {
    /// The layout for a falling edge `fall_ticks` after each update event (the compare value;
    /// 0 in dual-edge mode): the first piece of a split period must hold the fall, and pieces
    /// are at least half the longest entry, so the longest entry is above twice the fall. The
    /// half shrinks for long pulses so two halves stay within [`HORIZON_TICKS`].
    pub const fn for_pulse(fall_ticks: u32) -> Layout {
        let need = 2 * fall_ticks + 4;
        let max_tick = if need > ENTRY_TICKS { need } else { ENTRY_TICKS };
        let mut half = (HORIZON_TICKS / (2 * max_tick)) as usize;
        if half > HALF_MAX {
            half = HALF_MAX;
        }
        if half < 2 {
            half = 2;
        }
        Layout { half, max_tick }
    }

    /// Longest time between a change the engine sees and the pins showing it (ticks).
    pub const fn latency_ticks(&self) -> u32 {
        2 * self.half as u32 * self.max_tick
    }
}

/// The engine filling DMA buffers.
pub struct Burst<'a, const N: usize, const L: usize = RAMP_LEN> {
    step: Stepper<'a, N, L>,
    ramp: Ramper<'a, N, L>,
    shared: &'a Shared<N>,
    /// The position record's sequence and the move being entered, as the ramp half last saw
    /// them (a move change the step half made without asking for the ramp half).
    seen: (u32, usize),
    quick: bool,
}

impl<'a, const N: usize, const L: usize> Burst<'a, N, L> {
    /// The engine for buffers of entries at most `max_tick` ticks long.
    pub fn new(engine: Engine<'a, N, L>, shared: &'a Shared<N>, max_tick: u32) -> Self {
        let (mut step, ramp) = engine.split();
        step.set_max_tick(max_tick);
        Burst { step, ramp, shared, seen: (shared.record_seq(), 0), quick: true }
    }

    /// The engine back (to be rebuilt, see [`Engine::rebuild`]).
    pub fn into_engine(self) -> Engine<'a, N, L> {
        Engine::join(self.step, self.ramp)
    }

    /// Whether the next entry is a filler piece of a longer period (for tests, as
    /// [`Engine::filler_next`]).
    pub fn filler_next(&self) -> bool {
        self.step.filler_next()
    }

    /// The falling-edge word the compare event's DMA stores (0 in dual-edge mode).
    pub fn step_off(&self) -> u32 {
        self.step.step_off()
    }

    /// Fills `words` and `periods` (the same length) with the next entries: the BSRR word for
    /// each update event and the ARR value to preload at it.
    /// Runs of fillers and plain steps take the step half's fast path (the same words and
    /// periods without the per-tick checks, see `engine::stepper::plain`); every other entry is
    /// a whole tick.
    pub fn fill(&mut self, words: &mut [u32], periods: &mut [u16]) {
        self.fill_watched(words, periods, || 0);
    }

    /// [`Self::fill`] for buffers DMA is playing: `played` says how many entries of this half DMA
    /// has read so far ([`dma_played`]). Returns whether DMA read an entry before the fill wrote
    /// it (late), as far as the checks see: after every entry that ran the ramp half's work (the
    /// long ones; other entries take less time than DMA plays one at the rate caps, so DMA
    /// cannot catch up on them), and after a run of the slave-major lane against its first
    /// entry (its words are whole only at its end). The caller checks the fill's start (`played`
    /// more than 0) and end (the half's own completion flag set again) itself.
    pub fn fill_watched(&mut self, words: &mut [u32], periods: &mut [u16], mut played: impl FnMut() -> usize) -> bool {
        let len = words.len().min(periods.len());
        let mut late = false;
        let mut i = 0;
        while i < len {
            if self.quick {
                let at = i;
                let made = self.step.quick_entries(tail(words, i), tail(periods, i));
                i += made;
                if core::mem::replace(&mut self.step.slave_major, false) {
                    // DMA must not have reached the lane's first entry before its last pass.
                    late |= played() > at;
                }
                if made != 0 && self.ramp_work() {
                    // (A lane ended the ramp millisecond: its walk, then the fast path again.)
                    late |= played() > i;
                    continue;
                }
                if i >= len {
                    break;
                }
            }
            words[i] = self.step.word();
            periods[i] = self.step.tick();
            i += 1;
            if self.ramp_work() {
                // (The long entries: the ramp half's work.)
                late |= played() > i;
            }
        }
        late
    }

    /// Turns the fast path off (every entry a whole tick) or on, for tests that compare them.
    pub fn set_quick(&mut self, on: bool) {
        self.quick = on;
    }

    /// The ramp half's work, when a tick asked for it or changed moves (what the host engine
    /// does after every tick: its ramp half returns at once when nothing changed).
    /// Whether it ran.
    #[inline(always)]
    fn ramp_work(&mut self) -> bool {
        let link = &self.shared.link;
        let now = (self.shared.record_seq(), link.next.load(core::sync::atomic::Ordering::Relaxed));
        if self.step.take_pended() || now != self.seen {
            self.seen = now;
            self.ramp.run();
            return true;
        }
        false
    }
}

/// Entries DMA has read of the half `at..at + half` of a circular buffer of `n` entries, its
/// channel's remaining count being `cndtr` (n..=1: the next entry it reads is `n − cndtr`; it
/// reloads to n after the last); 0 while it plays the other half. For
/// [`Burst::fill_watched`].
pub fn dma_played(cndtr: u32, n: usize, at: usize, half: usize) -> usize {
    // (cndtr is 1..=n: no remainder needed, and none taken on this path.)
    let next = n.wrapping_sub(cndtr as usize);
    if next >= at && next < at + half {
        next - at
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::dma_played;

    #[test]
    fn dma_position_against_the_half_filled() {
        // 2 halves of 4: next entry 8 - cndtr (8 after a reload: entry 0)
        let played = |cndtr| (dma_played(cndtr, 8, 0, 4), dma_played(cndtr, 8, 4, 4));
        assert_eq!(played(8), (0, 0), "reloaded: entry 0 next, none of the first half read");
        assert_eq!(played(5), (3, 0), "entry 3 next");
        assert_eq!(played(4), (0, 0), "entry 4 next: the second half");
        assert_eq!(played(1), (0, 3), "entry 7 next");
    }
}
