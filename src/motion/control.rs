//! The control word: feed hold and the immediate-stop epoch in one atomic, so the step
//! interrupt learns of both with one load per tick.
//!
//! Who uses it: the shell and the controller write it ([`Control::set_hold`],
//! [`Control::stop`]); the engine reads a [`Ctl`] snapshot each tick and acts when it differs
//! from the last one it saw. Moves are stamped with the epoch they were queued in; an engine
//! that sees a newer epoch drops the running move and every move stamped older.

use core::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// One snapshot of the control word: bit 0 feed hold, bits 1.. the stop epoch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ctl(u32);

impl Ctl {
    /// Feed hold requested.
    #[inline(always)]
    pub fn hold(self) -> bool {
        self.0 & 1 != 0
    }

    /// The immediate-stop epoch.
    #[inline(always)]
    pub fn epoch(self) -> u32 {
        self.0 >> 1
    }

    /// True when an immediate stop happened between `older` and `self`.
    #[inline(always)]
    pub fn stopped_since(self, older: Ctl) -> bool {
        (self.0 ^ older.0) >> 1 != 0
    }
}

/// The shared control word.
pub struct Control(AtomicU32);

impl Default for Control {
    fn default() -> Self {
        Self::new()
    }
}

impl Control {
    /// No hold, epoch 0.
    pub const fn new() -> Self {
        Control(AtomicU32::new(0))
    }

    /// A snapshot (one load).
    #[inline(always)]
    pub fn load(&self) -> Ctl {
        Ctl(self.0.load(Relaxed))
    }

    /// Feed hold on (decelerate and pause) or off (resume).
    pub fn set_hold(&self, on: bool) {
        if on {
            self.0.fetch_or(1, Relaxed);
        } else {
            self.0.fetch_and(!1, Relaxed);
        }
    }

    /// Immediate stop: a new epoch.
    pub fn stop(&self) {
        self.0.fetch_add(2, Relaxed);
    }
}
