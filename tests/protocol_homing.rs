//! `$H` homing as in Grbl 1.1 (`limits_go_home`), on the host rig with limit switches: Z first,
//! then X and Y; seek, pull-off, locate, pull-off; Grbl's end position (−`$27` toward the max
//! end, −`$130+i` + `$27` toward the min end); `$HX`/`$HY`/`$HZ`; error:5 when disabled;
//! ALARM:9 (no switch within 1.5 × travel), ALARM:8 (pull-off leaves the switch closed),
//! ALARM:6 (Ctrl-X during the cycle).

mod protocol_rig;

use ddastep::grbl::settings::Settings;
use proptest::prelude::*;
use protocol_rig::Bench;

/// 100 steps/mm, homing on, 300 × 200 × 80 mm, 2 mm pull-off, fast seek, short debounce.
fn homing() -> Settings {
    let mut s = Settings { homing: true, soft_limits: true, axes: 3, ..Settings::BENCH };
    s.max_travel[..3].copy_from_slice(&[300.0, 200.0, 80.0]);
    s.homing_seek = 3000.0;
    s.homing_feed = 100.0;
    s.homing_pulloff = 2.0;
    s.homing_debounce_ms = 20;
    s
}

/// A rig with switches at the max ends, `at` steps from where the carriages start.
fn rig(s: Settings, at: [i32; 3]) -> Bench<3> {
    let mut b = Bench::<3>::new(s);
    b.switches = (0..3).map(|i| (i, at[i], true)).collect();
    b.take();
    b
}

/// Sends `$H…` and runs until its reply, noting whether `Home` showed in status reports.
fn home(b: &mut Bench<3>, cmd: &str) -> (String, bool) {
    b.send(cmd);
    b.send("\n");
    let mut saw_home = false;
    for n in 0..600_000 {
        if n % 50 == 0 {
            b.ctl.status_request();
        }
        b.tick_ms();
        saw_home |= b.text.contains("<Home|");
        if !b.ctl.busy() {
            break;
        }
    }
    b.run_ms(5);
    let out = b.take();
    let replies = out.lines().filter(|l| !l.starts_with('<')).collect::<Vec<_>>().join("\n");
    (replies, saw_home)
}

#[test]
fn full_cycle_ends_at_minus_pulloff_and_unlocks() {
    full_cycle_in(homing());
}

#[test]
fn full_cycle_in_s_mode_ends_at_minus_pulloff_and_unlocks() {
    // `$41=1`: every pass's ramps are S legs, the stops at the switches included.
    full_cycle_in(Settings { shape: ddastep::motion::ramp::Shape::SCurve, ..homing() });
}

fn full_cycle_in(s: Settings) {
    let mut b = rig(s, [12_345, 4_000, 777]);
    assert_eq!(b.line("G0 X-1"), "error:9\r\n", "homing lock at power-up");
    let (out, saw) = home(&mut b, "$H");
    assert_eq!(out, "ok", "{out}");
    assert!(saw, "status shows Home during the cycle");
    // Machine position −$27 on every axis; the engine stands 2 mm (200 steps) before each switch.
    assert_eq!(b.shared.positions(), [-200, -200, -200]);
    assert_eq!(b.ctl.planned_steps(), [-200, -200, -200]);
    // The carriages: switch − 200 steps, exactly.
    assert_eq!(b.carriage, [12_345 - 200, 4_000 - 200, 777 - 200]);
    assert_eq!(b.limit_mask(), 0);
    assert!(b.status().starts_with("<Idle|MPos:-2.000,-2.000,-2.000"));
    // Unlocked, soft limits valid: inside the box moves, beyond is refused (jog error:15).
    assert_eq!(b.line("G0 X-100 Y-50 Z-10"), "ok\r\n");
    b.run_to_idle(10_000);
    assert_eq!(b.line("$J=G91 X101 F1000"), "error:15\r\n");
}

