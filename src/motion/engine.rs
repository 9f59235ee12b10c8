//! The step engine: the TIM2 interrupt's half ([`Stepper`]) and the ramp's half ([`Ramper`]),
//! which runs in a lower-priority interrupt that the step interrupt pends.
//!
//! Who uses it: the firmware's TIM2 handler (one [`Stepper::tick`] per update event) and its
//! ramp handler ([`Ramper::run`] when the tick asks for it); host tests use [`Engine`], which
//! runs both halves in that order on every tick (the ramp's work done before the next edge, as
//! on the board whenever the step interrupt leaves it the time).
//!
//! Contract of one tick. At each timer update event the handler first stores
//! [`Stepper::word`] into the step port's BSRR (the rising step edges and any direction change,
//! all precomputed, so the edge time never depends on which axes step), then calls
//! [`Stepper::tick`], which computes the word for the *next* update event and returns the ARR
//! value to preload now (TIM2's ARR is buffered, so it takes effect at the next update and sets
//! the gap after it). Falling edges come from a compare event `pulse_ticks` after each update,
//! where the handler stores [`Stepper::step_off`] (dual-edge mode: no compare event, each step
//! word toggles its pins from a shadow of their level, `step_off` is 0). Periods longer than
//! 65 536 ticks (< 1.1 kHz) are split into filler events whose word is 0 (period extension;
//! the prescaler stays 0, so pulse width and resolution never change).
//!
//! The split. A tick does the same few things every time: the step word (master and the
//! move's slaves' DDA), the step count, the period (read from the running move's slot, where
//! the ramp half keeps it), the deceleration trigger (one compare with the slot's trigger) and
//! timer-time bookkeeping. Everything that walks the ramp table runs in the ramp half: the
//! ramp millisecond, the start of a deceleration, a move's trigger distances and period, a
//! hold and a resume. The step half only counts these events ([`Link`]) and asks for the ramp
//! interrupt; the ramp half reads the counts, does the work and publishes its results as single
//! words in the running move's slot (period, trigger), so neither side ever waits for the
//! other and the step interrupt preempts the ramp work at every edge.
//!
//! Moves arrive prepared ([`crate::motion::prepared`]) in a ring and run in their slot. A move change
//! in the step half is a pointer switch, a position-record swap and the new move's period,
//! which the ramp half computed beforehand (its period at the walk's index, primed in the
//! successor's slot at every ramp millisecond); its trigger follows when the ramp half has seen
//! the change (until then it cannot fire). The ramp index carries over from move to move
//! (look-ahead junctions run through at speed). A direction change at a junction is carved out
//! of the gap before the next step (the change, then `dir_setup`) when steps are slow; at speed
//! it comes one period after the last step, then `dir_setup`, so the new move's first step
//! waits for the setup.
//!
//! Invariants: every move emits exactly its step counts (the ramp only sets periods); each
//! axis's position equals the step words handed out (in dual-edge mode one toggle per step, the
//! pins' level the parity of the steps made since boot); a direction change is written alone and
//! followed by at least `dir_setup_ticks` before the next step. No floats, no division, no
//! loop over the queue in the step half: the only loop is the unrolled one over the move's
//! slaves (≤ 6).
//!
//! Cycle budget: see bench/RESULTS.md (modeled on the virtual bench).

use crate::board::PinMap;
use crate::motion::ramp::{RampSlot, RAMP_LEN};
use crate::motion::ring::RingConsumer;
use crate::motion::shared::Shared;

pub(crate) mod link;
mod ramper;
pub(crate) mod stepper;
mod ticks;
pub use link::Link;
pub use ramper::Ramper;
pub use stepper::Stepper;
pub use ticks::{IDLE_TICKS, MAX_TICK, PRIME_TICKS};

