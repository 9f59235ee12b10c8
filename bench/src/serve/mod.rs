//! `cargo sim -- --serve`: the release firmware on the emulated Blue Pill, paced to wall-clock
//! time (one simulated second per real second), with USART1 on a pseudo-terminal and, with
//! `--tcp`, a TCP socket, so a real G-code sender (UGS, CNCjs, bCNC, stream.py) drives it.
//!
//! The loop: read what clients wrote (Grbl's realtime bytes `?`, `!`, `~`, 0x18 and 0x80–0x9F
//! jump ahead of queued line bytes, so they reach the receiver at the next byte slot; every
//! byte still takes its 10 bit times at the programmed baud rate), run the board in slices of
//! at most 1 ms of simulated time up to the wall clock, pass new TX bytes to the clients, and
//! refresh a status line on stderr (simulated time, position in steps, the fastest axis's
//! step rate in the busiest 10 ms since the last refresh, modeled CPU load). When the emulator falls more than 250 ms behind the wall
//! clock, the lag is dropped (the board goes on from where it is, one second per second) and
//! the status line says the host cannot keep up. Runs until Ctrl-C (SIGINT/SIGTERM) or
//! `max_seconds` of simulated time. Each turn takes the board's pin edges off it: the VCD, if
//! asked, is written as they come, and the JSON's edge figures are kept as they come
//! (`emu/summary.rs`), so memory does not grow with the edges; the JSON is written at the end.

mod pty;
mod record;
mod status;
mod tcp;

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::Result;
use nix::sys::signal::{signal, SigHandler, Signal};

use crate::emu::{Board, InputFlip, HZ};
pub use pty::Pty;
pub use record::Recorder;
pub use status::Position;
pub use tcp::Tcp;

/// How to serve.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Firmware ELF.
    pub elf: PathBuf,
    /// Also make this symlink to the pseudo-terminal.
    pub pty_link: Option<PathBuf>,
    /// Also listen on this TCP address.
    pub tcp: Option<String>,
    /// Stop after this many simulated seconds (default: until Ctrl-C).
    pub max_seconds: Option<f64>,
    pub vcd: Option<PathBuf>,
    pub json: Option<PathBuf>,
    /// Scheduled input changes (simulated time).
    pub inputs: Vec<InputFlip>,
    /// A virtual machine wired to the pins (`--machine`).
    pub machine: Option<crate::machine::MachineSpec>,
    /// Serve the board's USB port instead of USART1 (`--usb`: a modeled host enumerates it
    /// and holds the port open; the firmware needs the `usb` feature, on by default).
    pub usb: bool,
    /// The emulated part's device registers (`--flash-kib`, `--uid`, `--cpuid`; default
    /// `emu::BLUE_PILL`).
    pub chip: Option<ddastep::grbl::chip::Chip>,
}

/// What a finished run did.
#[derive(Clone, Debug)]
pub struct Summary {
    pub simulated_s: f64,
    pub wall_s: f64,
    /// Simulated time the host could not keep up with (dropped lag), seconds.
    pub lagged_s: f64,
    pub steps: [i64; 7],
}

/// Grbl 1.1's realtime commands: acted on when received, never part of a line.
pub fn is_realtime(b: u8) -> bool {
    matches!(b, b'?' | b'!' | b'~' | 0x18 | 0x80..=0x9F)
}

static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: nix::libc::c_int) {
    STOP.store(true, Ordering::SeqCst);
}

// queue client bytes: over USART1 realtime bytes ahead of everything not yet on the wire, the
// rest in order; over USB each read as one write to the tty, in order (as a host sends them)
fn feed(board: &mut Board, bytes: &[u8], usb: bool) {
    if usb {
        board.usb_send(bytes);
        return;
    }
    let (urgent, lines): (Vec<u8>, Vec<u8>) = bytes.iter().partition(|&&b| is_realtime(b));
    if !urgent.is_empty() {
        board.serial_send_urgent(&urgent);
    }
    if !lines.is_empty() {
        board.serial_send(&lines);
    }
}

/// Stderr: a status line redrawn in place on a terminal, else a plain line now and then.
struct Console {
    tty: bool,
    shown: bool,
}

impl Console {
    // a message on its own line (clears the status line first)
    fn note(&mut self, text: &str) {
        let mut e = std::io::stderr().lock();
        if self.tty && self.shown {
            let _ = write!(e, "\r\x1b[K");
        }
        let _ = writeln!(e, "{text}");
        self.shown = false;
    }

    // the status line
    fn status(&mut self, text: &str) {
        let mut e = std::io::stderr().lock();
        let _ = if self.tty { write!(e, "\r{text}\x1b[K") } else { writeln!(e, "{text}") };
        let _ = e.flush();
        self.shown = true;
    }
}

