//! Planner throughput on the virtual bench: modeled cycles per streamed G1 line (parsing,
//! planning, look-ahead, feeder: everything outside interrupts) with the look-ahead full, and
//! the step interrupt's mean and max during back-to-back moves at speed. 300 segments of
//! 0.1–0.5 mm at F3000 sent like a sender (line, wait for `ok`) at 115200 baud.
//!
//! `cargo bench -p ddastep-bench --target host-tuple --bench plan_line` (about 20 s).
//!
//! Where the parse + plan cycles go: `-- --profile` adds the functions by exclusive cycles
//! per line inside `gcode` and `push`; `-- --time NAME` (repeatable; a demangled name with
//! generics as `<_>`, as the profile prints it) adds a function's inclusive cycles per line
//! and its callers.

use ddastep_bench::emu::{firmware_elf, stream, Board, HZ};

fn main() -> anyhow::Result<()> {
    if !std::env::args().any(|a| a == "--bench") {
        return Ok(());
    }
    let mut b = Board::load(firmware_elf()?)?;
    b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl"))?;
    let args: Vec<String> = std::env::args().collect();
    let extra: Vec<&str> = args.windows(2).filter(|w| w[0] == "--time").map(|w| w[1].as_str()).collect();
    let (r, why) = stream::stream_segments_profiled(&mut b, 300, 0x2545_F491_4F6C_DD1D, &extra)?;
    println!("{} lines of 0.1-0.5 mm at F3000 in {:.3} s of motion (modeled)", r.lines, r.seconds);
    println!(
        "thread mode per line: {:.0} modeled cycles = {:.3} ms at 72 MHz",
        r.thread_cycles_per_line,
        r.thread_cycles_per_line / 72_000.0
    );
    let p = &r.plan;
    println!(
        "parse + plan per line, look-ahead full ({} lines): mean {:.0} modeled cycles = {:.3} ms; longest parse {} ({:.3} ms), longest push {} ({:.3} ms)",
        p.lines,
        p.mean,
        p.mean / 72_000.0,
        p.max_parse,
        p.max_parse as f64 / 72_000.0,
        p.max_push,
        p.max_push as f64 / 72_000.0
    );
    println!(
        "step ISR at speed: mean {:.1}, max {} modeled cycles (max/mean {:.2}), {} entries",
        r.isr.mean_cycles,
        r.isr.max_cycles,
        r.isr.max_cycles as f64 / r.isr.mean_cycles.max(1.0),
        r.isr.entries
    );
    println!("10 ms windows without a step while streaming: {}", r.starved_windows);
    let per_line = |c: u64| c as f64 / p.lines.max(1) as f64;
    for (i, (name, calls, cycles)) in why.inclusive.iter().enumerate() {
        println!("inclusive: {:>8.0} cycles per line ({:>5.1} %), {calls} calls: {name}", per_line(*cycles), per_line(*cycles) / p.mean * 100.0);
        for (_, caller, n, c) in why.callers.iter().filter(|c| c.0 == i).take(12) {
            println!("    {:>8.0} per line, {n} calls, from {caller}", per_line(*c));
        }
    }
    if args.iter().any(|a| a == "--profile") {
        println!("parse + plan by function (exclusive, modeled cycles per line, share):");
        for f in why.functions.iter().take(40) {
            println!("{:>8.0} {:>5.1} % {}", per_line(f.cycles), f.share * 100.0, f.function);
        }
    }
    Ok(())
}
