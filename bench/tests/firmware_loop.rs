//! Firmware in the loop: the release ELF on the emulated Blue Pill, driven over its serial
//! line like a G-code sender, its pins read like a logic analyzer.

mod firmware_rig;

use ddastep_bench::emu::HZ;
use firmware_rig::*;
use proptest::prelude::*;

#[test]
fn paper_532_at_50_khz_exact_counts_pattern_and_cruise() {
    let mut b = boot();
    ok(&mut b, "G91");
    ok(&mut b, "G1 X50 Y30 Z20 F36986.484");
    wait_idle(&mut b, 2.0);
    let s = steps(&b);
    assert_eq!(net(&s), [5000, 3000, 2000, 0, 0, 0, 0]);
    assert!(s.iter().all(|s| s.positive));
    // Exact pattern: per five master steps, Y at 1,3,5 and Z at 2,4 (same edge as X).
    assert_eq!(assert_paper_pattern(&s), 5000);
    // Cruise: 1000 master steps in the middle at 50 kHz ± 0.5 %.
    let x: Vec<u64> = s.iter().filter(|s| s.axis == 0).map(|s| s.cycle).collect();
    let rate = 1000.0 * HZ as f64 / (x[3000] - x[2000]) as f64;
    assert!((rate - 50_000.0).abs() < 250.0, "cruise {rate} Hz");
    let r = b.report();
    assert_eq!(r.overruns, 0);
    assert!(r.max_slave_deviation_steps.is_some_and(|d| d <= 0.5), "{:?}", r.max_slave_deviation_steps);
}

#[test]
fn pulse_width_and_direction_setup_hold_on_every_edge() {
    let mut b = boot();
    ok(&mut b, "$0=2.5");
    ok(&mut b, "$29=7");
    ok(&mut b, "G91");
    for line in ["G1 X5 Y-3 Z1 F20000", "G1 X-5 Y3 Z-1 F20000", "G1 X0.5 Y0.5 F3000", "G1 X-1 Y-1 Z1 F9000"] {
        ok(&mut b, line);
    }
    wait_idle(&mut b, 2.0);
    let r = b.report();
    let v = serde_json_value(&r);
    for axis in ["X", "Y", "Z"] {
        let a = &v["axes"][axis];
        assert!(a["min_high_ns"].as_f64().unwrap() >= 2500.0, "{axis}: {a}");
        assert!(a["min_dir_setup_ns"].as_f64().unwrap() >= 7000.0, "{axis}: {a}");
        assert!(a["rising_edges"].as_u64().unwrap() > 0);
    }
    assert_eq!(net(&steps(&b))[..3], [-50, -50, 100]);
}

#[test]
fn feed_hold_and_resume_mid_move_end_exactly() {
    let mut b = boot();
    ok(&mut b, "G91 G1 X100 Y-40 F12000");
    b.run_seconds(0.15).unwrap();
    b.serial_send(b"!");
    b.run_seconds(0.1).unwrap();
    assert!(status(&mut b).starts_with("<Hold:0"), "{}", status(&mut b));
    let held = steps(&b).len();
    b.run_seconds(0.2).unwrap();
    assert_eq!(steps(&b).len(), held, "steps while held");
    let n = net(&steps(&b));
    assert!(n[0] > 0 && n[0] < 10_000, "paused mid-move at {n:?}");
    b.serial_send(b"~");
    wait_idle(&mut b, 3.0);
    assert_eq!(net(&steps(&b))[..2], [10_000, -4_000]);
    assert!(status(&mut b).contains("MPos:100.000,-40.000,"));
}