/// Serve the board until Ctrl-C or `max_seconds`.
pub fn run(opts: &Options) -> Result<Summary> {
    // The endpoints first: bad use fails before anything runs.
    let mut pty = Pty::open(opts.pty_link.as_deref())?;
    let mut tcp = opts.tcp.as_deref().map(Tcp::bind).transpose()?;
    let mut board = Board::load(&opts.elf)?;
    if let Some(c) = &opts.chip {
        board.set_chip(c)?;
    }
    if let Some(m) = &opts.machine {
        board.attach_plant(Box::new(crate::machine::VirtualMachine::new(m)));
    }
    for f in &opts.inputs {
        board.schedule_input(*f);
    }
    // The VCD is written as the edges come and the JSON's edge figures kept as they come: the
    // board's edge list is emptied every turn.
    let mut record = Recorder::new(&board, opts.vcd.as_deref(), opts.json.is_some())?;

    println!("serial: {}", pty.path.display());
    if let Some(l) = &opts.pty_link {
        println!("serial link: {} -> {}", l.display(), pty.path.display());
    }
    if let Some(t) = &tcp {
        println!("tcp: {}", t.addr);
    }
    if opts.usb {
        board.usb_plug(true);
        board.usb_open(true);
        println!("115200 8N1 accepted and ignored: the board's USB port (a modeled host enumerates it); simulated time runs at wall-clock pace; Ctrl-C stops");
    } else {
        println!("115200 8N1; simulated time runs at wall-clock pace; Ctrl-C stops");
    }
    std::io::stdout().flush()?;
    STOP.store(false, Ordering::SeqCst);
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
    unsafe {
        signal(Signal::SIGINT, SigHandler::Handler(on_signal))?;
        signal(Signal::SIGTERM, SigHandler::Handler(on_signal))?;
    }

    let mut console = Console { tty: std::io::stderr().is_terminal(), shown: false };
    let status_every = if console.tty { Duration::from_millis(250) } else { Duration::from_secs(1) };
    let limit = opts.max_seconds.map(|s| (s * HZ as f64) as u64);
    let start = Instant::now();
    let mut lag = Duration::ZERO; // wall time the board could not keep up with, dropped
    let mut tx_mark = 0usize;
    let mut pos = Position::default();
    let mut last = (Instant::now(), board.cycles(), Duration::ZERO);
    let mut buf = [0u8; 4096];

    while !STOP.load(Ordering::SeqCst) && limit.is_none_or(|l| board.cycles() < l) {
        // clients -> board (a pty client that came or left since the bytes before these: the
        // output queued for the port is flushed first, see `pty.rs`)
        let mut got = Vec::new();
        loop {
            let n = pty.read(&mut buf)?;
            if n == 0 {
                break;
            }
            got.extend_from_slice(&buf[..n]);
        }
        pty.clients();
        feed(&mut board, &got, opts.usb);
        if let Some(t) = tcp.as_mut() {
            if let Some(peer) = t.accept() {
                console.note(&format!("tcp: {peer} connected"));
            }
            loop {
                let peer = t.peer();
                match t.read(&mut buf) {
                    Some(0) => break,
                    Some(n) => feed(&mut board, &buf[..n], opts.usb),
                    None => {
                        if let Some(p) = peer {
                            console.note(&format!("tcp: {p} disconnected"));
                        }
                        break;
                    }
                }
            }
        }

        // run up to the wall clock, 1 ms of simulated time at most per turn
        let wall = start.elapsed().saturating_sub(lag);
        let target = (wall.as_secs_f64() * HZ as f64) as u64;
        let now = board.cycles();
        if now < target {
            let end = target.min(now + HZ / 1000);
            board.run_until_cycle(limit.map_or(end, |l| end.min(l)))?;
            let behind = target.saturating_sub(board.cycles());
            if behind > HZ / 4 {
                lag += Duration::from_secs_f64(behind as f64 / HZ as f64);
            }
        } else {
            let ahead = Duration::from_secs_f64((now - target) as f64 / HZ as f64);
            std::thread::sleep(ahead.min(Duration::from_millis(1)));
        }

        // board -> clients
        let (tx, _) = if opts.usb { board.usb_bytes() } else { board.serial_bytes() };
        if tx.len() > tx_mark {
            let new = tx[tx_mark..].to_vec();
            tx_mark = tx.len();
            pty.write(&new);
            if let Some(t) = tcp.as_mut() {
                t.write(&new);
            }
        }
        pos.feed(&record.turn(&mut board)?);

        if last.0.elapsed() >= status_every {
            let (t0, c0, lag0) = last;
            let dc = board.cycles() - c0;
            let speed = dc as f64 / HZ as f64 / t0.elapsed().as_secs_f64();
            let slow = if lag > lag0 { format!(" | host can't keep up: {speed:.2}x real time") } else { String::new() };
            let clients = tcp.as_ref().and_then(|t| t.peer()).map_or(String::new(), |p| format!(" | tcp {p}"));
            console.status(&format!(
                "{:9.3} s | {} steps | {} | CPU {:3.0}%{slow}{clients}",
                board.seconds(),
                pos.text(),
                status::rate_text(pos.rate_hz()),
                board.cpu_load(c0, board.cycles()) * 100.0,
            ));
            last = (Instant::now(), board.cycles(), lag);
        }
    }
    if STOP.load(Ordering::SeqCst) {
        console.note("stopped (Ctrl-C)");
    } else {
        console.note("stopped at --max-seconds");
    }
    // SAFETY: restores the default action; no handler state is involved.
    unsafe {
        let _ = signal(Signal::SIGINT, SigHandler::SigDfl);
        let _ = signal(Signal::SIGTERM, SigHandler::SigDfl);
    }
    let summary = Summary {
        simulated_s: board.seconds(),
        wall_s: start.elapsed().as_secs_f64(),
        lagged_s: lag.as_secs_f64(),
        steps: pos.steps,
    };
    let report = record.finish(&mut board)?;
    if let (Some(p), Some(r)) = (&opts.json, report) {
        std::fs::write(p, serde_json::to_string_pretty(&r)?)?;
    }
    Ok(summary)
}
