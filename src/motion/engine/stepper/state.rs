//! The step half's state, and what every part of it uses: building it, the accessors, asking
//! for the ramp half, keeping ramp time, publishing the engine's state.
//!
//! Who uses it: every file of the step half (`engine/stepper/*`).

use core::sync::atomic::Ordering::Relaxed;

use crate::board::PinMap;
use crate::motion::control::Ctl;
use crate::motion::engine::link::Link;
use crate::motion::engine::ticks::MAX_TICK;
use crate::motion::prepared::Prepared;
use crate::motion::ramp::{RampSlot, RAMP_LEN};
use crate::motion::ring::RingConsumer;
use crate::motion::shared::{Shared, State};
use crate::TICKS_PER_MS;

/// [`Link::succ`] as the step half leaves it when it enters a move or goes idle: no successor
/// primed, and never a value the ramp half last stored (so its compare-and-swap over a stale
/// view fails).
pub(super) const CLEARED: usize = 1;

/// What the step half is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Phase {
    /// No move loaded.
    Idle,
    /// The move after the running one starts at the next edge with its first step.
    Enter,
    /// The move after the running one starts at the next edge with its direction change,
    /// then its first step.
    Dir,
    /// Stepping.
    Run,
    /// Stopped by feed hold, move not finished.
    Held,
}

/// The step half for `N` axes.
pub struct Stepper<'a, const N: usize, const L: usize = RAMP_LEN> {
    pub(super) shared: &'a Shared<N>,
    pub(super) ring: RingConsumer<'a, N>,
    pub(super) ramp: &'a RampSlot<L>,
    pub(super) step_off: u32,
    /// Dual-edge mode: each step toggles its pin; `level` shadows the step pins' level (the
    /// pins are low when the engine is built: boot drives them low; `Engine::rebuild` takes
    /// their levels).
    pub(super) dual: bool,
    pub(super) level: u32,
    // The edge about to happen.
    pub(super) word: u32,
    pub(super) extend: u32,
    pub(super) frac: u32,
    pub(super) ms_left: i32,
    // The running move (a slot of the ring; valid while `phase != Idle`).
    pub(super) phase: Phase,
    pub(super) cur: *mut Prepared<N>,
    pub(super) left: u32,
    /// This tick's own period: from its update event to the next (the previous tick's ARR); for
    /// the last piece of a split period, the whole period (so the decisions that depend on it
    /// do not depend on how a period is split).
    pub(super) gap_in: u32,
    /// The whole of the period being split.
    pub(super) whole: u32,
    pub(super) hold: bool,
    pub(super) ctl_seen: Ctl,
    /// How to ask for the ramp half's interrupt (a counter in [`Link`] moved): write `.1` to
    /// the register at `.0` (the NVIC's set-pending word for its vector); null on the host,
    /// where the host's `Engine` runs the ramp half after every tick anyway.
    pub(super) pend: (*mut u32, u32),
    /// Set when a tick asked for the ramp half and no register is set to pend ([`Self::set_pend`]):
    /// the DMA burst fill runs the ramp half itself (`motion::burst`).
    pub(super) pended: bool,
    /// Longest period one event may have: [`MAX_TICK`] (the timer's 16 bits), less in DMA burst
    /// mode, where it bounds the time the buffers hold (longer periods are split into fillers).
    pub(super) max_tick: u32,
    /// The next tick may be a plain step ([`Self::tick_quick`]): stepping (`phase` is `Run`)
    /// and no period being split. Set by every whole tick; only ever conservative.
    pub(super) quick: bool,
    /// The DMA fill's last run of plain entries took the slave-major lane (its words are whole
    /// only at its end; the burst fill (`Burst::fill_watched`) checks DMA against its start).
    pub(crate) slave_major: bool,
}

// SAFETY: `cur` points into the ring the engine consumes; the step half is moved into the
// interrupt once and used only there.
unsafe impl<const N: usize, const L: usize> Send for Stepper<'_, N, L> {}

