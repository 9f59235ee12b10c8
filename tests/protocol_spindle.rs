//! Spindle, laser and coolant through the real controller and engine (host bench).

mod protocol_rig;

use ddastep::motion::moves::Overrides;
use ddastep::motion::shared::State;
use ddastep::grbl::settings::Settings;
use ddastep::grbl::spindle::{duty, PwmTiming};
use protocol_rig::{replies, Bench};

const ARR: u16 = 35_999; // $33 = 1000 Hz

fn out(b: &Bench<3>) -> ddastep::grbl::spindle::SpindleOut {
    b.actions.last().expect("polled").spindle
}

#[test]
fn m3_m4_m5_drive_pwm_enable_and_direction() {
    let mut b = Bench::<3>::with_defaults();
    b.run_ms(1);
    assert_eq!(b.actions[0].pwm, Some(PwmTiming { psc: 1, arr: ARR }));
    assert_eq!(out(&b).ccr, 0);
    assert!(!out(&b).enable);
    assert_eq!(replies(&b.line("M3 S500")), (1, 0));
    b.run_ms(1);
    assert_eq!((out(&b).ccr, out(&b).enable, out(&b).ccw), (18_000, true, false));
    b.line("M4 S1000");
    b.run_ms(1);
    assert_eq!((out(&b).ccr, out(&b).enable, out(&b).ccw), (36_000, true, true));
    assert!(b.line("$G").starts_with("[GC:G0 G54 G17 G21 G90 G94 M4 M9 T0 F0 S1000]"));
    // Spindle override: 50 % halves the duty.
    b.shared.set_overrides(Overrides { spindle: 50, ..Overrides::NONE });
    b.run_ms(1);
    assert_eq!(out(&b).ccr, 18_000);
    b.shared.set_overrides(Overrides::NONE);
    b.line("M5");
    b.run_ms(1);
    assert_eq!((out(&b).ccr, out(&b).enable), (0, false));
    // $30/$31 and $33.
    b.line("$30=24000");
    b.line("$31=6000");
    let polls = b.actions.len();
    b.line("$33=5000");
    b.run_ms(1);
    let pwm: Vec<_> = b.actions[polls..].iter().filter_map(|a| a.pwm).collect();
    assert_eq!(pwm, [PwmTiming { psc: 0, arr: 14_399 }], "one new timing for TIM1");
    b.line("M3 S15000");
    b.run_ms(1);
    assert_eq!(out(&b).ccr, 7_200);
    b.line("S100");
    b.run_ms(1);
    assert_eq!(out(&b).ccr, 1, "below $31: the lowest duty");
    assert!(b.line("M3 M4").starts_with("error:21"));
    assert!(b.line("M7 M9").starts_with("error:21"));
}

#[test]
fn spindle_changes_wait_for_the_queue_outside_laser_mode() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G1 X20 F6000");
    assert!(b.ctl.pending_moves() > 0);
    // The line is held until the move has finished, then the spindle starts.
    b.line("M3 S1000");
    assert_eq!(b.ctl.pending_moves(), 0);
    assert_eq!(b.shared.positions()[0], 2000);
    b.run_ms(1);
    assert_eq!(out(&b).ccr, 36_000);
    // An S change while it turns waits too.
    b.line("G1 X40");
    b.line("S500");
    assert_eq!(b.shared.positions()[0], 4000);
}

#[test]
fn coolant_pins_follow_m7_m8_m9_and_program_end() {
    let mut b = Bench::<3>::with_defaults();
    b.line("M7");
    b.run_ms(1);
    assert!(out(&b).mist && !out(&b).flood);
    b.line("M8");
    b.run_ms(1);
    assert!(out(&b).mist && out(&b).flood);
    assert!(b.line("$G").contains(" M7 M8 "), "{}", b.line("$G"));
    b.line("M9");
    b.run_ms(1);
    assert!(!out(&b).mist && !out(&b).flood);
    b.line("M3 S300 M8");
    b.line("M2");
    b.run_ms(1);
    assert_eq!(out(&b), Default::default(), "M2 stops spindle and coolant");
    assert!(b.line("$G").contains(" M5 M9 "));
}

