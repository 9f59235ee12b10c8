//! TIM1 as the spindle/laser PWM output on PA8 (RM0008 §14): PSC, ARR, CCR1, CCMR1, CCER,
//! BDTR, CR1, EGR. No interrupts, no counter reads: what the bench needs is the duty cycle the
//! pin carries over time. For `mcu.rs`.
//!
//! The output is on when the counter runs (CR1.CEN), channel 1 is in PWM mode 1
//! (CCMR1.OC1M = 110), enabled (CCER.CC1E) and the main output is on (BDTR.MOE); its duty is
//! then `min(CCR1, ARR + 1) / (ARR + 1)`, otherwise 0. PSC always, ARR with CR1.ARPE and CCR1
//! with CCMR1.OC1PE take effect at the next update event (the counter wrapping, or EGR.UG), as
//! on silicon; the timer clock is the core clock (APB2 at 72 MHz).

use serde::Serialize;

/// One change of the PWM output: from `cycle` on, `duty` (0..=1) at `hz`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PwmChange {
    pub cycle: u64,
    pub duty: f64,
    pub hz: f64,
}

/// The values an update event loads (the "shadow" registers) and the output's gating bits.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Active {
    psc: u32,
    arr: u32,
    ccr1: u32,
}

/// TIM1's model.
#[derive(Clone, Debug, Default)]
pub struct Pwm {
    psc: u32,
    arr: u32,
    ccr1: u32,
    ccmr1: u32,
    ccer: u32,
    bdtr: u32,
    cr1: u32,
    active: Active,
    /// Cycle of the last update event (the counter is 0 there).
    epoch: u64,
    /// Output changes, in time order.
    pub changes: Vec<PwmChange>,
}

impl Pwm {
    // counter period in cycles
    fn period(&self) -> u64 {
        (self.active.psc as u64 + 1) * (self.active.arr as u64 + 1)
    }

    fn running(&self) -> bool {
        self.cr1 & 1 != 0
    }

    // the output's (duty, frequency) now
    fn output(&self) -> (f64, f64) {
        let on = self.running() && (self.ccmr1 >> 4) & 7 == 6 && self.ccer & 1 != 0 && self.bdtr & (1 << 15) != 0;
        let top = self.active.arr as f64 + 1.0;
        let hz = super::clock::HZ as f64 / self.period() as f64;
        if on { ((self.active.ccr1 as f64).min(top) / top, hz) } else { (0.0, hz) }
    }

    fn record(&mut self, cycle: u64) {
        let (duty, hz) = self.output();
        let last = self.changes.last().map(|c| (c.duty, c.hz));
        if last != Some((duty, hz)) && !(last.is_none() && duty == 0.0) {
            self.changes.push(PwmChange { cycle, duty, hz });
        }
    }

    // update events up to cycle `t`: the first one loads the preloaded values
    pub fn advance(&mut self, t: u64) {
        if !self.running() {
            return;
        }
        let at = self.epoch + self.period();
        if at <= t {
            self.load();
            self.record(at);
            // Later wraps (with the period just loaded) load nothing new.
            self.epoch = at + (t - at) / self.period() * self.period();
        }
    }

    // an update event: preloaded registers take effect
    fn load(&mut self) {
        self.active = Active { psc: self.psc, arr: self.arr, ccr1: self.ccr1 };
    }

    // register read at `offset`
    pub fn read(&self, offset: u32) -> u32 {
        match offset {
            0x00 => self.cr1,
            0x18 => self.ccmr1,
            0x20 => self.ccer,
            0x28 => self.psc,
            0x2C => self.arr,
            0x34 => self.ccr1,
            0x44 => self.bdtr,
            _ => 0,
        }
    }

    // register write at `offset`, cycle `t` (`v` already merged for sub-word stores)
    pub fn write(&mut self, offset: u32, v: u32, t: u64) {
        self.advance(t);
        let was_running = self.running();
        match offset {
            0x00 => self.cr1 = v & 0x3FF,
            0x14 if v & 1 != 0 => {
                self.load();
                self.epoch = t;
            }
            0x18 => self.ccmr1 = v,
            0x20 => self.ccer = v,
            0x28 => self.psc = v & 0xFFFF,
            0x2C => {
                self.arr = v & 0xFFFF;
                if self.cr1 & (1 << 7) == 0 {
                    self.active.arr = self.arr;
                }
            }
            0x34 => {
                self.ccr1 = v & 0xFFFF;
                if self.ccmr1 & (1 << 3) == 0 {
                    self.active.ccr1 = self.ccr1;
                }
            }
            0x44 => self.bdtr = v,
            _ => {}
        }
        if !was_running && self.running() {
            self.epoch = t;
        }
        self.record(t);
    }

    /// Duty cycle of the output at `cycle` (0 before the first change).
    pub fn duty_at(&self, cycle: u64) -> f64 {
        self.changes.iter().take_while(|c| c.cycle <= cycle).last().map_or(0.0, |c| c.duty)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preloaded_compare_takes_effect_at_the_next_update() {
        let mut p = Pwm::default();
        // 72 MHz / (2 · 36 000) = 1 kHz; PWM mode 1 with preload, channel and MOE on.
        p.write(0x28, 1, 0);
        p.write(0x2C, 35_999, 0);
        p.write(0x18, 0x68, 0);
        p.write(0x20, 1, 0);
        p.write(0x44, 1 << 15, 0);
        p.write(0x14, 1, 0);
        p.write(0x00, 0x81, 100);
        assert!(p.changes.is_empty(), "CCR1 = 0: no output yet");
        p.write(0x34, 18_000, 1_000);
        assert!(p.changes.is_empty(), "preloaded until the update");
        p.write(0x34, 9_000, 80_000); // after the update at 100 + 72 000
        assert_eq!(p.changes, [PwmChange { cycle: 72_100, duty: 0.5, hz: 1000.0 }]);
        p.write(0x44, 0, 300_000);
        assert_eq!(p.changes.len(), 3, "{:?}", p.changes);
        assert_eq!(p.changes[1], PwmChange { cycle: 144_100, duty: 0.25, hz: 1000.0 });
        assert_eq!(p.changes[2].duty, 0.0);
        assert_eq!(p.duty_at(100_000), 0.5);
    }
}
