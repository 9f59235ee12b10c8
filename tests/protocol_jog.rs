//! `$J=` jogging as in Grbl 1.1's jogging.md: jog state, modal state untouched, cancel with
//! 0x85 (or `!`) decelerates, flushes the queued jogs and keeps the position exact.

mod protocol_rig;

use ddastep::queue::State;
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
    let mut b = Bench::<3>::with_defaults();
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
fn feed_hold_cancels_a_jog_like_0x85() {
    cancel_with(b'!');
}

#[test]
fn jog_cancel_when_idle_and_door_byte_do_nothing() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    b.byte(0x85);
    b.byte(0x84);
    b.run_ms(5);
    assert!(b.status().starts_with("<Idle|"));
    assert_eq!(b.line("G0 X1"), "ok\r\n");
}
