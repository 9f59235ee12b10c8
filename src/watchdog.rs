//! When the firmware may feed the independent watchdog (IWDG), and its timeout.
//!
//! Who uses it: the firmware's idle loop, once per pass. The watchdog is fed only when both
//! halves of the machine showed life since the previous feed: the protocol (SysTick's
//! millisecond clock advanced and the idle loop got here) and the engine (the step interrupt
//! was entered: TIM2 keeps ticking every 0.5 ms even at rest). A hung idle loop, a stopped
//! SysTick or a dead step interrupt all stop the feeding, and the IWDG resets the MCU.

/// IWDG prescaler code (PR = 2: LSI / 16) and reload value: 250 ms nominal, 167–333 ms over
/// the LSI's spread (RM0008 §19.3), above a healthy idle loop's longest stall (a flash save, a
/// TX drain); measured in `bench/tests/firmware_watchdog.rs`.
pub const IWDG_PR: u16 = 2;
pub const IWDG_RLR: u16 = 624;
/// Modeled timeout at the nominal 40 kHz LSI, ms.
pub const TIMEOUT_MS: u32 = (IWDG_RLR as u32 + 1) * (4 << IWDG_PR) / 40;

/// Tracks the two signs of life between feeds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Liveness {
    millis: u32,
    step_entries: u32,
}

impl Liveness {
    /// Starts from the counters' current values.
    pub fn new(millis: u32, step_entries: u32) -> Self {
        Liveness { millis, step_entries }
    }

    /// True (feed now) when both the millisecond clock and the step interrupt's entry count
    /// moved since the last time this returned true. `halted`: a hard limit stopped the step
    /// timer on purpose, so only the clock counts.
    pub fn alive(&mut self, millis: u32, step_entries: u32, halted: bool) -> bool {
        let ok = millis != self.millis && (halted || step_entries != self.step_entries);
        if ok {
            *self = Liveness { millis, step_entries };
        }
        ok
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feeds_only_when_both_moved() {
        let mut l = Liveness::new(10, 100);
        assert!(!l.alive(10, 100, false));
        assert!(!l.alive(11, 100, false), "step interrupt dead");
        assert!(!l.alive(10, 105, false), "clock dead");
        assert!(l.alive(11, 101, false));
        assert!(!l.alive(11, 140, false), "the clock has not moved since the feed");
        assert!(l.alive(12, 140, false));
        assert!(l.alive(13, 140, true), "step timer halted by a hard limit");
        assert!(!l.alive(13, 140, true));
        assert_eq!(TIMEOUT_MS, 250);
    }
}
