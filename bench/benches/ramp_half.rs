//! The engine's ramp half on the virtual bench: its modeled cycles per millisecond of motion in
//! trapezoid mode (`$41=0`) and S-curve mode (`$41=1`) on a ramp-heavy job
//! (`ddastep_bench::emu::ramp_half`).
//!
//! `cargo bench -p ddastep-bench --target host-tuple --bench ramp_half` (about 10 s).

use ddastep_bench::emu::{firmware_elf, ramp_half, Board, HZ};

fn main() -> anyhow::Result<()> {
    if !std::env::args().any(|a| a == "--bench") {
        return Ok(());
    }
    println!("ramp half (TIM4 vector), modeled cycles; job: {}", ramp_half::JOB);
    for shape in [0, 1] {
        let mut b = Board::load(firmware_elf()?)?;
        let r = ramp_half::measure(&mut b, shape)?;
        println!(
            "$41={shape} ({}): {:.0} ms of motion, {} cycles in the ramp half: {:.0} modeled cycles per ms ({:.2} % of the CPU)",
            if shape == 0 { "trapezoid" } else { "S-curve" },
            r.ms,
            r.cycles,
            r.per_ms(),
            r.per_ms() / (HZ / 1000) as f64 * 100.0
        );
    }
    Ok(())
}
