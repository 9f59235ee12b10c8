//! Probing, G38.2–G38.5, as Grbl 1.1: the probe edge stops the move at the engine's next tick
//! (at most one more step), the planner and `[PRB:]` take the pulses made; no contact is
//! ALARM:5 for G38.2/G38.4 only; a probe already in the looked-for state is ALARM:4; bad
//! words get Grbl's errors.

mod protocol_rig;

use protocol_rig::Bench;

/// A 3-axis bench (defaults) with a probe switch on Z at `at_mm` (machine mm).
fn bench(at_mm: f64) -> (Bench<3>, f64) {
    bench_in(at_mm, ddastep::grbl::settings::Settings::BENCH)
}

fn bench_in(at_mm: f64, s: ddastep::grbl::settings::Settings) -> (Bench<3>, f64) {
    let mut b = Bench::<3>::new(s);
    let spm = b.ctl.settings().steps_per_mm[2] as f64;
    b.probe = Some((2, (at_mm * spm).round() as i32));
    b.take();
    (b, spm)
}

fn mm(steps: i32, spm: f64) -> String {
    format!("{:.3}", steps as f64 / spm)
}

#[test]
fn g38_2_stops_at_the_trip_and_reports_it() {
    g38_2_in(ddastep::grbl::settings::Settings::BENCH);
}

#[test]
fn g38_2_in_s_mode_stops_at_the_trip_and_reports_it() {
    g38_2_in(ddastep::grbl::settings::Settings { shape: ddastep::motion::ramp::Shape::SCurve, ..ddastep::grbl::settings::Settings::BENCH });
}

fn g38_2_in(s: ddastep::grbl::settings::Settings) {
    let (mut b, spm) = bench_in(-5.0, s);
    b.run_ms(2);
    let r = b.line("G38.2 Z-10 F100");
    assert_eq!(b.probe_edges.len(), 1, "one contact edge: {:?}", b.probe_edges);
    let edge = b.probe_edges[0][2];
    let at = b.shared.positions();
    // The engine drops the move at its next tick: at most one step past the edge.
    assert!((edge - at[2]).abs() <= 1, "edge at {edge}, stopped at {}", at[2]);
    assert_eq!(r, format!("[PRB:0.000,0.000,{}:1]\r\nok\r\n", mm(at[2], spm)));
    // Nothing more runs: the rest of the move was flushed.
    b.run_ms(200);
    assert_eq!(b.shared.positions(), at);
    assert_eq!(b.ctl.pending_moves(), 0);
    // `$#` keeps it; the status shows the probe input; the planner goes on from the trip.
    let params = b.line("$#");
    assert!(params.contains(&format!("[PRB:0.000,0.000,{}:1]", mm(at[2], spm))), "{params}");
    assert!(b.status().contains("|Pn:P"), "probe in contact shows as Pn:P");
    assert_eq!(b.line("G91 G0 Z2"), "ok\r\n");
    b.run_to_idle(5_000);
    assert_eq!(b.shared.positions()[2], at[2] + (2.0 * spm) as i32);
    assert!(!b.status().contains("Pn:"));
    let g = b.line("$G");
    assert!(g.starts_with("[GC:G0 "), "{g}");
}

#[test]
fn g38_4_stops_when_contact_is_lost() {
    let (mut b, spm) = bench(-5.0);
    assert_eq!(b.line("G0 Z-6"), "ok\r\n");
    b.run_to_idle(10_000);
    let r = b.line("G38.4 Z0 F100");
    let edge = *b.probe_edges.last().unwrap();
    let at = b.shared.positions();
    assert!(at[2] > (-5.0 * spm) as i32 && (edge[2] - at[2]).abs() <= 1, "edge {edge:?} at {at:?}");
    assert_eq!(r, format!("[PRB:0.000,0.000,{}:1]\r\nok\r\n", mm(at[2], spm)));
    assert!(b.line("$G").starts_with("[GC:G38.4 "));
}

