//! `cargo sim -- [ARGS]`: run the release firmware on the emulated Blue Pill, stream G-code
//! over USART1, and print the summary (optionally VCD and JSON). See bench/README.md.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Parser;
use ddastep_bench::emu::{firmware_elf, gcode_lines, Board, InputFlip, Port, HZ};

#[derive(Parser)]
#[command(about = "Run the ddastep firmware ELF on an emulated Blue Pill (modeled cycles at 72 MHz)")]
struct Args {
    /// Firmware ELF (default: build and use the release ELF).
    #[arg(long)]
    elf: Option<PathBuf>,
    /// G-code streamed over USART1 (default: bench/demo/paper_532.gcode).
    #[arg(long)]
    gcode: Option<PathBuf>,
    /// Write a VCD of the step/dir/enable pins.
    #[arg(long)]
    vcd: Option<PathBuf>,
    /// Write the JSON report.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Stop after this many simulated seconds.
    #[arg(long, default_value_t = 60.0)]
    max_seconds: f64,
    /// Input flips, e.g. PA0@0.25=0 (pin PA0 low at 0.25 s simulated).
    #[arg(long)]
    pin: Vec<String>,
}

// parse "PA0@0.25=0"
fn parse_pin(s: &str) -> Result<InputFlip> {
    let (pin, rest) = s.split_once('@').context("expected PIN@SECONDS=LEVEL")?;
    let (t, level) = rest.split_once('=').context("expected PIN@SECONDS=LEVEL")?;
    let port = match pin.get(..2) {
        Some("PA") => Port::A,
        Some("PB") => Port::B,
        Some("PC") => Port::C,
        _ => bail!("unknown port in {pin}"),
    };
    let n: u8 = pin[2..].parse()?;
    let t: f64 = t.parse()?;
    Ok(InputFlip { cycle: (t * HZ as f64) as u64, port, pin: n, level: level == "1" })
}

fn main() -> Result<()> {
    let args = Args::parse();
    let elf = match args.elf {
        Some(p) => p,
        None => firmware_elf()?,
    };
    let gcode_path = args.gcode.unwrap_or_else(|| ddastep_bench::emu::repo_root().join("bench/demo/paper_532.gcode"));
    let gcode = std::fs::read_to_string(&gcode_path).with_context(|| format!("reading {}", gcode_path.display()))?;
    let mut board = Board::load(&elf)?;
    for p in &args.pin {
        board.schedule_input(parse_pin(p)?);
    }
    let limit = (args.max_seconds * HZ as f64) as u64;
    let wall = std::time::Instant::now();
    board.run_seconds(0.05)?; // boot
    for line in gcode_lines(&gcode) {
        if board.cycles() >= limit {
            eprintln!("stopped at --max-seconds");
            break;
        }
        match board.send_line_wait_ok_within(&line, limit.saturating_sub(board.cycles()).max(1)) {
            Ok(reply) => eprintln!("[{:9.4} s] {line} -> {}", board.seconds(), reply.trim_end().replace('\n', " | ")),
            Err(e) => eprintln!("[{:9.4} s] {e:#}", board.seconds()),
        }
    }
    // Let the motion finish: run until no step/dir edge for 100 ms, with progress.
    loop {
        let last = board.edges().last().map_or(0, |e| e.cycle);
        if board.cycles() >= limit || board.cycles() > last + HZ / 10 {
            break;
        }
        board.run_for(HZ / 20)?;
        eprint!("\r{:.2} s simulated, {:.1} s wall", board.seconds(), wall.elapsed().as_secs_f64());
    }
    eprintln!();
    let report = board.report();
    println!("{report}");
    println!("wall {:.2} s for {:.3} s simulated", wall.elapsed().as_secs_f64(), board.seconds());
    if let Some(p) = args.vcd {
        board.write_vcd(&p)?;
    }
    if let Some(p) = args.json {
        std::fs::write(&p, serde_json::to_string_pretty(&report)?)?;
    }
    Ok(())
}
