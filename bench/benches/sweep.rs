//! The step-rate sweep on the virtual bench (the same as `cargo sim -- --sweep`): highest
//! sustainable master rate and CPU load per axis count, in modeled cycles. Prints the table;
//! `cargo sim -- --sweep --results bench/RESULTS.md` also writes the results file.
//!
//! `cargo bench -p ddastep-bench --target host-tuple --bench sweep` (about a minute per mode: single-edge, then
//! dual-edge `$580=1`).

use ddastep_bench::emu::{firmware_elf, sweep};

fn main() -> anyhow::Result<()> {
    // `cargo bench` passes --bench; `cargo test --all-targets` runs this without it: skip the
    // minute-long sweep there.
    if !std::env::args().any(|a| a == "--bench") {
        return Ok(());
    }
    let elf = firmware_elf()?;
    for dual_edge in [false, true] {
        let s = sweep::sweep(&elf, &sweep::Options { mode: sweep::Mode { dual_edge, dma: false }, ..Default::default() })?;
        let mode = if dual_edge { "dual-edge, $580=1" } else { "single-edge" };
        println!("max step rate ($I with the sweep settings, {mode}): {} Hz", s.cap_hz);
        print!("{}", s.table());
        println!("{} points in {:.1} s wall", s.points, s.wall_s);
    }
    Ok(())
}
