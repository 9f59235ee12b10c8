//! `cargo sim -- [ARGS]`: run the release firmware on the emulated Blue Pill, stream G-code
//! over USART1 (or USB, `--usb`), and print the summary (optionally VCD and JSON); or, with `--serve`, serve the
//! board to a real G-code sender in real time (pseudo-terminal, TCP). See bench/README.md.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Parser;
use ddastep_bench::emu::sender::{stream_char_count, stream_wait_ok, Link};
use ddastep_bench::emu::{firmware_elf, gcode_lines, isr_profile, sweep, Board, InputFlip, Port, HZ};
use ddastep_bench::machine::{MachineSpec, VirtualMachine};
use ddastep_bench::serve;

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
    /// Stop after this many simulated seconds (default 60; with --serve: until Ctrl-C).
    #[arg(long)]
    max_seconds: Option<f64>,
    /// Stream --gcode over the board's own USB port: the modeled host enumerates it as Linux
    /// does and opens the port first (the firmware needs the `usb` feature, on by default). With
    /// --serve: the pty/TCP clients talk to the USB port instead of USART1.
    #[arg(long, conflicts_with_all = ["sweep", "point"])]
    usb: bool,
    /// With --usb: pull the cable at AT_S simulated seconds and plug it back at REPLUG_S.
    #[arg(long, requires = "usb", value_name = "AT_S[,REPLUG_S]")]
    unplug: Option<String>,
    /// Stream with Grbl's character counting (lines in flight up to the 128-byte RX buffer)
    /// instead of waiting for each `ok`; over USART1, or USB with --usb.
    #[arg(long, conflicts_with_all = ["sweep", "point", "serve"])]
    char_count: bool,
    /// Serve the board to a G-code sender in real time: USART1 on a pseudo-terminal (prints
    /// `serial: /dev/pts/N`) until Ctrl-C or --max-seconds.
    #[arg(long, conflicts_with_all = ["gcode", "sweep", "point", "profile"])]
    serve: bool,
    /// With --serve: also make a symlink to the pseudo-terminal, e.g. /tmp/ttyBLUEPILL.
    #[arg(long, requires = "serve", value_name = "PATH")]
    pty_link: Option<PathBuf>,
    /// With --serve: also listen on a TCP address, e.g. 127.0.0.1:23000.
    #[arg(long, requires = "serve", value_name = "ADDR")]
    tcp: Option<String>,
    /// Input flips, e.g. PA0@0.25=0 (pin PA0 low at 0.25 s simulated).
    #[arg(long)]
    pin: Vec<String>,
    /// Wire a virtual machine to the pins: carriages that follow the steps and limit switches
    /// on PA0-PA2 (TOML; sample bench/demo/gantry300.toml, format in bench/src/machine.rs).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["sweep", "point"])]
    machine: Option<PathBuf>,
    /// Print where the step interrupt's modeled cycles go (per function and per block).
    #[arg(long)]
    profile: bool,
    /// Step-rate sweep: max sustainable master rate and CPU load per axis count (see
    /// bench/README.md); prints a table.
    #[arg(long)]
    sweep: bool,
    /// With --sweep: write bench/RESULTS.md-style results to this file.
    #[arg(long)]
    results: Option<PathBuf>,
    /// With --sweep: rewrite the measured rows of this page's "Figures" table (docs/performance.md).
    #[arg(long)]
    readme: Option<PathBuf>,
    /// With --sweep: axis counts, e.g. 1,3,7 (default 1..=7).
    #[arg(long, value_delimiter = ',')]
    axes: Vec<usize>,
    /// With --sweep: worker threads.
    #[arg(long, default_value_t = 2)]
    jobs: usize,
    /// With --results: how to describe the firmware (default: the last commit of src/, marked when
    /// src/ has uncommitted changes).
    #[arg(long)]
    firmware_label: Option<String>,
    /// The floor of a one-axis step handler: a hand-scheduled one doing only what interrupt
    /// mode's plain step must, and without its optional parts (bench/src/emu/floor.rs).
    #[arg(long, conflicts_with_all = ["gcode", "sweep", "point", "serve"])]
    floor: bool,
    /// One sweep point, AXES@HZ (e.g. 7@200000), with the step-ISR profile of its cruise.
    #[arg(long)]
    point: Option<String>,
    /// With --sweep or --point: dual-edge step mode (`$580=1`, each step toggles its pin).
    /// With --results the sweep runs every mode and the file shows them side by side.
    #[arg(long)]
    dual_edge: bool,
    /// The emulated part's flash size register (F_SIZE, KiB; default 64; 65535 reads as
    /// unknown): the chip check at boot refuses motion below 64.
    #[arg(long, value_name = "KIB", conflicts_with_all = ["sweep", "point", "floor"])]
    flash_kib: Option<u16>,
    /// The emulated part's 96-bit unique ID, 24 hex digits (the words in address order).
    #[arg(long, value_name = "HEX", conflicts_with_all = ["sweep", "point", "floor"])]
    uid: Option<String>,
    /// The emulated part's CPUID, hex (default 411FC231: Cortex-M3 r1p1).
    #[arg(long, value_name = "HEX", conflicts_with_all = ["sweep", "point", "floor"])]
    cpuid: Option<String>,
    /// With --sweep or --point: DMA burst step output (`$581=1`; the step path is the buffer
    /// fill, DMA1 channel 1's interrupt).
    #[arg(long)]
    dma: bool,
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