#[test]
fn serial_garbage_gets_errors_while_the_accepted_move_completes() {
    let mut b = boot();
    ok(&mut b, "G91 G1 X30 Y20 Z-10 F6000");
    for (line, code) in [("X--5", "error:2"), ("G1 Q5", "error:"), ("$0=abc", "error:2"), ("XNaN", "error:2")] {
        let r = reply(&mut b, line);
        assert!(r.contains(code), "{line}: {r}");
    }
    // Binary junk and an overlong line, each ending in a newline.
    let mut junk = vec![0u8, 0x01, 0x7f, b'#', b'\n'];
    junk.extend(std::iter::repeat_n(b'G', 300));
    junk.push(b'\n');
    b.serial_send(&junk);
    b.run_seconds(0.05).unwrap();
    assert!(b.serial_output().contains("error:11"), "overlong line: {}", b.serial_output());
    wait_idle(&mut b, 3.0);
    assert_eq!(net(&steps(&b))[..3], [3000, 2000, -1000]);
    assert!(b.fault().is_none());
}

#[test]
fn soft_reset_stops_motion_and_keeps_position_equal_to_pulses() {
    let mut b = boot();
    ok(&mut b, "G91 G1 X200 F6000");
    ok(&mut b, "G1 X-200");
    b.run_seconds(0.3).unwrap();
    b.serial_send(&[0x18]);
    b.run_seconds(0.1).unwrap();
    let out = b.serial_output();
    assert_eq!(out.matches("Grbl").count(), 2, "banner again: {out}");
    assert!(out.contains("ALARM:3"), "{out}");
    let n = net(&steps(&b));
    b.run_seconds(0.2).unwrap();
    assert_eq!(net(&steps(&b)), n, "no steps after reset");
    assert!(n[0] > 0 && n[0] < 20_000);
    ok(&mut b, "$X");
    let st = status(&mut b);
    let want = format!("MPos:{:.3},", n[0] as f64 / 100.0);
    assert!(st.contains(&want), "{st} vs {want}");
    // And it moves again.
    ok(&mut b, "G90 G1 X0 F6000");
    wait_idle(&mut b, 3.0);
    assert_eq!(net(&steps(&b))[0], 0);
}

/// A decimal with 3 fraction digits (`-4.595`) times 100 steps/mm, rounded half away from
/// zero, in integers: thousandths / 10.
fn exact_steps_at_100(text: &str) -> i64 {
    let thousandths: i64 = text.replace('.', "").parse().unwrap();
    let n = (thousandths.abs() + 5) / 10;
    if thousandths < 0 {
        -n
    } else {
        n
    }
}

fn serde_json_value(r: &ddastep_bench::emu::Report) -> serde_json::Value {
    serde_json::to_value(r).expect("report serializes")
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    #[test]
    fn random_moves_emit_exactly_the_commanded_steps(
        moves in prop::collection::vec((-20.0f64..20.0, -20.0f64..20.0, -5.0f64..5.0, 500.0f64..20_000.0), 1..4)
    ) {
        let mut b = boot();
        ok(&mut b, "G90");
        let mut want = [0i64; 3];
        for (x, y, z, f) in &moves {
            let line = format!("G1 X{x:.3} Y{y:.3} Z{z:.3} F{f:.0}");
            ok(&mut b, &line);
            // As the firmware (and Grbl 1.1h) rounds it: the decimal as written times 100
            // steps/mm, exactly, halves away from zero (X4.595 is 459.5 steps: 460).
            want = [x, y, z].map(|v| exact_steps_at_100(&format!("{v:.3}")));
        }
        wait_idle(&mut b, 10.0);
        let n = net(&steps(&b));
        prop_assert_eq!(&n[..3], &want[..]);
        prop_assert_eq!(b.report().overruns, 0);
    }
}

#[test]
fn pin_invert_setting_answers_ok_and_reaches_flash_with_no_restart() {
    let mut b = boot();
    // Let the banner finish, so the TX interrupt is off when the reply is queued.
    b.run_seconds(0.1).unwrap();
    ok(&mut b, "$3=5");
    let saved = stored(&mut b).expect("an image in flash");
    assert_eq!(saved.settings.dir_invert, 5);
    b.run_seconds(0.1).unwrap();
    assert_eq!(b.serial_output().matches("Grbl").count(), 1, "{}", b.serial_output());
    assert!(b.system_resets().is_empty());
}