/// Runs until idle, returning per millisecond (master rate, compare value).
fn trace(b: &mut Bench<3>, max_ms: u32) -> Vec<(u32, u16)> {
    let mut t = Vec::new();
    for _ in 0..max_ms {
        b.tick_ms();
        t.push((b.shared.rate_hz(), out(b).ccr));
        if !b.ctl.busy() && b.ctl.pending_moves() == 0 && b.shared.state() == State::Idle {
            break;
        }
    }
    t
}

#[test]
fn laser_m4_power_follows_the_rate_through_the_ramps() {
    let mut b = Bench::<3>::new(Settings { laser_mode: true, ..Settings::BENCH });
    b.line("G1 F3000 M4 S1000");
    b.run_ms(2);
    assert_eq!(out(&b).ccr, 0, "M4: off while not moving");
    b.send("G1 X30\n");
    let t = trace(&mut b, 5_000);
    // 50 mm/s = 5 kHz cruise; the ramp from 1 kHz at 10^6 steps/s² lasts 4 ms each way.
    let cruise = 5_000.0;
    let mut ramp_points = 0;
    for &(rate, ccr) in &t {
        let want = duty(1000.0 * (rate as f32 / cruise).min(1.0), 0.0, 1000.0, ARR);
        // The rig polls right after running the engine, reading the same rate.
        assert!((ccr as i64 - want as i64).abs() <= 1, "rate {rate} Hz: ccr {ccr}, want {want}");
        if rate > 0 && rate < 4_900 {
            ramp_points += 1;
            assert!(ccr > 0 && ccr < 36_000, "partial power on the ramp: {ccr}");
        }
    }
    assert!(ramp_points >= 4, "{t:?}");
    assert!(t.iter().any(|&(_, c)| c == 36_000), "full power at cruise");
    assert_eq!(t.last().unwrap().1, 0, "off when the move ends");
}

#[test]
fn laser_s_changes_do_not_stop_motion_and_g0_is_dark() {
    let mut b = Bench::<3>::new(Settings { laser_mode: true, ..Settings::BENCH });
    b.line("G1 F600 M3 S100");
    b.run_ms(1);
    assert_eq!(out(&b).ccr, 3_600, "M3 in G1 mode: on while stopped (focusing)");
    b.line("G1 X10 S200");
    b.line("G1 X20 S900");
    // Both accepted while the first still runs: no stop for the S change.
    assert_eq!(b.ctl.pending_moves(), 2);
    let mut seen = Vec::new();
    while b.ctl.pending_moves() > 0 {
        b.tick_ms();
        if b.shared.state() == State::Run {
            seen.push(out(&b).ccr);
        }
    }
    assert!(seen.contains(&7_200) && seen.contains(&32_400), "S200 then S900 while moving");
    b.line("G0 X0");
    b.tick_ms();
    let mut dark = true;
    while b.ctl.pending_moves() > 0 {
        b.tick_ms();
        dark &= out(&b).ccr == 0;
    }
    assert!(dark, "G0: laser off");
    // A feed hold turns the laser off.
    b.line("G1 X30 S500");
    b.run_ms(20);
    b.shared.set_hold(true);
    b.run_ms(50);
    assert_eq!(b.shared.state(), State::Held);
    assert_eq!(out(&b).ccr, 0);
    b.shared.set_hold(false);
    b.run_to_idle(10_000);
}

#[test]
fn status_reports_spindle_speed_and_accessories() {
    let mut b = Bench::<3>::with_defaults();
    assert!(b.status().contains("|FS:0,0"));
    b.line("M4 S500 M8");
    let st = b.status();
    assert!(st.contains("|FS:0,500"), "{st}");
    // `A:` rides with `Ov:` (Grbl's refresh rule): within ten reports.
    let reports: Vec<String> = (0..10).map(|_| b.status()).collect();
    assert!(reports.iter().any(|r| r.contains("|Ov:100,100,100|A:CF>")), "{reports:?}");
    // Above $30 the report shows $30, as Grbl's clamped speed.
    b.line("S5000");
    assert!(b.status().contains("|FS:0,1000"));
    b.line("M5 M9");
    let reports: Vec<String> = (0..10).map(|_| b.status()).collect();
    assert!(reports.iter().all(|r| r.contains("|FS:0,0") && !r.contains("|A:")), "{reports:?}");
}
