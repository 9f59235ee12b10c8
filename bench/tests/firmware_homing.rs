//! `$H` homing on the release firmware with the virtual gantry (`bench/demo/gantry300.toml`:
//! X and Y switches at 0 and 300 mm, Z at 80 mm; all home toward their max end, `$23=0`):
//! every cycle ends with each carriage `$27` before its switch, to the step, from any start;
//! a missing switch is ALARM:9; chattering contacts home to the same step; `$HX` alone.

mod firmware_rig;

use ddastep::grbl::settings::Settings;
use ddastep_bench::emu::Board;
use ddastep_bench::machine::{MachineSpec, VirtualMachine};
use firmware_rig::*;

/// Bench rates, homing on: 300 × 300 × 80 mm, seek 15 000 mm/min, locate 600 mm/min, 1 mm
/// pull-off, 10 ms debounce.
fn settings() -> Settings {
    let mut s = Settings { homing: true, axes: 3, ..Settings::BENCH };
    s.max_travel[..3].copy_from_slice(&[300.0, 300.0, 80.0]);
    s.homing_seek = 15_000.0;
    s.homing_feed = 600.0;
    s.homing_pulloff = 1.0;
    s.homing_debounce_ms = 10;
    s
}

fn gantry_spec() -> MachineSpec {
    MachineSpec::load(&ddastep_bench::emu::repo_root().join("bench/demo/gantry300.toml")).unwrap()
}

/// The firmware on `spec`'s machine with [`settings`], its banner complete.
fn boot(spec: &MachineSpec, s: Settings) -> Board {
    let mut b = boot_machine(spec, s);
    b.run_seconds(0.05).unwrap();
    b
}

fn vm(b: &Board) -> &VirtualMachine {
    VirtualMachine::of(b).expect("machine attached")
}

/// Sends `$H…` and runs until its `ok` (or `error`), at most `max_s` simulated seconds;
/// returns the output and whether a status report said `Home` meanwhile.
fn home(b: &mut Board, cmd: &str, max_s: f64) -> (String, bool) {
    let mark = b.serial_output().len();
    b.serial_send(format!("{cmd}\n").as_bytes());
    let mut saw_home = false;
    let end = b.seconds() + max_s;
    while b.seconds() < end {
        b.run_seconds(0.05).unwrap();
        let out = &b.serial_output()[mark..];
        if out.contains("ok\r\n") || out.contains("error:") {
            b.run_seconds(0.02).unwrap();
            // The replies, without the status reports asked for meanwhile.
            let text = b.serial_output()[mark..].split_inclusive('\n').filter(|l| !l.starts_with('<')).collect();
            return (text, saw_home);
        }
        saw_home |= status(b).starts_with("<Home|");
    }
    panic!("{cmd}: no reply within {max_s} s: {:?}", &b.serial_output()[mark..]);
}

/// Carriage steps, rounded to whole steps of each axis.
fn at(b: &Board) -> Vec<i64> {
    vm(b).steps()
}

