//! Encoder feedback in the controller (issue 14), on the host bench with a modeled encoder:
//! the `|Enc:` status field, step loss with feed hold (`$98=0`) or alarm (`$98=1`),
//! and no false alarm through ramps and reversals with a lagging motor (proptest).

mod protocol_rig;

use ddastep::motion::shared::State;
use ddastep::grbl::settings::Settings;
use proptest::prelude::*;
use protocol_rig::{Bench, EncoderModel};

/// Bench settings (100 steps/mm, 10 000 mm/s²) on 3 axes, an encoder of `cps` counts per step
/// on X with `threshold` steps, `lag` ms allowance and `$98=alarm`.
fn bench(cps: f64, threshold: u32, lag: f64, alarm: bool) -> Bench<3> {
    let mut s = Settings { axes: 3, ..Settings::BENCH };
    for (id, v) in [(87, 1.0), (88, cps), (97, threshold as f64), (98, alarm as u8 as f64), (99, lag)] {
        s.set(id, v as f32, 3).unwrap();
    }
    let mut b = Bench::<3>::new(s);
    b.encoder = Some(EncoderModel::new(0, cps, 0));
    b.take();
    b
}

/// Runs until `text` appears in the output (at most `max_ms`), returning the output so far.
fn run_until(b: &mut Bench<3>, text: &str, max_ms: u32) -> String {
    let mut out = String::new();
    for _ in 0..max_ms {
        b.tick_ms();
        out += &b.take();
        if out.contains(text) {
            return out;
        }
    }
    panic!("no {text:?} within {max_ms} ms: {out}");
}

#[test]
fn status_and_enc_command_follow_the_encoder() {
    let mut b = bench(4.0, 20, 1.0, false);
    let st = b.status();
    assert!(st.contains("|FS:0,0|") && st.ends_with("|Enc:0.000,0>\r\n"), "{st}");
    assert_eq!(b.ctl.encoder_error_steps(), Some(0.0));
    assert_eq!(b.line("$ENC"), "[ENC:X,0.000,0.000,0]\r\nok\r\n");
    assert_eq!(b.line("G1 X50 F3000"), "ok\r\n");
    b.run_ms(400);
    // Cruising at 3000 mm/min: the 8 ms window sees it to the count (4 counts per step).
    let st = b.status();
    let enc = st.split("|Enc:").nth(1).unwrap().trim_end_matches(">\r\n");
    let (_, speed) = enc.split_once(',').unwrap();
    assert_eq!(speed, "3000", "{st}");
    b.run_to_idle(5000);
    assert_eq!(b.ctl.encoder_error_steps(), Some(0.0));
    // 5000 steps × 4 counts: the encoder's own position; standing still once the window passed.
    b.run_ms(8);
    assert!(b.status().contains("|Enc:50.000,0>"));
    assert_eq!(b.line("$ENC"), "[ENC:X,50.000,50.000,0]\r\nok\r\n");
    // Off: no field, no check, and `$ENC` is refused.
    assert_eq!(b.line("$87=0"), "ok\r\n");
    assert!(b.line("$ENC").starts_with("error:"));
    assert!(!b.status().contains("Enc"));
    assert_eq!(b.ctl.encoder_error_steps(), None);
}

#[test]
fn slip_feed_holds_and_resume_rearms() {
    let mut b = bench(4.0, 20, 1.0, false);
    assert_eq!(b.line("G1 X50 F3000"), "ok\r\n");
    b.run_ms(300);
    // The rotor slips 30 steps back (a crash): the next check sees it.
    b.encoder.as_mut().unwrap().slipped = 120.0;
    b.tick_ms();
    assert_eq!(b.take(), "[MSG:Step loss X 30]\r\n");
    run_until(&mut b, "", 1);
    b.run_ms(200);
    assert_eq!(b.shared.state(), State::Held);
    assert!(b.status().starts_with("<Hold:0"));
    // The deviation stays while held; no second report.
    assert_eq!(b.ctl.encoder_error_steps(), Some(30.0));
    // Resume accepts the position: the move finishes without another report.
    b.send("~");
    b.run_to_idle(5000);
    assert!(!b.take().contains("Step loss"));
    assert_eq!(b.shared.positions()[0], 5000);
    assert_eq!(b.ctl.encoder_error_steps(), Some(0.0));
    b.run_ms(8);
    assert!(b.status().ends_with("|Enc:50.000,0>\r\n"));
}

#[test]
fn missed_steps_alarm_17_locks_until_reset() {
    let mut b = bench(1.0, 10, 1.0, true);
    assert_eq!(b.line("G1 X50 F3000"), "ok\r\n");
    assert_eq!(b.line("G1 X0"), "ok\r\n");
    b.run_ms(300);
    // From now on the motor misses one step in ten: at 5000 steps/s the deviation grows half
    // a step per ms.
    let mut out = String::new();
    let mut lost = 0.0;
    for _ in 0..100 {
        let before = b.shared.positions()[0];
        b.tick_ms();
        lost += (b.shared.positions()[0] - before) as f64 / 10.0;
        b.encoder.as_mut().unwrap().slipped = lost;
        out += &b.take();
        if out.contains("Step loss") {
            break;
        }
    }
    // Limit: (10 + 1) steps + 1 count (1 count per step) + 5 steps/ms × 1 ms of lag = 17
    // steps; reported at the first check past it (half a step per check).
    let steps: f64 = out.trim_end().trim_end_matches(']').rsplit(' ').next().unwrap().parse().unwrap();
    assert!(out.starts_with("[MSG:Step loss X ") && (17.0..=18.0).contains(&steps), "{out}");
    out += &run_until(&mut b, "ALARM:17", 500);
    assert!(out.ends_with("ALARM:17\r\n[MSG:Reset to continue]\r\n"), "{out}");
    let stopped = b.shared.positions();
    b.run_ms(100);
    assert_eq!(b.shared.positions(), stopped);
    // Nothing more is read (the queued G1 X0 was dropped) until Ctrl-X, then $X.
    b.send("\x18");
    assert!(b.take().contains("Grbl 1.1h"));
    assert_eq!(b.line("G0 X1"), "error:9\r\n");
    assert_eq!(b.line("$X"), "[MSG:Caution: Unlocked]\r\nok\r\n");
    // In the alarm state the check followed the position: armed again from here.
    assert_eq!(b.ctl.encoder_error_steps(), Some(0.0));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// Random moves (with reversals, short triangles and long cruises) on a motor that trails
    /// its commands by up to 2 ms, with a lag allowance of 3 ms: no step loss is reported.
    #[test]
    fn no_false_alarm_through_ramps_and_reversals(
        moves in prop::collection::vec((-400i32..400, -100i32..100, 100u32..30_000), 12),
        cps in prop::sample::select(vec![0.25, 1.0, 4.0]),
        lag in 0usize..=2,
    ) {
        let mut b = bench(cps, 20, 3.0, true);
        b.encoder.as_mut().unwrap().lag_ms = lag;
        for (x, y, f) in moves {
            let line = format!("G1 X{:.2} Y{:.2} F{f}", x as f64 / 10.0, y as f64 / 10.0);
            prop_assert_eq!(b.line(&line), "ok\r\n");
        }
        b.run_to_idle(60_000);
        let out = b.take();
        prop_assert!(!out.contains("Step loss") && !out.contains("ALARM"), "{}", out);
    }
}
