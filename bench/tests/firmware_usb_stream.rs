//! Issue 27: no byte lost or doubled over a long stream on the modeled USB. A sender with
//! Grbl's character counting writes one line per write; the host cuts the bytes into OUT
//! packets of random lengths (1..=64, across lines: `Board::usb_random_splits`), so every
//! packet boundary lands in every place of a line. The test drives the port only through the
//! emulated host.
//!
//! The lines are relative moves by whole millimetres at 1 step/mm on 7 axes, without spaces
//! (`X7`, `G1X-12Y3`, `Z5A-9B2`, ...): a byte lost or doubled anywhere in a line is an
//! `error:`, a reply too many or too few, or a final position off by at least one step. The
//! check: every line exactly one `ok`, no `error:`, no other reply, the exact net steps on the
//! pins and the exact `MPos:`. The packet split seed is printed (on failure the test output
//! shows it); `USB_SPLIT_SEED=N` repeats a run.

use std::collections::VecDeque;

use ddastep::board::{DIR_PINS, STEP_PINS};
use ddastep::grbl::settings::Settings;
use ddastep::grbl::store::Stored;
use ddastep_bench::emu::sender::RX_BUFFER;
use ddastep_bench::emu::usb_splits::Splits;
use ddastep_bench::emu::{firmware_elf, Board, Port, HZ};

const AXES: [char; 7] = ['X', 'Y', 'Z', 'A', 'B', 'C', 'U'];

/// 1 step/mm, so a whole-millimetre word is whole steps; 60 kHz cruise, 10⁸ steps/s², ramps
/// from 20 kHz: moves of a few steps that take little time, so 10⁵ lines run in little
/// modeled time.
fn stream_settings() -> Settings {
    Settings {
        steps_per_mm: [1.0; 7],
        max_rate: [3_600_000.0; 7],
        accel: [100_000_000.0; 7],
        ramp_start_hz: 20_000,
        ..Settings::BENCH
    }
}

/// The lines' generator (the host's packet split has its own): SplitMix64 from the bench.
struct Rng(Splits);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(Splits::new(seed))
    }

    // uniform in 0..n
    fn below(&mut self, n: u64) -> u64 {
        self.0.next_len(n as usize) as u64 - 1
    }
}

/// `n` lines of mixed lengths (3 to 31 bytes with the newline) and the net millimetres
/// (= steps) they move each axis. Every value is a non-zero whole number without a leading
/// zero, so each digit, sign, letter and newline matters.
fn job(n: usize, seed: u64) -> (Vec<String>, [i64; 7]) {
    let mut rng = Rng::new(seed ^ 0x5EED);
    let mut lines = Vec::with_capacity(n);
    let mut net = [0i64; 7];
    for _ in 0..n {
        // (`G1` only: a doubled `0` would leave `G00` the same as `G0`.)
        let mut line = if rng.below(8) == 0 { "G1".to_string() } else { String::new() };
        // 1 axis most often, now and then all seven.
        let axes = match rng.below(10) {
            0..=3 => 1,
            4..=6 => 2,
            7 | 8 => 3,
            _ => 7,
        };
        let first = rng.below(7) as usize;
        for k in 0..axes {
            let a = (first + k) % 7;
            let top = if rng.below(4) == 0 { 19 } else { 9 };
            let v = 1 + rng.below(top) as i64;
            let v = if rng.below(2) == 0 { v } else { -v };
            net[a] += v;
            line.push_str(&format!("{}{v}", AXES[a]));
        }
        lines.push(line);
    }
    (lines, net)
}

/// Net steps per axis from the step and direction pins, fed edge batches as the run goes.
struct NetSteps {
    dir_high: [bool; 7],
    net: [i64; 7],
}

impl NetSteps {
    // counting from now: the direction pins as they are, no edges kept
    fn new(b: &mut Board) -> Self {
        b.take_edges();
        NetSteps { dir_high: std::array::from_fn(|a| b.output(Port::B, DIR_PINS[a])), net: [0; 7] }
    }

    fn take(&mut self, b: &mut Board) {
        for e in b.take_edges() {
            if e.port != 1 {
                continue;
            }
            if let Some(a) = DIR_PINS.iter().position(|&p| p == e.pin) {
                self.dir_high[a] = e.level;
            }
            if let Some(a) = STEP_PINS.iter().position(|&p| p == e.pin) {
                if e.level {
                    self.net[a] += if self.dir_high[a] { -1 } else { 1 };
                }
            }
        }
    }
}

