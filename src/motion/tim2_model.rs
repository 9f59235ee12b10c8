//! A model of TIM2's buffered period register driving the engine: ticks in, timed edges out.
//!
//! Who uses it: host tests and benchmarks that check what the pins would do. It follows the
//! firmware exactly: at each update event the shadow ARR takes the preloaded value, the handler
//! stores the engine's word and preloads the ARR the engine returns.

use crate::motion::engine::Engine;

/// One update event: time in timer ticks and the BSRR word stored at it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    pub t: u64,
    pub word: u32,
}

/// The timer pipeline around an engine.
pub struct TimerSim {
    t: u64,
    preload: u16,
}

impl Default for TimerSim {
    fn default() -> Self {
        Self::new()
    }
}

impl TimerSim {
    /// Timer at time 0 with the idle period preloaded (as the firmware starts it).
    pub fn new() -> Self {
        TimerSim { t: 0, preload: (crate::motion::engine::IDLE_TICKS - 1) as u16 }
    }

    /// Time of the next update event (ticks).
    pub fn now(&self) -> u64 {
        self.t
    }

    /// Runs one update event: returns the edge written at it.
    pub fn update<const N: usize, const L: usize>(&mut self, eng: &mut Engine<'_, N, L>) -> Edge {
        let shadow = self.preload;
        let edge = Edge { t: self.t, word: eng.word() };
        self.preload = eng.tick();
        self.t += shadow as u64 + 1;
        edge
    }
}

/// Applies a BSRR word to an output register value (set wins over reset, as on the STM32).
pub fn apply_bsrr(odr: u16, word: u32) -> u16 {
    (odr & !((word >> 16) as u16)) | word as u16
}
