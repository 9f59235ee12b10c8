//! What every sweep point sets up: the step ratio, the sweep's settings lines and the step
//! output mode. A leaf: the measurement, the search, and `emu/changes.rs` (the move-change
//! benchmark on the same settings) import it.

use serde::Serialize;

/// Steps per axis per 10 master steps: X:Y:Z:A:B:C:U = 10:6:4:8:2:7:5 (the paper's 5:3:2 first).
pub const RATIO: [u64; 7] = [10, 6, 4, 8, 2, 7, 5];
/// Steps/mm the sweep leaves at its default.
pub(crate) const STEPS_PER_MM: f64 = 100.0;
/// `$120..126` for the sweep, mm/s² (10⁸ master steps/s²: 500 kHz in 5 ms).
const ACCEL_MM_S2: f64 = 1_000_000.0;
/// `$110..126` for the sweep, mm/min (1 MHz at 100 steps/mm: never the limit).
const MAX_RATE_MM_MIN: f64 = 600_000.0;
/// `$0` for the sweep, µs. The firmware's cap (`Timing::max_rate_for`, src/motion/timing.rs)
/// combines the pulse rule (2 × pulse + 72 ticks) with the step handler's measured cost; the
/// search runs up to whatever `$I` reports for it.
pub const PULSE_US: f64 = 0.5;

/// How the firmware puts out steps: interrupt mode (the default), dual-edge (`$580=1`), DMA
/// burst (`$581=1`), or both.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Mode {
    /// Every step toggles its pin.
    pub dual_edge: bool,
    /// DMA stores the buffered words at TIM2's events; the step path is the buffer fill.
    pub dma: bool,
}

impl Mode {
    /// The settings that select it (each applies in place).
    pub(super) fn lines(self) -> Vec<&'static str> {
        let mut v = Vec::new();
        if self.dual_edge {
            v.push("$580=1");
        }
        if self.dma {
            v.push("$581=1");
        }
        v
    }

    /// How tables and logs name it.
    pub fn label(self) -> &'static str {
        match (self.dual_edge, self.dma) {
            (false, false) => "interrupt",
            (true, false) => "dual-edge",
            (false, true) => "DMA",
            (true, true) => "DMA dual-edge",
        }
    }
}

// the settings lines every point sends (after reset)
pub fn settings_lines() -> Vec<String> {
    // All seven axes ($42), at the sweep's steps/mm (the defaults are a 3-axis gantry's).
    let mut v = vec![format!("$0={PULSE_US}"), "$41=0".to_string(), "$40=1000".to_string(), "$42=7".to_string()];
    for i in 0..7 {
        v.push(format!("$10{i}={STEPS_PER_MM}"));
        v.push(format!("$11{i}={MAX_RATE_MM_MIN}"));
        v.push(format!("$12{i}={ACCEL_MM_S2}"));
    }
    v
}
