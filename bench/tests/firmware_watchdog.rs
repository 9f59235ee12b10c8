//! The independent watchdog on the release firmware: fed while the machine is alive (idle and
//! moving), and a stalled idle loop (the bench sets the firmware's `DDASTEP_STALL_IDLE` word)
//! resets the MCU: step pins low and drivers off first, `[MSG:Reset by watchdog]` after the
//! banner, and the alarm state.

mod firmware_rig;

use ddastep::board::{ENABLE_PIN, STEP_PINS};
use ddastep_bench::emu::{firmware_elf, Port, HZ};
use firmware_rig::*;
use object::{Object, ObjectSymbol};

/// RAM address of the firmware's stall hook.
fn stall_flag() -> u32 {
    let elf = std::fs::read(firmware_elf().unwrap()).unwrap();
    let file = object::File::parse(&*elf).unwrap();
    let sym = file.symbols().find(|s| s.name() == Ok("DDASTEP_STALL_IDLE")).expect("stall hook symbol");
    sym.address() as u32
}

#[test]
fn a_healthy_machine_is_never_reset() {
    let mut b = boot();
    b.run_seconds(0.6).unwrap(); // idle for > 2 timeouts
    ok(&mut b, "G91 G1 X30 F3000"); // 0.6 s of motion
    wait_idle(&mut b, 2.0);
    b.run_seconds(0.3).unwrap();
    assert_eq!(b.watchdog_resets(), &[] as &[u64]);
    assert!(!b.serial_output().contains("watchdog"));
}

#[test]
fn a_stalled_idle_loop_trips_the_watchdog_and_boots_safe_in_alarm() {
    let mut b = boot();
    ok(&mut b, "G91 G1 X100 F6000"); // 1 s of motion at 10 kHz
    b.run_seconds(0.1).unwrap();
    assert!(status(&mut b).starts_with("<Run"));
    assert!(!b.output(Port::B, ENABLE_PIN), "drivers enabled while moving");
    let stalled_at = b.cycles();
    b.write_mem(stall_flag(), &1u32.to_le_bytes()).unwrap();
    let mark = b.serial_output().len();
    let reset = b.run_until(HZ, |b| !b.watchdog_resets().is_empty()).unwrap();
    assert!(reset, "no watchdog reset within 1 s of the stall");
    let at = b.watchdog_resets()[0];
    let timeout_ms = (at - stalled_at) as f64 * 1e3 / HZ as f64;
    // 250 ms nominal, counted from the last feed (at most a poll before the stall).
    assert!((240.0..=252.0).contains(&timeout_ms), "tripped {timeout_ms:.1} ms after the stall");
    // First the step port: EN driven high (drivers off) and the step pins low.
    b.run_seconds(0.001).unwrap();
    let safe_at = b.edges().iter().find(|e| e.cycle >= at && e.port == 1 && e.pin == ENABLE_PIN && e.level).map(|e| e.cycle);
    let safe_at = safe_at.expect("EN driven high after the reset");
    let safe_us = (safe_at - at) as f64 * 1e6 / HZ as f64;
    assert!(safe_us < 20.0, "pins safe {safe_us:.1} µs (modeled) after the reset");
    eprintln!("watchdog: tripped {timeout_ms:.1} ms after the stall, pins safe {safe_us:.2} µs after the reset (modeled)");
    let up = b.run_until(HZ / 2, |b| b.serial_output()[mark..].contains("to unlock]")).unwrap();
    assert!(up, "{:?}", &b.serial_output()[mark..]);
    let boot = b.serial_output()[mark..].to_string();
    let banner = boot.find("Grbl 1.1").expect("banner");
    let msg = boot.find("[MSG:Reset by watchdog]").expect("reset cause reported");
    assert!(banner < msg, "{boot}");
    assert!(STEP_PINS.iter().all(|&p| !b.output(Port::B, p)));
    assert!(b.output(Port::B, ENABLE_PIN));
    assert!(status(&mut b).starts_with("<Alarm|"));
    // Nothing moves: G-code is locked until `$X`.
    let step_edges = |b: &ddastep_bench::emu::Board| b.edges().iter().filter(|e| e.port == 1 && STEP_PINS.contains(&e.pin)).count();
    let edges = step_edges(&b);
    assert!(reply(&mut b, "G1 X5 F1000").contains("error:9"));
    b.run_seconds(0.3).unwrap();
    assert_eq!(step_edges(&b), edges, "no step in the alarm state");
    assert_eq!(b.watchdog_resets().len(), 1, "the stall flag is cleared by the reset: no second trip");
    assert!(reply(&mut b, "$X").contains("ok"));
    ok(&mut b, "G91 G1 X1 F1000");
    wait_idle(&mut b, 1.0);
    // A plain soft reset afterwards does not claim a watchdog reset.
    let mark = b.serial_output().len();
    b.serial_send(&[0x18]);
    b.run_seconds(0.05).unwrap();
    assert!(!b.serial_output()[mark..].contains("watchdog"));
}