/// The USB build with `stream_settings`, enumerated, port open, banner seen, packets split at
/// random from `seed`, relative feed moves set up.
fn boot(seed: u64) -> Board {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    b.write_mem(0x0800_0000 + 62 * 1024, &Stored::from(stream_settings()).to_bytes()).unwrap();
    b.usb_connect(2 * HZ).unwrap();
    assert!(b.run_until(HZ / 10, |b| b.usb_output().contains("Grbl 1.1")).unwrap(), "banner: {:?}", b.usb_output());
    b.usb_random_splits(seed);
    assert!(b.usb_send_line_wait_ok("G91G1F3600000").unwrap().contains("ok"));
    b
}

/// Writes `lines` (each as one write, with its newline) with character counting against
/// Grbl's 128-byte RX buffer, counting the step edges as they come; returns the net steps.
/// Stops when every line has its reply (`ok`/`error:N`), or with an error when none comes
/// within a second (modeled).
fn stream(b: &mut Board, lines: &[String]) -> Result<NetSteps, String> {
    let mut pins = NetSteps::new(b);
    let mut cursor = b.usb_bytes().0.len();
    let mut in_flight: VecDeque<usize> = VecDeque::new();
    let mut queued = 0;
    let mut replies = 0;
    let mut next = 0;
    while replies < lines.len() {
        while next < lines.len() && queued + lines[next].len() < RX_BUFFER {
            b.usb_send(format!("{}\n", lines[next]).as_bytes());
            in_flight.push_back(lines[next].len() + 1);
            queued += lines[next].len() + 1;
            next += 1;
        }
        let start = cursor;
        let got = b.run_until(HZ, |b| b.usb_bytes().0[start..].contains(&b'\n')).map_err(|e| e.to_string())?;
        if !got {
            return Err(format!("no reply within 1 s after {replies} of {} lines", lines.len()));
        }
        let out = b.usb_bytes().0;
        while let Some(n) = out[cursor..].iter().position(|&c| c == b'\n') {
            let line = String::from_utf8_lossy(&out[cursor..cursor + n]).trim_end().to_string();
            cursor += n + 1;
            // (A reply with no line in flight is left for the caller's count of replies.)
            if let (true, Some(n)) = (line.starts_with("ok") || line.starts_with("error"), in_flight.pop_front()) {
                queued -= n;
                replies += 1;
            }
        }
        if b.edges().len() > 100_000 {
            pins.take(b);
        }
    }
    pins.take(b);
    Ok(pins)
}

/// Streams `sent` from position `start` and checks the board against `expected` lines (as
/// they should arrive) moving `net` steps: one `ok` per expected line and nothing else, the
/// net steps on the pins and `MPos:`. Returns what differs.
fn run_and_check(b: &mut Board, sent: &[String], expected: usize, start: [i64; 7], net: [i64; 7]) -> Result<(), String> {
    let mark = b.usb_bytes().0.len();
    let mut pins = stream(b, sent)?;
    // Until the pins are quiet for 10 ms (the last moves run after the last reply).
    loop {
        b.run_seconds(0.01).map_err(|e| e.to_string())?;
        if b.edges().is_empty() {
            break;
        }
        pins.take(b);
    }
    let out = String::from_utf8_lossy(&b.usb_bytes().0[mark..]).into_owned();
    let mut problems = Vec::new();
    let oks = out.lines().filter(|l| *l == "ok\r" || *l == "ok").count();
    if oks != expected {
        problems.push(format!("{oks} ok for {expected} lines"));
    }
    let others: Vec<&str> = out.lines().filter(|l| !l.trim_end().is_empty() && !l.starts_with("ok")).take(5).collect();
    if !others.is_empty() {
        problems.push(format!("other replies: {others:?}"));
    }
    if pins.net != net {
        problems.push(format!("net steps {:?}, expected {net:?}", pins.net));
    }
    let mark = b.usb_bytes().0.len();
    b.usb_send(b"?");
    b.run_until(HZ / 10, |b| b.usb_bytes().0[mark..].ends_with(b">\r\n")).map_err(|e| e.to_string())?;
    let status = String::from_utf8_lossy(&b.usb_bytes().0[mark..]).trim_end().to_string();
    let mpos: Vec<String> = (0..7).map(|a| format!("{}.000", start[a] + net[a])).collect();
    if !status.starts_with(&format!("<Idle|MPos:{}|", mpos.join(","))) {
        problems.push(format!("status {status}"));
    }
    let s = b.usb_stats();
    if !s.errors.is_empty() || b.usb_toggle_mismatches() != 0 || s.in_toggle_errors != 0 {
        problems.push(format!("USB: {:?}, {} OUT toggle mismatches", s, b.usb_toggle_mismatches()));
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("; "))
    }
}

