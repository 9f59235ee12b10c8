//! Hard limits (`$21`) on the release firmware with the virtual gantry: a carriage reaching its
//! switch mid-move stops all step output within one step period (measured: switch to the
//! last step edge and to the step pins forced low), ALARM:1 follows and nothing moves until
//! Ctrl-X, a soft reset with no MCU reset (the step output is rebuilt in place) into the alarm
//! state, keeping the position (as Grbl keeps its position across a soft reset, but asks for
//! `$H`/`$X`).

mod firmware_rig;

use ddastep::board::STEP_PINS;
use ddastep::grbl::settings::Settings;
use ddastep_bench::emu::{Board, HZ};
use ddastep_bench::machine::VirtualMachine;
use firmware_rig::*;

/// The firmware with gantry300's steps/mm and `$21=1`, wired to the virtual gantry.
fn gantry(hard: bool, pulse_us: f32) -> Board {
    boot_gantry(Settings { hard_limits: hard, pulse_us, ..Settings::BENCH })
}

/// The same in DMA burst mode (`$581=1`).
fn gantry_dma(pulse_us: f32) -> Board {
    boot_gantry(Settings { hard_limits: true, pulse_us, dma_burst: true, ..Settings::BENCH })
}

/// Rising edges of X's step pin.
fn x_steps(b: &Board) -> Vec<u64> {
    b.edges().iter().filter(|e| e.port == 1 && e.pin == STEP_PINS[0] && e.level).map(|e| e.cycle).collect()
}

#[test]
fn a_switch_mid_move_stops_the_steps_within_a_period_then_alarm_1() {
    // 10 µs pulses, so step pins going low sooner than that are the limit interrupt's doing.
    switch_mid_move(gantry(true, 10.0));
}

/// DMA mode: the limit interrupt stops TIM2 and with it every DMA store at once (the buffered
/// entries are dropped, not played), so the same bounds hold.
#[test]
fn in_dma_mode_a_switch_stops_the_steps_at_once_too() {
    switch_mid_move(gantry_dma(10.0));
}

fn switch_mid_move(mut b: Board) {
    // 150 mm to the max switch at 300 mm, cruising at 16 kHz (12 000 mm/min × 80 steps/mm).
    ok(&mut b, "G91 G1 X200 Y10 F12000");
    let hit = b.run_until(2 * HZ, |b| VirtualMachine::of(b).unwrap().events().len() > 0).unwrap();
    assert!(hit, "the carriage never reached the switch");
    b.run_seconds(0.2).unwrap();
    let switch = VirtualMachine::of(&b).unwrap().events()[0].cycle;
    let steps = x_steps(&b);
    let last = *steps.last().unwrap();
    let period = steps[steps.len() - 1] - steps[steps.len() - 2];
    assert!(last <= switch + period, "a step {} cycles after the switch", last - switch);
    // The step pins forced low by the limit interrupt.
    let low = b.edges().iter().filter(|e| e.port == 1 && STEP_PINS.contains(&e.pin) && !e.level && e.cycle >= switch).map(|e| e.cycle).next();
    let low_us = (low.expect("step pins low") - switch) as f64 * 1e6 / HZ as f64;
    assert!(low_us < 10.0, "the pulse ended by itself ({low_us:.2} µs): the interrupt was late");
    eprintln!(
        "hard limit: last step {:.2} µs after the switch closed (step period {:.2} µs); step pins low after {low_us:.2} µs (modeled)",
        (last as f64 - switch as f64) * 1e6 / HZ as f64,
        period as f64 * 1e6 / HZ as f64
    );
    assert!(VirtualMachine::of(&b).unwrap().positions_mm()[0] >= 300.0);
    let out = b.serial_output();
    assert!(out.contains("ALARM:1\r\n[MSG:Reset to continue]"), "{out}");
    assert!(status(&mut b).starts_with("<Alarm|"));
    // Nothing moves, the watchdog stays fed with the step timer stopped.
    let n = x_steps(&b).len();
    b.run_seconds(0.5).unwrap();
    assert_eq!(x_steps(&b).len(), n);
    assert!(b.watchdog_resets().is_empty());
    // Ctrl-X clears the halt in place: the banner (as every soft reset), the alarm kept (no
    // ALARM:3: the move was already cut), no MCU reset, no step, the same position, `$X`, and
    // off the switch.
    let mpos = |s: &str| s.split("MPos:").nth(1).and_then(|r| r.split('|').next()).unwrap_or("").to_string();
    let before = mpos(&status(&mut b));
    assert!(!before.starts_with("0.000"), "{before}");
    let mark = b.serial_output().len();
    b.serial_send(&[0x18]);
    let up = b.run_until(HZ / 2, |b| b.serial_output()[mark..].contains("to unlock]\r\n")).unwrap();
    assert!(up, "{:?}", &b.serial_output()[mark..]);
    assert_eq!(&b.serial_output()[mark..], "\r\nGrbl 1.1h ['$' for help]\r\n[MSG:'$H'|'$X' to unlock]\r\n");
    assert!(b.system_resets().is_empty(), "MCU reset at {:?}", b.system_resets());
    b.run_seconds(0.1).unwrap();
    assert_eq!(x_steps(&b).len(), n, "a step after the Ctrl-X");
    let s = status(&mut b);
    assert!(s.contains("<Alarm|"));
    assert_eq!(mpos(&s), before, "the position survives the Ctrl-X");
    assert!(reply(&mut b, "$X").contains("ok"));
    ok(&mut b, "G91 G1 X-5 F3000");
    wait_idle(&mut b, 2.0);
    assert!(status(&mut b).starts_with("<Idle|"), "releasing the switch does not trip");
    assert!(VirtualMachine::of(&b).unwrap().positions_mm()[0] < 300.0);
}

#[test]
fn without_hard_limits_the_switch_only_shows_in_pn() {
    let mut b = gantry(false, 3.0);
    ok(&mut b, "G91 G1 X151 F36000");
    wait_idle(&mut b, 3.0);
    assert_eq!(VirtualMachine::of(&b).unwrap().steps()[0], 151 * 80);
    let s = status(&mut b);
    assert!(s.starts_with("<Idle|") && s.contains("Pn:X"), "{s}");
}