// the emulated part: the Blue Pill's registers with the arguments' changes
fn chip(args: &Args) -> Result<ddastep::grbl::chip::Chip> {
    let mut c = ddastep_bench::emu::BLUE_PILL;
    if let Some(k) = args.flash_kib {
        c.flash_kib = k;
    }
    if let Some(u) = &args.uid {
        let u = u.replace('-', "");
        if u.len() != 24 || !u.is_ascii() {
            bail!("--uid: expected 24 hex digits, got {}", u.len());
        }
        for (i, w) in c.uid.iter_mut().enumerate() {
            *w = u32::from_str_radix(&u[8 * i..8 * i + 8], 16).context("--uid: not hex")?;
        }
    }
    if let Some(v) = &args.cpuid {
        c.cpuid = u32::from_str_radix(v.trim_start_matches("0x"), 16).context("--cpuid: not hex")?;
    }
    Ok(c)
}

// run, and on failure say why in one line (exit 1); usage errors exit 2 (clap)
fn main() -> std::process::ExitCode {
    match run(Args::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("sim: error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> Result<()> {
    if args.floor {
        print!("{}", ddastep_bench::emu::floor::markdown(&ddastep_bench::emu::floor::measure()?));
        return Ok(());
    }
    let elf = match args.elf.clone() {
        Some(p) => p,
        None => firmware_elf()?,
    };
    if args.sweep {
        return run_sweep(&args, &elf);
    }
    let machine = args.machine.as_deref().map(MachineSpec::load).transpose()?;
    let part = chip(&args)?;
    if args.serve {
        let opts = serve::Options {
            elf,
            pty_link: args.pty_link.clone(),
            tcp: args.tcp.clone(),
            max_seconds: args.max_seconds,
            vcd: args.vcd.clone(),
            json: args.json.clone(),
            inputs: args.pin.iter().map(|p| parse_pin(p)).collect::<Result<_>>()?,
            machine,
            usb: args.usb,
            chip: Some(part),
        };
        let s = serve::run(&opts)?;
        println!(
            "served {:.3} s simulated in {:.3} s wall{}",
            s.simulated_s,
            s.wall_s,
            if s.lagged_s > 0.0 { format!(" (the host fell {:.3} s behind real time)", s.lagged_s) } else { String::new() }
        );
        return Ok(());
    }
    if let Some(spec) = &args.point {
        let (axes, hz) = spec.split_once('@').context("expected AXES@HZ")?;
        let mode = sweep::Mode { dual_edge: args.dual_edge, dma: args.dma };
        let p = sweep::run_point(&elf, axes.parse()?, hz.parse()?, 20, 0.95, true, mode);
        println!("{}", sweep::point_line(&p));
        let entries = p.isr_entries.max(1) as f64;
        println!("step ISR profile over the measured cruise ({} entries, {:.1} cycles per master step):", p.isr_entries, p.isr_cycles_per_step);
        for f in &p.profile {
            println!("  {:>5.1}% {:>8.1} cycles/entry  {}", f.share * 100.0, f.cycles as f64 / entries, f.function);
        }
        println!("by block (cycles per entry, cycles per run):");
        for (name, runs, cycles) in p.profile_blocks.iter().take(20) {
            println!("  {:>8.1} {:>6.1}  {name}", *cycles as f64 / entries, *cycles as f64 / (*runs).max(1) as f64);
        }
        println!("thread mode over the same stretch (cycles per step-ISR entry):");
        for f in p.profile_thread.iter().take(8) {
            println!("  {:>5.1}% {:>8.1}  {}", f.share * 100.0, f.cycles as f64 / entries, f.function);
        }
        return Ok(());
    }
    let gcode_path = args.gcode.unwrap_or_else(|| ddastep_bench::emu::repo_root().join("bench/demo/paper_532.gcode"));
    let gcode = std::fs::read_to_string(&gcode_path).with_context(|| format!("reading {}", gcode_path.display()))?;
    let mut board = Board::load(&elf)?;
    board.set_chip(&part)?;
    if let Some(m) = &machine {
        board.attach_plant(Box::new(VirtualMachine::new(m)));
    }
    board.set_profile(args.profile);
    for p in &args.pin {
        board.schedule_input(parse_pin(p)?);
    }
    let limit = (args.max_seconds.unwrap_or(60.0) * HZ as f64) as u64;
    let wall = std::time::Instant::now();
    board.run_seconds(0.05)?; // boot
    if args.usb {
        board.usb_connect(2 * HZ)?;
        board.run_seconds(0.01)?; // the banner
        if let Some(spec) = &args.unplug {
            let mut t = spec.split(',').map(|v| v.trim().parse::<f64>().map(|s| (s * HZ as f64) as u64));
            let at = t.next().context("--unplug AT_S[,REPLUG_S]")??;
            board.usb_unplug_at(at, t.next().transpose()?);
        }
    }
    let sender_lines = if args.usb || args.char_count { gcode_lines(&gcode) } else { Vec::new() };
    if !sender_lines.is_empty() {
        let link = if args.usb { Link::Usb } else { Link::Usart };
        let wait = limit.saturating_sub(board.cycles()).max(1);
        let replies = if args.char_count {
            stream_char_count(&mut board, link, &sender_lines, wait)
        } else {
            stream_wait_ok(&mut board, link, &sender_lines, wait)
        };
        match replies {
            Ok(replies) => {
                let errors = replies.iter().filter(|r| r.starts_with("error")).count();
                eprintln!(
                    "[{:9.4} s] {} lines over {link:?}{}: {} ok, {errors} error",
                    board.seconds(),
                    replies.len(),
                    if args.char_count { " (character counting)" } else { "" },
                    replies.len() - errors
                );
            }
            Err(e) => eprintln!("[{:9.4} s] {e:#}", board.seconds()),
        }
    }
    for line in gcode_lines(&gcode).into_iter().filter(|_| !args.usb && !args.char_count) {
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
    // The firmware's own DWT timing of its step path over the run (what `$I` gives on a board).
    if let Ok(info) = board.send_line_wait_ok("$I") {
        info.lines().filter(|l| l.contains("step isr") || l.contains("chip flash")).for_each(|l| println!("firmware self-report: {l}"));
    }
    if let Some(vm) = VirtualMachine::of(&board) {
        println!("{}", vm.summary());
    }
    if args.profile {
        print!("{}", isr_profile(&board, 12));
    }
    println!("wall {:.2} s for {:.3} s simulated", wall.elapsed().as_secs_f64(), board.seconds());
    if let Some(p) = args.vcd {
        board.write_vcd(&p)?;
    }
    if let Some(p) = args.json {
        std::fs::write(&p, serde_json::to_string_pretty(&report)?)?;
    }
    Ok(())
}

// the step-rate sweep: table on stdout, progress on stderr, optionally the results file
fn run_sweep(args: &Args, elf: &std::path::Path) -> Result<()> {
    let mode = if args.results.is_none() { sweep::Mode { dual_edge: args.dual_edge, dma: args.dma } } else { sweep::Mode::default() };
    let mut opts = sweep::Options { jobs: args.jobs, mode, ..Default::default() };
    if !args.axes.is_empty() {
        opts.axes = args.axes.clone();
    }
    let s = sweep::sweep(elf, &opts)?;
    println!("max step rate ($I with the sweep settings, {} mode): {} Hz", mode.label(), s.cap_hz);
    print!("{}", s.table());
    println!("{} points in {:.1} s wall", s.points, s.wall_s);
    if let Some(p) = &args.results {
        let mut others = Vec::new();
        for m in [sweep::Mode { dual_edge: true, dma: false }, sweep::Mode { dual_edge: false, dma: true }, sweep::Mode { dual_edge: true, dma: true }] {
            let o = sweep::sweep(elf, &sweep::Options { mode: m, ..opts.clone() })?;
            println!("{} mode: max step rate {} Hz", m.label(), o.cap_hz);
            print!("{}", o.table());
            others.push(o);
        }
        let command = std::env::args().skip(1).collect::<Vec<_>>().join(" ");
        let label = args.firmware_label.clone().unwrap_or_else(sweep::firmware_commit);
        std::fs::write(p, sweep::results_markdown(&s, &others, &format!("cargo sim -- {command}"), &label, elf)?)?;
        eprintln!("wrote {}", p.display());
    }
    if let Some(p) = &args.readme {
        ddastep_bench::emu::figures::update_readme(p, &s, elf)?;
        eprintln!("rewrote the figures rows of {}", p.display());
    }
    Ok(())
}