#[test]
fn twenty_random_starts_home_to_the_same_step() {
    let mut b = boot(&gantry_spec(), settings());
    assert!(b.serial_output().contains("'$H'|'$X' to unlock"), "homing lock at power-up");
    let (out, saw) = home(&mut b, "$H", 10.0);
    assert!(out.ends_with("ok\r\n") && !out.contains("ALARM"), "{out}");
    assert!(saw, "status said Home during the cycle");
    assert!(status(&mut b).starts_with("<Idle|MPos:-1.000,-1.000,-1.000"), "{}", status(&mut b));
    // 1 mm before each switch: X, Y at 299 mm (80 steps/mm), Z at 79 mm (400 steps/mm).
    let p = vm(&b).positions_mm();
    assert!((p[0] - 299.0).abs() < 1.5 / 80.0 && (p[1] - 299.0).abs() < 1.5 / 80.0 && (p[2] - 79.0).abs() < 1.5 / 400.0, "{p:?}");
    let home_steps = at(&b);
    let mut seed = 0x2545_F491_u32;
    let mut rnd = |lo: f64, hi: f64| {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        lo + (hi - lo) * (seed as f64 / u32::MAX as f64)
    };
    for k in 0..20 {
        // Within 60 mm (Z 20 mm) of the switches: the emulator's time goes with the steps.
        let (x, y, z) = (rnd(-60.0, -2.0), rnd(-60.0, -2.0), rnd(-20.0, -2.0));
        ok(&mut b, &format!("G53 G0 X{x:.3} Y{y:.3} Z{z:.3}"));
        wait_idle(&mut b, 5.0);
        let (out, _) = home(&mut b, "$H", 10.0);
        assert!(out.ends_with("ok\r\n") && !out.contains("ALARM"), "start {k}: {out}");
        let now = at(&b);
        for i in 0..3 {
            assert!((now[i] - home_steps[i]).abs() <= 1, "start {k} ({x:.3}, {y:.3}, {z:.3}): axis {i} at {now:?}, first home {home_steps:?}");
        }
        assert!(status(&mut b).starts_with("<Idle|MPos:-1.000,-1.000,-1.000"));
    }
    assert!(b.watchdog_resets().is_empty());
}

#[test]
fn a_missing_switch_is_alarm_9_after_one_and_a_half_travel() {
    let mut spec = gantry_spec();
    spec.axis[0].max = None; // X has only its min switch
    let mut b = boot(&spec, settings());
    let before = at(&b);
    let (out, _) = home(&mut b, "$HX", 10.0);
    assert!(out.starts_with("ALARM:9\r\nok\r\n"), "{out}");
    assert!(out.contains("'$H'|'$X' to unlock"), "reset into alarm: {out}");
    // The seek went 1.5 × 300 mm and stopped there; nothing else moved.
    let now = at(&b);
    assert_eq!(now[0] - before[0], 450 * 80);
    assert_eq!((now[1], now[2]), (before[1], before[2]));
    assert!(status(&mut b).starts_with("<Alarm|"));
}

#[test]
fn chattering_switches_home_to_the_same_step() {
    let mut spec = gantry_spec();
    spec.bounce_us = 1000.0; // each pin change chatters for a millisecond
    let mut s = settings();
    s.homing_debounce_ms = 5;
    let mut b = boot(&spec, s);
    let (out, _) = home(&mut b, "$H", 10.0);
    assert!(out.ends_with("ok\r\n") && !out.contains("ALARM"), "{out}");
    let first = at(&b);
    for (k, target) in ["X-200 Y-20 Z-60", "X-3 Y-250 Z-2", "X-150 Y-150 Z-40"].iter().enumerate() {
        ok(&mut b, &format!("G53 G0 {target}"));
        wait_idle(&mut b, 5.0);
        let (out, _) = home(&mut b, "$H", 10.0);
        assert!(out.ends_with("ok\r\n") && !out.contains("ALARM"), "{k}: {out}");
        let now = at(&b);
        for i in 0..3 {
            assert!((now[i] - first[i]).abs() <= 1, "{k}: axis {i} at {now:?}, first {first:?}");
        }
    }
}

#[test]
fn hx_homes_x_alone() {
    let mut b = boot(&gantry_spec(), settings());
    let before = at(&b);
    let (out, _) = home(&mut b, "$HX", 10.0);
    assert!(out.ends_with("ok\r\n") && !out.contains("ALARM"), "{out}");
    let now = at(&b);
    assert_eq!(now[0], 149 * 80, "X 1 mm before its switch at 300 mm (started at 150)");
    assert_eq!((now[1], now[2]), (before[1], before[2]), "Y and Z did not move");
    assert!(status(&mut b).starts_with("<Idle|MPos:-1.000,0.000,0.000"), "{}", status(&mut b));
    // `$H` with homing disabled is error:5.
    assert!(reply(&mut b, "$22=0").contains("ok"));
    assert!(reply(&mut b, "$H").contains("error:5"));
}
