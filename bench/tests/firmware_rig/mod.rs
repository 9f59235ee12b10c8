//! Firmware-in-the-loop helpers: boot the release ELF on the virtual bench and read its pins.
#![allow(dead_code)]

use ddastep::board::{DIR_PINS, STEP_PINS};
use ddastep::grbl::settings::Settings;
use ddastep::grbl::store::{Stored, PAGE_LEN};
use ddastep_bench::emu::{firmware_elf, Board, HZ};

/// Flash address of the persistent store's first page (A/B over the last two pages).
pub const STORE_ADDR: u32 = 0x0800_0000 + 62 * 1024;

/// A booted board with the seed paper's bench settings in flash (`Settings::BENCH`: 100
/// steps/mm, 36 000 mm/min, 10 000 mm/s², 7 axes): banner seen.
pub fn boot() -> Board {
    boot_with(Some(Stored::from(Settings::BENCH)))
}

/// A booted board with `stored` in flash (`None`: blank flash, the firmware's defaults).
pub fn boot_with(stored: Option<Stored>) -> Board {
    boot_part(stored, &ddastep_bench::emu::BLUE_PILL)
}

/// A booted board that is part `chip` (flash size, unique ID, CPUID), with `stored` in flash.
pub fn boot_part(stored: Option<Stored>, chip: &ddastep::grbl::chip::Chip) -> Board {
    let elf = firmware_elf().expect("firmware builds");
    let mut b = Board::load(elf).expect("ELF loads");
    b.set_chip(chip).expect("chip registers");
    if let Some(s) = stored {
        b.write_mem(STORE_ADDR, &s.to_bytes()).expect("flash preload");
    }
    let up = b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl")).expect("runs");
    assert!(up, "no banner: {:?}", b.serial_output());
    assert_stack_fits(&b);
    b
}

/// The deepest stack use so far left at least 256 bytes untouched above the statics (the
/// emulator paints RAM at power-up, `Board::stack_peak`).
pub fn assert_stack_fits(b: &Board) {
    let (used, room) = b.stack_peak().expect("ELF has _stack_end");
    assert!(used + 256 <= room, "stack: {used} B used of {room} B between the statics and the top of RAM");
}

/// Sends a line and expects `ok`.
pub fn ok(b: &mut Board, line: &str) {
    let r = b.send_line_wait_ok(line).unwrap_or_else(|e| panic!("{line}: {e}"));
    assert!(r.contains("ok"), "{line}: {r}");
}

/// Sends a line and returns the reply (ok or error).
pub fn reply(b: &mut Board, line: &str) -> String {
    match b.send_line_wait_ok(line) {
        Ok(r) => r,
        Err(e) => e.to_string(),
    }
}

/// Asks `?` and returns the status line.
pub fn status(b: &mut Board) -> String {
    let mark = b.serial_output().len();
    b.serial_send(b"?");
    b.run_until(HZ / 10, |b| b.serial_output()[mark..].contains(">\r\n")).expect("runs");
    let out = b.serial_output()[mark..].to_string();
    out.lines().find(|l| l.starts_with('<')).unwrap_or("").to_string()
}

/// Runs until the status says Idle (checked every 10 ms), at most `max_s` simulated seconds.
pub fn wait_idle(b: &mut Board, max_s: f64) {
    let end = b.seconds() + max_s;
    while b.seconds() < end {
        b.run_seconds(0.01).expect("runs");
        if status(b).starts_with("<Idle") {
            return;
        }
    }
    panic!("not idle after {max_s} s: {}", status(b));
}

/// One step edge seen on the pins.
#[derive(Clone, Copy, Debug)]
pub struct Step {
    pub cycle: u64,
    pub axis: usize,
    pub positive: bool,
}

/// Rising step edges of every axis, in order, with the direction pin's meaning (low = +).
pub fn steps(b: &Board) -> Vec<Step> {
    step_edges(b, false)
}

/// Dual-edge steps (`$580=1`): every edge of a step pin, with the direction pin's meaning.
pub fn toggles(b: &Board) -> Vec<Step> {
    step_edges(b, true)
}

fn step_edges(b: &Board, dual_edge: bool) -> Vec<Step> {
    let mut dir_high = [false; 7];
    let mut out = Vec::new();
    for e in b.edges() {
        if e.port != 1 {
            continue;
        }
        if let Some(a) = DIR_PINS.iter().position(|&p| p == e.pin) {
            dir_high[a] = e.level;
        }
        if let Some(a) = STEP_PINS.iter().position(|&p| p == e.pin) {
            if e.level || dual_edge {
                out.push(Step { cycle: e.cycle, axis: a, positive: !dir_high[a] });
            }
        }
    }
    out
}

/// A booted board in dual-edge mode (`$580=1` in flash with `base`): [`Board::report`] counts
/// both edges.
pub fn boot_dual(base: Settings) -> Board {
    let mut b = boot_with(Some(Stored::from(Settings { dual_edge: true, ..base })));
    b.dual_edge = true;
    b
}

/// Net steps per axis.
pub fn net(steps: &[Step]) -> [i64; 7] {
    let mut n = [0i64; 7];
    for s in steps {
        n[s.axis] += if s.positive { 1 } else { -1 };
    }
    n
}