/// Both halves in one, for host tests: each tick runs the ramp half's work right after the
/// step half's (on the board: the ramp interrupt, tail-chained after the step interrupt).
pub struct Engine<'a, const N: usize, const L: usize = RAMP_LEN> {
    step: Stepper<'a, N, L>,
    ramp: Ramper<'a, N, L>,
    /// Ticks the ramp half waits between runs (0: after every tick; tests of the two halves
    /// out of step, as when the step interrupt leaves the ramp interrupt little time).
    lag: u32,
    since: u32,
    /// Ticks take the step interrupt's fast path ([`Stepper::tick_quick`]); off: every tick a
    /// whole one (tests compare the two).
    quick: bool,
}

impl<'a, const N: usize, const L: usize> Engine<'a, N, L> {
    /// An idle engine.
    pub fn new(shared: &'a Shared<N>, ring: RingConsumer<'a, N>, ramp: &'a RampSlot<L>, pins: PinMap<N>) -> Self {
        let peek = ring.peek();
        Engine { step: Stepper::new(shared, ring, ramp, pins), ramp: Ramper::new(shared, peek, ramp), lag: 0, since: 0, quick: true }
    }

    /// The two halves, for the two interrupts.
    pub fn split(self) -> (Stepper<'a, N, L>, Ramper<'a, N, L>) {
        (self.step, self.ramp)
    }

    /// The two halves back in one (taken from their interrupts, to be rebuilt).
    pub fn join(step: Stepper<'a, N, L>, ramp: Ramper<'a, N, L>) -> Self {
        Engine { step, ramp, lag: 0, since: 0, quick: true }
    }

    /// Takes a new pin map with the step pins at their idle level ([`PinMap::idle_word`]; `high`:
    /// the port's pins that are high, which dual-edge mode toggles from), for either output
    /// (the ramp interrupt unset, periods up to [`MAX_TICK`]), keeping the position and the
    /// queue. Only with the output stopped: at rest, or cut by a hard limit
    /// with a stop pending (the edge computed for the next event was never stored: it is
    /// dropped, and the next tick takes the stop). The ramp half catches up with what the
    /// step half asked of it.
    pub fn rebuild(&mut self, pins: PinMap<N>, high: u32) {
        self.step.rebuild(pins, high);
        self.ramp.run();
    }

    /// The BSRR word to store at this update event (precomputed by the previous tick).
    #[inline(always)]
    pub fn word(&self) -> u32 {
        self.step.word()
    }

    /// The BSRR word for the compare event (falling step edges).
    #[inline(always)]
    pub fn step_off(&self) -> u32 {
        self.step.step_off()
    }

    /// One tick of the step half (as the step interrupt runs it), then the ramp half's work it
    /// asked for; returns the ARR value.
    pub fn tick(&mut self) -> u16 {
        let arr = if self.quick { self.step.tick_quick() } else { self.step.tick() };
        if self.since >= self.lag {
            self.since = 0;
            self.ramp.run();
        } else {
            self.since += 1;
        }
        arr
    }

    /// Turns the step interrupt's fast path off (every tick a whole one) or on, for tests that
    /// compare them.
    pub fn set_quick(&mut self, on: bool) {
        self.quick = on;
    }

    /// Runs the ramp half only after every `lag + 1`-th tick from now on (0: every tick).
    pub fn set_ramp_lag(&mut self, lag: u32) {
        self.lag = lag;
    }

    /// Whether the next tick is a filler piece of a period longer than one event holds: it
    /// reads nothing shared (for tests that act between real ticks only).
    pub fn filler_next(&self) -> bool {
        self.step.filler_next()
    }

    /// Stores the running move as its own primed successor, as a ramp pass preempted between
    /// its look at the ring and its store of the successor can after a move change (tests).
    pub fn stale_succ(&self) {
        self.step.stale_succ();
    }

    /// Ramp-walk state for tests: (index Q20, decelerating, decel trigger, master steps left).
    pub fn walk_state(&self) -> (u32, bool, u32, u32) {
        let (idx, decel, at) = self.ramp.walk_state();
        (idx, decel, at, self.step.left())
    }
}