/// The seed from `USB_SPLIT_SEED`, else a new one; printed so a failure can be repeated.
fn seed() -> u64 {
    let seed = std::env::var("USB_SPLIT_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or_else(|| {
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(1, |d| d.as_nanos() as u64)
    });
    println!("packet split seed {seed} (USB_SPLIT_SEED={seed} repeats it)");
    seed
}

/// Streams `n` lines and asserts nothing was lost or doubled.
fn no_byte_lost_or_doubled(n: usize) {
    let seed = seed();
    let (lines, net) = job(n, seed);
    let mut b = boot(seed);
    let t0 = b.cycles();
    if let Err(e) = run_and_check(&mut b, &lines, lines.len(), [0; 7], net) {
        panic!("seed {seed}: {e}");
    }
    let s = b.usb_stats();
    println!(
        "{n} lines in {:.2} s modeled, {} bytes out, {} NAKed OUT packets",
        (b.cycles() - t0) as f64 / HZ as f64,
        s.bytes_out,
        s.naked_out
    );
}

/// A fault in the bytes a line arrives as, to show the check catches it.
#[derive(Clone, Copy, Debug)]
enum Fault {
    DropByte,
    DoubleByte,
    DropNewline,
    DoubleNewline,
}

/// `lines` as they arrive with `fault` at line `k`, byte `j` of it (modulo its length).
fn with_fault(lines: &[String], fault: Fault, k: usize, j: usize) -> Vec<String> {
    let mut sent = lines.to_vec();
    let line = &mut sent[k];
    let j = j % line.len();
    match fault {
        Fault::DropByte => {
            line.remove(j);
        }
        Fault::DoubleByte => {
            let c = line.as_bytes()[j] as char;
            line.insert(j, c);
        }
        Fault::DropNewline => {
            let next = sent.remove(k + 1);
            sent[k].push_str(&next);
        }
        Fault::DoubleNewline => line.push('\n'),
    }
    sent
}

/// The check fails when one byte of a line is lost or doubled (sent so by the sender, as if
/// the link had done it), wherever it is: a byte or a newline of a random line, and every
/// byte of the longest line.
#[test]
fn the_check_catches_a_lost_or_doubled_byte() {
    let seed = seed();
    let (lines, net) = job(100, seed);
    let mut rng = Rng::new(seed);
    let mut cases: Vec<(Fault, usize, usize)> = [Fault::DropByte, Fault::DoubleByte, Fault::DropNewline, Fault::DoubleNewline]
        .into_iter()
        .map(|f| (f, 30 + rng.below(50) as usize, rng.below(64) as usize))
        .collect();
    let long = (30..80).max_by_key(|&k| lines[k].len()).unwrap();
    println!("line {long}: {}", lines[long]);
    for j in 0..lines[long].len() {
        cases.push((Fault::DropByte, long, j));
        cases.push((Fault::DoubleByte, long, j));
    }
    let mut b = boot(seed);
    run_and_check(&mut b, &lines, lines.len(), [0; 7], net).unwrap_or_else(|e| panic!("seed {seed}, no fault: {e}"));
    // Relative moves: each case starts where the last one ended.
    let mut at = net;
    for (fault, k, j) in cases {
        let sent = with_fault(&lines, fault, k, j);
        match run_and_check(&mut b, &sent, lines.len(), at, net) {
            Ok(()) => panic!("seed {seed}: {fault:?} at line {k} byte {j} ({:?}) not caught", lines[k]),
            Err(e) => println!("{fault:?} at line {k} byte {j} of {:?}: {e}", lines[k]),
        }
        at = position(&mut b);
    }
}

/// The board's `MPos:` in whole steps (1 step/mm).
fn position(b: &mut Board) -> [i64; 7] {
    b.run_seconds(0.05).unwrap();
    let mark = b.usb_bytes().0.len();
    b.usb_send(b"?");
    b.run_until(HZ / 10, |b| b.usb_bytes().0[mark..].ends_with(b">\r\n")).unwrap();
    let status = String::from_utf8_lossy(&b.usb_bytes().0[mark..]).into_owned();
    let mpos = status.split("MPos:").nth(1).and_then(|s| s.split('|').next()).expect("MPos in the status");
    let v: Vec<i64> = mpos.split(',').map(|x| x.parse::<f64>().unwrap().round() as i64).collect();
    std::array::from_fn(|a| v[a])
}

/// 10⁵ lines, the issue's count: about 78 s modeled with the CPU 99 % busy (some 56 000
/// modeled cycles a line, nearly all parse and plan, which no fast-forward can skip), 65 to
/// 80 s of host CPU. A cheaper parse and plan makes it shorter.
#[test]
fn usb_stream_of_1e5_lines_with_random_packet_splits_loses_or_doubles_no_byte() {
    no_byte_lost_or_doubled(100_000);
}
