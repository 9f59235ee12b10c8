//! The engine's ramp half (the TIM4 vector the step interrupt pends at each ramp millisecond,
//! trigger and move start): its modeled cycles per millisecond of motion on a ramp-heavy job,
//! in trapezoid mode (`$41=0`) or S-curve mode (`$41=1`, every ramp leg mapped through the
//! logistic in the ramp half, `src/motion/ramp/scurve.rs`).
//!
//! Who uses it: `cargo bench --bench ramp_half` and the sweep's bench/RESULTS.md.

use anyhow::{ensure, Result};

use super::nvic::IRQ0;
use super::{Board, HZ};

/// TIM4's IRQ number: the ramp half's vector (`src/firmware/step.rs`).
pub const TIM4_IRQ: u32 = 30;

/// The job: one long move, then short ones there and back (every one all ramps).
pub const JOB: &str = "`$100=100 $110=36000 $120=2000`, `G91`, `G1 X60 F3000`, then 10 × (`G1 X3 F6000`, `G1 X-3 F6000`)";

/// What one run measured.
#[derive(Clone, Copy, Debug)]
pub struct RampHalf {
    /// First to last pin edge of the job, ms.
    pub ms: f64,
    /// Modeled cycles in the ramp half's vector over the job.
    pub cycles: u64,
}

impl RampHalf {
    /// Modeled cycles per millisecond of motion.
    pub fn per_ms(&self) -> f64 {
        self.cycles as f64 / self.ms
    }
}

/// Runs [`JOB`] with `$41=shape` on a freshly booted `board`.
pub fn measure(board: &mut Board, shape: u8) -> Result<RampHalf> {
    let b = board;
    b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl"))?;
    for l in ["$100=100", "$110=36000", "$120=2000", &format!("$41={shape}"), "G91"] {
        b.send_line_wait_ok(l)?;
    }
    b.set_profile(true);
    let from = b.edges().len();
    b.send_line_wait_ok("G1 X60 F3000")?;
    for _ in 0..10 {
        b.send_line_wait_ok("G1 X3 F6000")?;
        b.send_line_wait_ok("G1 X-3 F6000")?;
    }
    ensure!(b.run_until_quiet(HZ / 5, 10 * HZ)?, "motion did not end");
    let cycles = b.profile(IRQ0 + TIM4_IRQ).iter().map(|f| f.cycles).sum();
    b.set_profile(false);
    let e = &b.edges()[from..];
    ensure!(e.len() > 1, "no motion");
    Ok(RampHalf { ms: (e[e.len() - 1].cycle - e[0].cycle) as f64 / (HZ / 1000) as f64, cycles })
}