#[test]
fn z_homes_before_x_and_y() {
    let mut b = rig(homing(), [3_000, 3_000, 3_000]);
    b.send("$H\n");
    let mut z_done_at = None;
    let mut xy_moved_at = None;
    for t in 0..200_000 {
        b.tick_ms();
        let p = b.shared.positions();
        if z_done_at.is_none() && p[2] < 3_000 && p[2] > 2_000 {
            z_done_at = Some(t); // Z off its switch after the seek
        }
        if xy_moved_at.is_none() && (p[0] != 0 || p[1] != 0) {
            xy_moved_at = Some(t);
        }
        if !b.ctl.busy() {
            break;
        }
    }
    assert!(b.take().contains("ok"));
    let (z, xy) = (z_done_at.unwrap(), xy_moved_at.unwrap());
    assert!(z < xy, "Z pulled off at {z} ms, X/Y started at {xy} ms");
    assert_eq!(b.shared.positions(), [-200, -200, -200]);
}

#[test]
fn single_axis_and_min_end_direction() {
    // $23=2: Y homes toward its min end; its machine position is −200 + 2 mm.
    let mut s = homing();
    s.homing_dir = 2;
    let mut b = rig(s, [5_000, 0, 5_000]);
    b.switches[1] = (1, -7_000, false);
    let (out, _) = home(&mut b, "$HY");
    assert_eq!(out, "ok");
    let p = b.shared.positions();
    assert_eq!((p[0], p[1], p[2]), (0, -19_800, 0), "only Y moved and was set");
    assert_eq!(b.carriage, [0, -7_000 + 200, 0]);
    let (out, _) = home(&mut b, "$HX");
    assert_eq!(out, "ok");
    assert_eq!(b.shared.positions()[0], -200);
    assert_eq!(b.line("$HA"), "error:3\r\n");
}

#[test]
fn disabled_is_error_5_and_busy_is_error_8() {
    let mut b = rig(Settings { axes: 3, ..Settings::BENCH }, [1000, 1000, 1000]);
    assert_eq!(b.line("$H"), "error:5\r\n");
    assert_eq!(b.line("$22=1"), "ok\r\n");
    assert_eq!(b.line("$X"), "ok\r\n");
    b.send("G1 X5 F600\n");
    b.run_ms(5);
    b.take();
    b.send("$H\n");
    b.run_ms(2);
    assert!(b.take().contains("error:8"), "not idle while moving");
}

#[test]
fn missing_switch_is_alarm_9_after_one_and_a_half_travel() {
    let mut b = rig(homing(), [1000, 1000, 1000]);
    b.switches.retain(|s| s.0 != 0); // no X switch
    let (out, _) = home(&mut b, "$H");
    assert!(out.starts_with("ALARM:9\nok"), "{out}");
    assert!(out.contains("Grbl 1.1h") && out.contains("'$H'|'$X' to unlock"), "{out}");
    // X searched 1.5 × 300 mm (it stopped when Y's seek ended, Y found its switch first).
    assert!(b.status().starts_with("<Alarm|"));
    assert_eq!(b.line("G0 X-1"), "error:9\r\n");
}

#[test]
fn a_switch_that_stays_closed_is_alarm_8() {
    // Z's switch stays pressed over more than the pull-off (a stuck switch).
    let mut b = rig(homing(), [1000, 1000, 1000]);
    b.switches[2] = (2, -100_000, true);
    let (out, _) = home(&mut b, "$HZ");
    assert!(out.starts_with("ALARM:8\nok"), "{out}");
    assert!(b.status().starts_with("<Alarm|"));
}

#[test]
fn already_on_the_switch_pulls_off_first() {
    let mut b = rig(homing(), [-50, -50, -50]);
    assert_eq!(b.limit_mask(), 7);
    let (out, _) = home(&mut b, "$H");
    assert_eq!(out, "ok");
    assert_eq!(b.shared.positions(), [-200, -200, -200]);
}

#[test]
fn reset_during_homing_is_alarm_6() {
    let mut b = rig(homing(), [20_000, 20_000, 20_000]);
    b.send("$H\n");
    b.run_ms(100);
    b.take();
    b.byte(0x18);
    b.run_ms(5);
    let out = b.take();
    assert!(out.starts_with("ALARM:6\r\n"), "{out}");
    assert!(b.status().starts_with("<Alarm|"));
}

