//! Settings that change how steps are made (`$2`, `$3`, `$580`, `$581`, a `$0` that needs a new
//! DMA layout) apply in place on the release firmware, as Grbl's do: the step output is rebuilt
//! at rest, every line gets its one reply, no banner follows and the MCU never resets (the
//! emulator counts AIRCR.SYSRESETREQ), so a pasted block of settings loses nothing. Moves stay
//! exact after each change: step counts, directions per `$3`, step polarity per `$2`, in
//! interrupt, dual-edge and DMA modes and switching between them.

mod firmware_rig;

use ddastep::board::{DIR_PINS, STEP_PINS};
use ddastep_bench::emu::{Board, HZ};
use firmware_rig::*;

/// Sends a setting and expects exactly `ok` and nothing after it (no banner), then lets the
/// output settle (the rebuild follows the flash write). Returns how many step pin edges the
/// change made (only a change of the idle level makes one: single-edge `$2`, leaving dual-edge).
fn set(b: &mut Board, line: &str) -> usize {
    let mark = b.serial_output().len();
    let edges = b.edges().len();
    b.serial_send(format!("{line}\n").as_bytes());
    let done = b.run_until(HZ / 2, |b| b.serial_output()[mark..].contains("\r\n")).unwrap();
    assert!(done, "{line}: no reply");
    b.run_seconds(0.02).unwrap();
    assert_eq!(&b.serial_output()[mark..], "ok\r\n", "{line}");
    b.edges()[edges..].iter().filter(|e| e.port == 1 && STEP_PINS.contains(&e.pin)).count()
}

/// [`set`] for a change that keeps every step pin's level.
fn set_quiet(b: &mut Board, line: &str) {
    assert_eq!(set(b, line), 0, "{line}: step pin edges");
}

/// One axis's step pin after `mark` (an index into `b.edges()`): the pulses it made (active
/// edges, or every edge in dual-edge mode), signed by the direction pin as `dir_invert` reads
/// it; checks each pulse's polarity (`step_invert`: active low) and that the pin rests at its
/// idle level.
fn pulses(b: &Board, mark: usize, axis: usize, step_invert: bool, dir_invert: bool, dual: bool) -> i64 {
    let (step, dir) = (STEP_PINS[axis], DIR_PINS[axis]);
    let mut dir_high = b.edges()[..mark].iter().rev().find(|e| e.port == 1 && e.pin == dir).is_some_and(|e| e.level);
    let mut last: Option<(bool, u64)> = None;
    let mut n = 0i64;
    for e in &b.edges()[mark..] {
        if e.port != 1 {
            continue;
        }
        if e.pin == dir {
            dir_high = e.level;
        }
        if e.pin != step {
            continue;
        }
        let positive = dir_high == dir_invert;
        let sign = if positive { 1 } else { -1 };
        if dual {
            n += sign;
        } else if e.level != step_invert {
            // The active edge: the pulse's end follows within its width (µs), not a step period.
            n += sign;
        } else if let Some((active, at)) = last {
            assert!(active != step_invert && e.cycle - at < 100 * HZ / 1_000_000, "axis {axis}: an idle phase of {} cycles", e.cycle - at);
        }
        last = Some((e.level, e.cycle));
    }
    if !dual {
        let idle = b.output(ddastep_bench::emu::Port::B, step);
        assert_eq!(idle, step_invert, "axis {axis}: step pin not at its idle level");
    }
    n
}

/// The firmware with the bench settings, its banner complete.
fn up() -> Board {
    let mut b = boot();
    assert!(b.run_until(HZ / 10, |b| b.serial_output().ends_with("help]\r\n")).unwrap());
    b
}

/// `G91 G1 X0.05 Y-0.03`: X makes 5 steps forward and Y 3 back, as `$2`, `$3` and the mode
/// say they look on the pins.
fn move_is_exact(b: &mut Board, step_invert: u8, dir_invert: u8, dual: bool, what: &str) {
    let mark = b.edges().len();
    ok(b, "G91 G1 X0.05 Y-0.03 F600");
    wait_idle(b, 1.0);
    for (axis, want) in [(0, 5), (1, -3)] {
        let got = pulses(b, mark, axis, step_invert >> axis & 1 != 0, dir_invert >> axis & 1 != 0, dual);
        assert_eq!(got, want, "{what}: axis {axis}");
    }
}