/// What the two store pages hold now (the newest valid image).
pub fn stored(b: &mut Board) -> Option<Stored> {
    let a = b.read_mem(STORE_ADDR, PAGE_LEN);
    let c = b.read_mem(STORE_ADDR + PAGE_LEN as u32, PAGE_LEN);
    Stored::decode(&a).into_iter().chain(Stored::decode(&c)).max_by_key(|s| s.seq)
}

/// A booted board with `base` plus the sample gantry's steps/mm (`bench/demo/gantry300.toml`)
/// in flash, wired to that virtual machine (carriages, limit switches): banner seen.
pub fn boot_gantry(base: Settings) -> Board {
    use ddastep_bench::machine::MachineSpec;
    let spec = MachineSpec::load(&ddastep_bench::emu::repo_root().join("bench/demo/gantry300.toml")).unwrap();
    boot_machine(&spec, base)
}

/// A booted board with `base` plus `spec`'s steps/mm in flash, wired to that virtual machine.
pub fn boot_machine(spec: &ddastep_bench::machine::MachineSpec, base: Settings) -> Board {
    use ddastep_bench::machine::VirtualMachine;
    let mut s = base;
    for (i, a) in spec.axis.iter().enumerate() {
        s.steps_per_mm[i] = a.steps_per_mm as f32;
    }
    let mut b = Board::load(firmware_elf().unwrap()).unwrap();
    b.attach_plant(Box::new(VirtualMachine::new(spec)));
    b.write_mem(STORE_ADDR, &Stored::from(s).to_bytes()).unwrap();
    assert!(b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl")).unwrap());
    b
}

/// A booted board in DMA burst mode (`$581=1` in flash with `base`; `dual`: with `$580=1`).
pub fn boot_dma(base: Settings, dual: bool) -> Board {
    let mut b = boot_with(Some(Stored::from(Settings { dma_burst: true, dual_edge: dual, ..base })));
    b.dual_edge = dual;
    b.step_irq = ddastep_bench::emu::dma::IRQ_CHANNEL1;
    b
}

/// The seed paper's 5:3:2 pattern in `s` (every step of X, Y, Z, each a rising edge or, in
/// dual-edge mode, a toggle): per five master steps Y steps with X at 1, 3, 5 and Z at 2, 4, the
/// edges of one master step in one store (the same cycle). Returns how many master steps.
pub fn assert_paper_pattern(s: &[Step]) -> usize {
    let mut k = 0usize;
    for (i, st) in s.iter().enumerate().filter(|(_, st)| st.axis == 0) {
        let mut all: Vec<usize> = s[..i].iter().rev().take_while(|o| o.cycle == st.cycle).map(|o| o.axis).collect();
        all.extend(s[i..].iter().take_while(|o| o.cycle == st.cycle).map(|o| o.axis));
        all.sort();
        let want = if k % 5 % 2 == 0 { vec![0, 1] } else { vec![0, 2] };
        assert_eq!(all, want, "master step {}", k + 1);
        k += 1;
    }
    k
}

/// The paper move's cruise and counts as the checker sees them: 1000 master steps in the middle
/// at 50 kHz ± 0.5 %; X, Y, Z made 5000, 3000, 2000 steps (rising edges and net; both edges with
/// `Board::dual_edge`), each high and low for at least `min_ns`. Returns the checker's report.
pub fn assert_paper_cruise(b: &Board, s: &[Step], min_ns: f64) -> ddastep_bench::emu::Report {
    let x: Vec<u64> = s.iter().filter(|s| s.axis == 0).map(|s| s.cycle).collect();
    let rate = 1000.0 * HZ as f64 / (x[3000] - x[2000]) as f64;
    assert!((rate - 50_000.0).abs() < 250.0, "cruise {rate} Hz");
    let r = b.report();
    for (i, want) in [5000u64, 3000, 2000].into_iter().enumerate() {
        let a = &r.axes.0[i].1;
        assert_eq!((a.rising_edges, a.net_steps), (want, want as i64), "{}", r.axes.0[i].0);
        assert!(a.min_high_ns.unwrap() >= min_ns && a.min_low_ns.unwrap() >= min_ns, "{a:?}");
    }
    r
}

/// Runs `bench/demo/circle360.gcode` from rest (its settings and the move to the start point
/// first, then a wait) and returns the circle's steps.
pub fn circle360_steps(b: &mut Board) -> Vec<Step> {
    let g = std::fs::read_to_string(ddastep_bench::emu::repo_root().join("bench/demo/circle360.gcode")).unwrap();
    let lines: Vec<String> = ddastep_bench::emu::gcode_lines(&g);
    let start = lines.iter().position(|l| l.starts_with("G1")).unwrap();
    for l in &lines[..=start] {
        ok(b, l);
    }
    wait_idle(b, 2.0);
    let t0 = b.cycles();
    for l in &lines[start + 1..] {
        ok(b, l);
    }
    wait_idle(b, 10.0);
    steps(b).into_iter().filter(|s| s.cycle >= t0).collect()
}
