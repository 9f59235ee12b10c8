//! `$J=` jogging as in Grbl 1.1's jogging.md: jog state, modal state untouched, cancel with
//! 0x85 (or `!`) decelerates, flushes the queued jogs and keeps the position exact.

mod protocol_rig;

use ddastep::motion::shared::State;
use protocol_rig::Bench;

#[test]
fn jog_moves_without_touching_the_modal_state() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    assert_eq!(b.line("$J=G21G91X10F500"), "ok\r\n"); // UGS's jog line
    b.run_ms(20);
    let s = b.status();
    assert!(s.starts_with("<Jog|MPos:"), "{s}");
    assert_eq!(b.line("G0 X1"), "error:9\r\n", "G-code is locked out while jogging");
    b.run_to_idle(5000);
    b.run_ms(2);
    assert_eq!(b.shared.positions(), [1000, 0, 0]);
    assert!(b.status().starts_with("<Idle|"));
    assert_eq!(b.line("$G"), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
    // G20 for one jog; absolute by default (G90 in force): X to 0.5 inch.
    assert_eq!(b.line("$J=G20X0.5F20"), "ok\r\n");
    b.run_to_idle(10_000);
    assert_eq!(b.shared.positions(), [1270, 0, 0]);
    // G53: machine coordinates even with a work offset.
    b.line("G10 L20 P1 X0");
    b.run_ms(2);
    assert_eq!(b.line("$J=G53X2F1000"), "ok\r\n");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [200, 0, 0]);
    assert_eq!(b.line("$J=X1Y1F1000"), "ok\r\n", "work coordinates otherwise");
    b.run_to_idle(5000);
    b.run_ms(2);
    assert_eq!(b.shared.positions(), [1370, 100, 0]);
}

#[test]
fn jog_refused_while_a_program_moves() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G1 X50 F3000");
    b.run_ms(10);
    assert_eq!(b.line("$J=G91X1F100"), "error:8\r\n");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [5000, 0, 0]);
}

/// Queues jogs, cancels mid-way with `cancel`, and checks the stop, the flush and the re-sync.
fn cancel_with(cancel: u8) {
    cancel_in(cancel, ddastep::grbl::settings::Settings::BENCH);
}

fn cancel_in(cancel: u8, s: ddastep::grbl::settings::Settings) {
    let mut b = Bench::<3>::new(s);
    b.take();
    for _ in 0..6 {
        assert_eq!(b.line("$J=G91X20F6000"), "ok\r\n");
    }
    assert!(b.ctl.pending_moves() > 1, "jogs queue like moves");
    b.run_ms(150);
    let before = b.shared.positions();
    b.byte(cancel);
    b.tick_ms();
    assert!(b.status().starts_with("<Jog|"), "decelerating is still Jog");
    b.run_to_idle(2000);
    b.run_ms(5);
    let at = b.shared.positions();
    assert!(at[0] > before[0] && at[0] < 12_000, "stopped along the path: {at:?}");
    assert_eq!(b.ctl.pending_moves(), 0, "queued jogs flushed");
    assert_eq!(b.shared.state(), State::Idle);
    assert!(!b.shared.hold_requested());
    assert_eq!(b.ctl.planned_steps(), at.map(i64::from), "planner re-synced to the engine");
    assert!(b.status().starts_with("<Idle|"));
    // The next jog starts exactly where the cancel stopped.
    assert_eq!(b.line("$J=G91X1F500"), "ok\r\n");
    b.run_to_idle(2000);
    assert_eq!(b.shared.positions(), [at[0] + 100, 0, 0]);
    // And a program runs again.
    assert_eq!(b.line("G90 G0 X0"), "ok\r\n");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [0, 0, 0]);
}

#[test]
fn jog_cancel_0x85_decelerates_flushes_and_resyncs() {
    cancel_with(0x85);
}

#[test]
fn jog_cancel_in_s_mode_decelerates_flushes_and_resyncs() {
    // `$41=1`: the way down is an S from where the cancel finds the walk.
    let s = ddastep::grbl::settings::Settings { shape: ddastep::motion::ramp::Shape::SCurve, ..ddastep::grbl::settings::Settings::BENCH };
    cancel_in(0x85, s);
}

#[test]
fn feed_hold_cancels_a_jog_like_0x85() {
    cancel_with(b'!');
}

#[test]
fn jog_cancel_when_idle_does_nothing() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    b.byte(0x85);
    b.run_ms(5);
    assert!(b.status().starts_with("<Idle|"));
    assert_eq!(b.line("G0 X1"), "ok\r\n");
}

/// Grbl runs queued jogs through its planner like program moves: consecutive `$J=` lines join
/// at speed, and 0x85 decelerates at the jog's acceleration across the buffered jogs (never
/// faster, never speeding up) before they are flushed.
#[test]
fn queued_jogs_join_at_speed_and_a_cancel_decelerates_across_them() {
    // 200 mm/s² on every axis (100 steps/mm): X's master changes by 20 Hz per ms.
    let mut s = ddastep::grbl::settings::Settings::BENCH;
    s.accel = [200.0; ddastep::MAX_AXES];
    let mut b = Bench::<3>::new(s);
    b.take();
    b.trace = Some(Vec::new());
    for _ in 0..10 {
        assert_eq!(b.line("$J=G91X5F3000"), "ok\r\n"); // 50 mm/s: 5 kHz
    }
    b.run_ms(700);
    let done = b.shared.moves_done();
    assert!(done >= 3, "{done} jogs done");
    assert_eq!(b.shared.rate_hz(), 5_000);
    let at = b.shared.positions()[0];
    let t0 = b.timer.now();
    b.byte(0x85);
    b.run_to_idle(2_000);
    let tr = b.trace.take().unwrap();
    // Every jog after the first ran into the next at its full 5 kHz.
    for w in tr.windows(2) {
        if w[1].2 == w[0].2 + 1 && w[1].2 <= done && w[0].2 >= 1 {
            assert_eq!(w[0].1, 5_000, "jog {} ended at {} Hz", w[0].2, w[0].1);
        }
    }
    // The cancel: from 50 mm/s down to the table's start (10 mm/s) at 200 mm/s² is
    // (50² − 10²) / 400 = 6 mm, through at least one more jog, slowing by one walk per ms.
    let after: Vec<_> = tr.iter().filter(|e| e.0 > t0 && e.1 > 0).collect();
    assert!(after.windows(2).all(|w| w[1].1 <= w[0].1), "never speeds up while cancelling");
    // (The table's entries are 202 Hz apart and it interpolates periods: within an entry the
    // rate may change faster by the ratio of its ends.)
    for w in after.windows(2) {
        let allowed = 20.0 * (1.0 + 202.0 / w[1].1 as f64) + 1.0;
        assert!((w[0].1 - w[1].1) as f64 <= allowed, "one walk (20 Hz) per ms at most: {:?}", w);
    }
    assert!(after.last().unwrap().2 > done, "decelerated across a jog boundary");
    let ms = (after.last().unwrap().0 - t0) as f64 / ddastep::TICKS_PER_MS as f64;
    // (±5 %: the engine spreads a ramp millisecond's work over the following ticks, so the last
    // rate change can land a few ms early or late against the ideal 200 ms.)
    assert!((190.0..=215.0).contains(&ms), "decelerated in {ms} ms (200 expected)");
    let moved = b.shared.positions()[0] - at;
    assert!((560..=640).contains(&moved), "{moved} steps after the cancel (600 expected)");
    assert_eq!(b.ctl.pending_moves(), 0, "the rest flushed");
    assert!(b.shared.positions()[0] < 5_000);
}