#[test]
fn g38_3_without_contact_takes_the_end_without_alarm() {
    let (mut b, _) = bench(-50.0);
    let r = b.line("G38.3 Z-2 F200");
    assert_eq!(r, "[PRB:0.000,0.000,-2.000:0]\r\nok\r\n");
    assert!(b.status().starts_with("<Idle|"));
    assert_eq!(b.line("G0 Z0"), "ok\r\n");
}

#[test]
fn g38_2_without_contact_is_alarm_5() {
    let (mut b, _) = bench(-50.0);
    let r = b.line("G38.2 Z-2 F200");
    // Grbl: the alarm, then the report (the last probe position, flag 0), then the line's ok.
    assert_eq!(r, "ALARM:5\r\n[PRB:0.000,0.000,0.000:0]\r\nok\r\n");
    assert_eq!(b.shared.positions()[2], -2 * b.ctl.settings().steps_per_mm[2] as i32);
    assert!(b.status().starts_with("<Alarm|"));
    assert_eq!(b.line("G0 Z0"), "error:9\r\n");
    assert!(b.line("$X").ends_with("ok\r\n"));
    assert_eq!(b.line("G0 Z0"), "ok\r\n");
}

#[test]
fn probe_already_triggered_is_alarm_4_and_nothing_moves() {
    let (mut b, _) = bench(0.0);
    b.run_ms(2);
    assert_eq!(b.line("G38.2 Z-10 F100"), "ALARM:4\r\nok\r\n");
    b.run_ms(100);
    assert_eq!(b.shared.positions(), [0, 0, 0]);
    assert!(b.status().starts_with("<Alarm|"));
    // Away from a probe that is not in contact: the same alarm.
    let (mut b, _) = bench(-50.0);
    b.run_ms(2);
    assert_eq!(b.line("G38.5 Z-10 F100"), "ALARM:4\r\nok\r\n");
    assert_eq!(b.shared.positions(), [0, 0, 0]);
}

#[test]
fn bad_probe_words_get_grbls_errors() {
    let (mut b, _) = bench(-5.0);
    assert_eq!(b.line("G38.2 F100"), "error:26\r\n", "no axis words");
    assert_eq!(b.line("G38.2 Z0 F100"), "error:33\r\n", "target is the position");
    assert_eq!(b.line("G38.2 Z-1"), "error:22\r\n", "no feed rate");
    assert_eq!(b.line("G38.1 Z-1 F100"), "error:20\r\n");
    assert_eq!(b.line("G38.6 Z-1 F100"), "error:20\r\n");
    // Grbl checks the axis-command conflict first (G0/G1/G2/G3/G38 all claim the axis words).
    assert_eq!(b.line("G38.2 G1 Z-1 F100"), "error:24\r\n", "two motion commands");
    assert_eq!(b.line("G53 G38.2 Z-1 F100"), "error:30\r\n");
    assert_eq!(b.line("G93 G38.2 Z-1"), "error:22\r\n", "G93 needs F on the line");
    assert_eq!(b.shared.positions(), [0, 0, 0]);
    assert_eq!(b.line("$G").split(' ').next(), Some("[GC:G0"));
}

#[test]
fn reset_during_a_probe_cycle_disarms_it() {
    let (mut b, spm) = bench(-5.0);
    b.send("G38.2 Z-10 F100\n");
    b.run_ms(300);
    assert!(b.shared.positions()[2] < 0, "probing");
    b.byte(0x18);
    b.run_ms(50);
    assert!(b.take().contains("Grbl"));
    let at = b.shared.positions();
    assert!(b.status().starts_with("<Alarm|"), "reset while moving: ALARM:3");
    assert!(b.line("$X").ends_with("ok\r\n"));
    // A move through the probe's contact afterwards is not stopped by it.
    assert_eq!(b.line("G91 G1 Z-6 F3000"), "ok\r\n");
    b.run_to_idle(10_000);
    assert_eq!(b.shared.positions()[2], at[2] - (6.0 * spm) as i32);
    assert!(b.line("$#").contains(":0]"), "no success flag after the reset");
}