impl<'a, const N: usize, const L: usize> Stepper<'a, N, L> {
    pub(in crate::motion::engine) fn new(shared: &'a Shared<N>, ring: RingConsumer<'a, N>, ramp: &'a RampSlot<L>, pins: PinMap<N>) -> Self {
        Stepper {
            shared,
            ring,
            ramp,
            step_off: pins.step_off,
            dual: pins.dual,
            level: 0,
            word: 0,
            extend: 0,
            frac: 0,
            ms_left: TICKS_PER_MS as i32,
            phase: Phase::Idle,
            cur: core::ptr::null_mut(),
            left: 0,
            gap_in: 0,
            whole: 0,
            hold: false,
            ctl_seen: shared.ctl.load(),
            pend: (core::ptr::null_mut(), 0),
            pended: false,
            max_tick: MAX_TICK,
            quick: false,
            slave_major: false,
        }
    }

    /// See `Engine::rebuild`: the pin map's words, no pending edge or filler, no ramp register.
    pub(in crate::motion::engine) fn rebuild(&mut self, pins: PinMap<N>, high: u32) {
        self.step_off = pins.step_off;
        self.dual = pins.dual;
        self.level = high & pins.step_on.iter().fold(0, |m, s| m | s);
        self.word = 0;
        self.extend = 0;
        self.pend = (core::ptr::null_mut(), 0);
        self.max_tick = MAX_TICK;
        self.quick = false;
        self.slave_major = false;
    }

    /// Whether the next tick is a filler piece of an extended period (it reads nothing shared).
    pub(crate) fn filler_next(&self) -> bool {
        self.extend != 0
    }

    /// Master steps left in the running move.
    pub(in crate::motion::engine) fn left(&self) -> u32 {
        self.left
    }

    /// The running move as the primed successor in the link: what a ramp pass preempted
    /// between its look at the ring and its store of the successor leaves once this half has
    /// entered that move (host tests).
    pub(in crate::motion::engine) fn stale_succ(&self) {
        self.link().succ.store(self.cur as usize, core::sync::atomic::Ordering::Relaxed);
    }

    /// The BSRR word to store at this update event (precomputed by the previous tick).
    #[inline(always)]
    pub fn word(&self) -> u32 {
        self.word
    }

    /// The BSRR word for the compare event (falling step edges).
    #[inline(always)]
    pub fn step_off(&self) -> u32 {
        self.step_off
    }

    /// How to ask for the ramp half's interrupt: write `bit` to the register at `reg`.
    ///
    /// # Safety
    /// `reg` must be valid for volatile writes of `bit` whenever the step half runs, with no
    /// effect but pending the ramp half's interrupt (the NVIC's ISPR word of its vector).
    pub unsafe fn set_pend(&mut self, reg: *mut u32, bit: u32) {
        self.pend = (reg, bit);
    }

    /// Pends the ramp half's interrupt (or notes the request, with no register set).
    #[inline(always)]
    pub(super) fn pend(&mut self) {
        if !self.pend.0.is_null() {
            // SAFETY: `set_pend`'s contract.
            unsafe { core::ptr::write_volatile(self.pend.0, self.pend.1) };
        } else {
            self.pended = true;
        }
    }

    /// Whether a tick asked for the ramp half since the last call (no register set).
    #[inline(always)]
    pub(crate) fn take_pended(&mut self) -> bool {
        core::mem::replace(&mut self.pended, false)
    }

    /// Longest period of one event, timer ticks (at most [`MAX_TICK`], at least 2).
    pub(crate) fn set_max_tick(&mut self, ticks: u32) {
        self.max_tick = ticks.clamp(2, MAX_TICK);
    }

    /// `chunk` ticks until the next update event: keeps time for the ramp; returns the ARR
    /// value.
    #[inline(always)]
    pub(super) fn elapse(&mut self, chunk: u32) -> u16 {
        self.ms_left -= chunk as i32;
        if self.ms_left <= 0 {
            self.ms_left += TICKS_PER_MS as i32;
            if self.phase != Phase::Idle && self.phase != Phase::Held {
                bump(&self.link().ms);
                self.pend();
            }
        }
        self.gap_in = chunk;
        (chunk - 1) as u16
    }

    #[inline(always)]
    pub(super) fn link(&self) -> &'a Link {
        &self.shared.link
    }

    #[inline(always)]
    pub(super) fn publish(&self, s: State) {
        self.shared.state.store(s as u8, Relaxed);
    }
}

/// One more on a counter only the step half writes (no read-modify-write race: every other
/// context only reads it).
#[inline(always)]
pub(super) fn bump(c: &core::sync::atomic::AtomicU32) {
    c.store(c.load(Relaxed).wrapping_add(1), Relaxed);
}
