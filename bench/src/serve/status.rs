//! The live status line of `--serve`: simulated time, machine position (steps counted on the
//! step/dir pins, dir low = +), the fastest axis's step rate, modeled CPU load, how far the
//! host lags real time, and who is connected. For the serve loop.

use crate::emu::{PinEdge, AXES, DIR_LOW_IS_POSITIVE, DIR_PINS, HZ, STEP_PINS};

/// Rates are counted in bins of 10 ms of simulated time.
const BIN: u64 = HZ / 100;

/// Step counting from pin edges, fed in time order.
#[derive(Default)]
pub struct Position {
    pub steps: [i64; 7],
    dir_high: [bool; 7],
    /// The current 10 ms bin, its rising step edges per axis, and the busiest bin's count
    /// (any axis) since the last `rate_hz` call.
    bin: u64,
    count: [u64; 7],
    peak: u64,
}

impl Position {
    // count the step and dir edges of port B
    pub fn feed(&mut self, edges: &[PinEdge]) {
        for e in edges.iter().filter(|e| e.port == 1) {
            if let Some(a) = DIR_PINS.iter().position(|&p| p == e.pin) {
                self.dir_high[a] = e.level;
            } else if let Some(a) = STEP_PINS.iter().position(|&p| p == e.pin) {
                if e.level {
                    let plus = self.dir_high[a] != DIR_LOW_IS_POSITIVE;
                    self.steps[a] += if plus { 1 } else { -1 };
                    if e.cycle / BIN != self.bin {
                        self.close_bin();
                        self.bin = e.cycle / BIN;
                    }
                    self.count[a] += 1;
                }
            }
        }
    }

    // fold the current bin into the peak
    fn close_bin(&mut self) {
        self.peak = self.peak.max(self.count.iter().copied().max().unwrap_or(0));
        self.count = [0; 7];
    }

    // the fastest axis's step rate in the busiest 10 ms since the last call (then restart)
    pub fn rate_hz(&mut self) -> f64 {
        self.close_bin();
        let peak = std::mem::take(&mut self.peak);
        (peak * HZ / BIN) as f64
    }

    // "X+5000 Y+3000 Z+2000" (axes that moved; "X0" when none has)
    pub fn text(&self) -> String {
        let moved: Vec<String> = AXES
            .iter()
            .zip(self.steps)
            .filter(|(_, s)| *s != 0)
            .map(|(a, s)| format!("{a}{s:+}"))
            .collect();
        if moved.is_empty() {
            "X0".into()
        } else {
            moved.join(" ")
        }
    }
}

// "50.0 kHz" / "0 Hz"
pub fn rate_text(hz: f64) -> String {
    if hz >= 1000.0 {
        format!("{:.1} kHz", hz / 1000.0)
    } else {
        format!("{hz:.0} Hz")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // a step pulse on axis `a` at cycle `t`
    fn step(a: usize, t: u64) -> [PinEdge; 2] {
        [
            PinEdge { cycle: t, port: 1, pin: STEP_PINS[a], level: true },
            PinEdge { cycle: t + 100, port: 1, pin: STEP_PINS[a], level: false },
        ]
    }

    #[test]
    fn steps_follow_the_dir_pin_and_rate_counts_the_window() {
        let mut p = Position::default();
        for k in 0..10 {
            p.feed(&step(0, k * 1000));
        }
        // dir high on Y = negative with Grbl's dir-low-positive convention
        p.feed(&[PinEdge { cycle: 20_000, port: 1, pin: DIR_PINS[1], level: true }]);
        for k in 0..4 {
            p.feed(&step(1, 30_000 + k * 1000));
        }
        // port A edges (inputs, LED on C) do not count
        p.feed(&[PinEdge { cycle: 40_000, port: 0, pin: STEP_PINS[0], level: true }]);
        assert_eq!(&p.steps[..2], &[10, -4]);
        assert_eq!(p.text(), "X+10 Y-4");
        // 10 X steps 1000 cycles apart: all in one 10 ms bin -> 1 kHz
        assert_eq!(p.rate_hz(), 1000.0);
        assert_eq!(p.rate_hz(), 0.0);
        assert_eq!(rate_text(50_000.0), "50.0 kHz");
    }
}