/// A sender's "import settings" or a pasted block: every byte at once. Each line gets one
/// reply, no banner appears, and the MCU is never reset.
#[test]
fn a_pasted_settings_block_answers_every_line_without_a_banner() {
    let mut b = up();
    let mark = b.serial_output().len();
    b.serial_send(b"$2=1\n$3=2\n$2=0\n");
    b.run_until(HZ, |b| b.serial_output()[mark..].matches("\r\n").count() >= 3).unwrap();
    b.run_seconds(0.1).unwrap();
    assert_eq!(&b.serial_output()[mark..], "ok\r\nok\r\nok\r\n");
    assert!(b.system_resets().is_empty(), "MCU reset at {:?}", b.system_resets());
    let s = stored(&mut b).unwrap().settings;
    assert_eq!((s.step_invert, s.dir_invert), (0, 2));
    // The block's end state is the pins' (Y's direction inverted, steps active high).
    move_is_exact(&mut b, 0, 2, false, "after the block");
}

/// Interrupt mode with `$2` and `$3`, dual-edge (`$580`), DMA (`$581`) single and dual-edge,
/// a `$0` the DMA buffers' layout cannot hold, and back to interrupt mode: every move exact,
/// every setting answered `ok` alone, no MCU reset.
#[test]
fn moves_stay_exact_across_every_mode_switch() {
    let mut b = up();
    // Taken only at rest: during a move, error:8 (Grbl's "not idle"), and nothing changes.
    ok(&mut b, "G91 G1 X1 F600");
    b.run_seconds(0.02).unwrap();
    assert!(reply(&mut b, "$2=1").ends_with("error:8"), "not refused");
    wait_idle(&mut b, 1.0);
    assert_eq!(stored(&mut b).map_or(0, |s| s.settings.step_invert), 0);
    move_is_exact(&mut b, 0, 0, false, "interrupt");
    set_quiet(&mut b, "$3=2");
    move_is_exact(&mut b, 0, 2, false, "interrupt $3=2");
    assert_eq!(set(&mut b, "$2=1"), 1, "X's step pin to its idle level, high");
    move_is_exact(&mut b, 1, 2, false, "interrupt $2=1 $3=2");
    // Into dual-edge mode: the pins toggle from the levels they have (X high), no edge.
    set_quiet(&mut b, "$580=1");
    move_is_exact(&mut b, 1, 2, true, "dual-edge");
    // (Y is high now: the DMA fill toggles it from there.)
    set_quiet(&mut b, "$581=1");
    assert!(reply(&mut b, "$I").contains(" Hz dual-edge DMA]"));
    move_is_exact(&mut b, 1, 2, true, "DMA dual-edge");
    let _ = set(&mut b, "$580=0");
    move_is_exact(&mut b, 1, 2, false, "DMA");
    set_quiet(&mut b, "$3=1");
    move_is_exact(&mut b, 1, 1, false, "DMA $3=1");
    // 20 µs pulses need longer entries: a new layout, in place.
    set_quiet(&mut b, "$0=20");
    move_is_exact(&mut b, 1, 1, false, "DMA $0=20");
    let widths: Vec<u64> = {
        let e: Vec<_> = b.edges().iter().filter(|e| e.port == 1 && e.pin == STEP_PINS[0]).collect();
        e.windows(2).filter(|w| !w[0].level).map(|w| w[1].cycle - w[0].cycle).collect()
    };
    let last = *widths.last().unwrap();
    assert!(last >= 20 * HZ / 1_000_000, "pulse {last} cycles");
    set_quiet(&mut b, "$581=0");
    move_is_exact(&mut b, 1, 1, false, "interrupt again");
    set_quiet(&mut b, "$0=3");
    assert_eq!(set(&mut b, "$2=0"), 1, "X's step pin to its idle level, low");
    move_is_exact(&mut b, 0, 1, false, "interrupt $2=0");
    set_quiet(&mut b, "$580=1");
    move_is_exact(&mut b, 0, 1, true, "dual-edge again");
    let _ = set(&mut b, "$580=0");
    move_is_exact(&mut b, 0, 1, false, "single-edge again");
    assert!(b.system_resets().is_empty(), "MCU reset at {:?}", b.system_resets());
    assert!(b.watchdog_resets().is_empty());
    assert_eq!(b.serial_output().matches("Grbl").count(), 1, "one banner, at boot");
    // The position is the sum of the moves (X1, then 12 of X0.05 Y-0.03).
    let s = status(&mut b);
    assert!(s.contains("MPos:1.600,-0.360,"), "{s}");
}