#[test]
fn pulloff_not_below_travel_is_refused() {
    let mut b = rig(homing(), [1000, 1000, 1000]);
    assert_eq!(b.line("$27=80"), "ok\r\n");
    assert_eq!(b.line("$HZ"), "error:3\r\n");
    let (out, _) = home(&mut b, "$HX");
    assert_eq!(out, "ok", "X (300 mm travel) homes");
}

#[test]
fn homing_settings_are_stored_and_listed() {
    let mut b = rig(homing(), [1000, 1000, 1000]);
    for l in ["$23=3", "$24=50.5", "$25=1200", "$26=100", "$27=1.5"] {
        assert_eq!(b.line(l), "ok\r\n", "{l}");
    }
    let list = b.line("$$");
    for l in ["$23=3\r\n", "$24=50.500\r\n", "$25=1200.000\r\n", "$26=100\r\n", "$27=1.500\r\n"] {
        assert!(list.contains(l), "{l} in {list}");
    }
    let s = *b.ctl.settings();
    assert_eq!(Settings::decode(&s.to_bytes()), Some(s));
    assert_eq!(b.line("$26=70000"), "error:3\r\n");
    assert_eq!(b.line("$24=0"), "error:3\r\n");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    /// From any start, the cycle ends at the same place relative to the switches.
    #[test]
    fn any_start_ends_at_the_same_place(x in -20_000i32..20_000, y in -10_000i32..10_000, z in -4_000i32..4_000) {
        // Switches at fixed machine places; the carriages start at (x, y, z) from them.
        let at = [25_000 - x, 15_000 - y, 6_000 - z];
        let mut b = rig(homing(), at);
        let (out, _) = home(&mut b, "$H");
        prop_assert_eq!(out, "ok");
        prop_assert_eq!(b.shared.positions(), [-200, -200, -200]);
        // Machine −2 mm = 200 steps short of each switch, to the step.
        prop_assert_eq!(b.carriage, [at[0] as i64 - 200, at[1] as i64 - 200, at[2] as i64 - 200]);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]
    /// With any switches missing or already pressed, any pull-off and direction mask, `$H`
    /// either ends with every carriage exactly `$27` off its switch and Grbl's machine
    /// position, or is ALARM:9/8 in the alarm state: never a silent wrong position.
    #[test]
    fn never_a_wrong_position(
        frac in prop::array::uniform3(0.0f64..1.0),
        present in prop::array::uniform3(prop::bool::weighted(0.85)),
        dir in 0u8..8,
        pulloff in 1u32..50,
    ) {
        let mut s = homing();
        s.homing_dir = dir;
        s.homing_pulloff = pulloff as f32 / 10.0;
        let mut b = Bench::<3>::new(s);
        b.take();
        // Each axis's switch at its homing end, within the travel of the carriage's start (up
        // to 3 mm past it: already pressed).
        let mut sw = Vec::new();
        for i in 0..3 {
            if present[i] {
                let max = dir & 1 << i == 0;
                let d = (frac[i] * ([300.0, 200.0, 80.0][i] * 100.0 + 300.0)) as i32 - 300;
                sw.push((i, if max { d } else { -d }, max));
            }
        }
        b.switches = sw.clone();
        let (out, _) = home(&mut b, "$H");
        let pull = (pulloff * 10) as i64; // steps (100 steps/mm)
        if out == "ok" {
            prop_assert!(present.iter().all(|&p| p));
            let p = b.shared.positions();
            for &(i, at, max) in &sw {
                let travel = [300.0, 200.0, 80.0][i];
                let (carriage, mpos) = if max { (at as i64 - pull, -pull) } else { (at as i64 + pull, -(travel as i64) * 100 + pull) };
                prop_assert_eq!(b.carriage[i], carriage, "axis {}", i);
                prop_assert_eq!(p[i] as i64, mpos, "axis {}", i);
            }
        } else {
            prop_assert!(out.starts_with("ALARM:9\nok") || out.starts_with("ALARM:8\nok"), "{}", out);
            prop_assert!(!present.iter().all(|&p| p) || out.starts_with("ALARM:8"), "{}", out);
            prop_assert!(b.status().starts_with("<Alarm|"));
        }
    }
}
