//! Soft limits (`$20`, travel `$130+i`) as in Grbl 1.1: `$20=1` needs homing (`$22=1`,
//! error:10); a G-code target outside `-$130+i ..= 0` (machine mm) is ALARM:2 with no motion
//! and `[MSG:Reset to continue]`; a jog target outside is error:15 and changes nothing.

mod protocol_rig;

use ddastep::motion::shared::State;
use ddastep::grbl::settings::Settings;
use proptest::prelude::*;
use protocol_rig::Bench;

/// Bench settings (100 steps/mm) with homing and soft limits on and a 300 × 200 × 80 mm box.
fn boxed() -> Settings {
    let mut s = Settings { homing: true, soft_limits: true, axes: 3, ..Settings::BENCH };
    s.max_travel[..3].copy_from_slice(&[300.0, 200.0, 80.0]);
    s
}

/// A bench with [`boxed`] settings, unlocked (homing enabled boots in alarm).
fn unlocked() -> Bench<3> {
    let mut b = Bench::<3>::new(boxed());
    let banner = b.take();
    assert!(banner.contains("[MSG:'$H'|'$X' to unlock]"), "homing lock at power-up: {banner}");
    assert_eq!(b.line("G0 X-1"), "error:9\r\n");
    assert_eq!(b.line("$X"), "[MSG:Caution: Unlocked]\r\nok\r\n");
    b
}

#[test]
fn soft_limits_need_homing() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    assert_eq!(b.line("$20=1"), "error:10\r\n");
    assert_eq!(b.line("$22=1"), "ok\r\n");
    assert_eq!(b.line("$20=1"), "ok\r\n");
    let s = *b.ctl.settings();
    assert!(s.soft_limits && s.homing);
    // Stored: the flash image round-trips both flags.
    assert_eq!(Settings::decode(&s.to_bytes()), Some(s));
    let list = b.line("$$");
    assert!(list.contains("$20=1\r\n") && list.contains("$22=1\r\n"), "{list}");
    // Homing off turns soft limits off too.
    assert_eq!(b.line("$22=0"), "ok\r\n");
    let list = b.line("$$");
    assert!(list.contains("$20=0\r\n") && list.contains("$22=0\r\n"), "{list}");
    // An image claiming soft limits without homing is not a valid one.
    let bad = Settings { soft_limits: true, homing: false, ..Settings::DEFAULT };
    assert_eq!(Settings::decode(&bad.to_bytes()), None);
}

#[test]
fn gcode_beyond_travel_is_alarm_2_without_motion() {
    let mut b = unlocked();
    assert_eq!(b.line("G0 X-10 Y-5"), "ok\r\n");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [-1000, -500, 0]);
    // X+ of machine zero: refused with the alarm, the line gets no reply, nothing moves.
    b.send("G0 X1\n");
    b.run_ms(20);
    assert_eq!(b.take(), "ALARM:2\r\n[MSG:Reset to continue]\r\n");
    assert_eq!(b.shared.positions(), [-1000, -500, 0]);
    assert!(b.status().starts_with("<Alarm|MPos:-10.000,-5.000,0.000"));
    // Nothing more is read until Ctrl-X, which leaves the alarm state locked.
    assert!(!b.ctl.byte(b'$', &mut b.tx));
    b.byte(0x18);
    let t = b.take();
    assert!(t.starts_with("\r\nGrbl 1.1") && t.ends_with("[MSG:'$H'|'$X' to unlock]\r\n"), "{t}");
    assert!(!t.contains("ALARM:3"), "{t}");
    assert_eq!(b.line("G0 Y-1"), "error:9\r\n");
    assert_eq!(b.line("$X"), "[MSG:Caution: Unlocked]\r\nok\r\n");
    // Work offsets do not move the box: it is in machine coordinates.
    assert_eq!(b.line("G10 L2 P1 X-300"), "ok\r\n");
    b.send("G0 X-1\n"); // machine -301
    b.run_ms(5);
    assert!(b.take().starts_with("ALARM:2"));
    assert_eq!(b.shared.positions(), [-1000, -500, 0]);
}

#[test]
fn arcs_and_g28_targets_are_checked() {
    let mut b = unlocked();
    assert_eq!(b.line("G0 X-100 Y-100"), "ok\r\n");
    b.run_to_idle(5000);
    // A full circle of radius 60 about (-100,-150) ends in the box but dips below Y -200.
    b.send("G2 X-100 Y-100 J-60 F1000\n");
    b.run_ms(5);
    assert!(b.take().starts_with("ALARM:2"));
    assert_eq!(b.shared.positions(), [-10_000, -10_000, 0]);
    b.byte(0x18);
    b.line("$X");
    // Radius 40 stays in: it runs.
    assert_eq!(b.line("G2 X-100 Y-100 J-40 F3000"), "ok\r\n");
    b.run_to_idle(20_000);
    // G28 through an intermediate point outside the box.
    b.take();
    b.send("G28 Z5\n");
    b.run_ms(5);
    assert!(b.take().starts_with("ALARM:2"));
    assert_eq!(b.shared.positions(), [-10_000, -10_000, 0]);
}

#[test]
fn a_trip_while_moving_holds_then_flushes_keeping_the_position() {
    let mut b = unlocked();
    assert_eq!(b.line("G1 X-250 F30000"), "ok\r\n");
    b.run_ms(100);
    assert_eq!(b.shared.state(), State::Run);
    b.send("G0 X-301\n");
    b.tick_ms();
    assert_eq!(b.take(), "", "no alarm before the machine has stopped");
    for _ in 0..5000 {
        b.tick_ms();
        if b.text.contains("ALARM:2") {
            break;
        }
    }
    assert_eq!(b.take(), "ALARM:2\r\n[MSG:Reset to continue]\r\n");
    let stopped = b.shared.positions();
    assert!(stopped[0] > -25_000 && stopped[0] < 0, "decelerated short of the first target: {stopped:?}");
    b.run_ms(200);
    assert_eq!(b.shared.positions(), stopped, "flushed: nothing moves after the alarm");
    assert_eq!(b.ctl.pending_moves(), 0);
    b.byte(0x18);
    b.line("$X");
    // The planner took the exact position: a relative move lands exactly.
    assert_eq!(b.line("G91 G0 X-1"), "ok\r\n");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions()[0], stopped[0] - 100);
}

#[test]
fn jog_beyond_travel_is_error_15() {
    let mut b = unlocked();
    assert_eq!(b.line("$J=G91 X-20 F1000"), "ok\r\n");
    b.run_to_idle(5000);
    assert_eq!(b.line("$J=G91 X30 F1000"), "error:15\r\n");
    assert_eq!(b.line("$J=G53 Z-80.001 F1000"), "error:15\r\n");
    assert!(b.status().starts_with("<Idle|"));
    assert_eq!(b.shared.positions(), [-2000, 0, 0]);
    assert_eq!(b.line("$J=G53 Z-80 F6000"), "ok\r\n", "the box edge is inside");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [-2000, 0, -8000]);
}

#[test]
fn check_mode_trips_too() {
    let mut b = unlocked();
    assert!(b.line("$C").contains("Enabled"));
    b.send("G0 Y-201\n");
    b.run_ms(2);
    assert!(b.take().starts_with("ALARM:2"));
    b.byte(0x18);
    assert!(b.status().starts_with("<Alarm|"), "check mode left, alarm kept");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Random G90/G91 moves and jogs: whatever is accepted, the machine (planner and engine)
    /// never leaves the box; after a trip, a reset and `$X` carry on.
    #[test]
    fn no_accepted_move_leaves_the_box(
        moves in prop::collection::vec((0u8..3, -350.0f64..50.0, -250.0f64..50.0, -100.0f64..20.0), 1..12)
    ) {
        let mut b = unlocked();
        let travel = [300.0, 200.0, 80.0];
        for (kind, x, y, z) in moves {
            let text = match kind {
                0 => format!("G90 G0 X{x:.3} Y{y:.3} Z{z:.3}"),
                1 => format!("G91 G1 X{:.3} Y{:.3} F20000", x / 4.0, y / 4.0),
                _ => format!("$J=G53 X{x:.3} Z{z:.3} F20000"),
            };
            b.send(&text);
            b.send("\n");
            for _ in 0..3000 {
                b.tick_ms();
                let p = b.shared.positions();
                for i in 0..3 {
                    prop_assert!(p[i] <= 0 && p[i] as f64 >= -travel[i] * 100.0, "{text}: {p:?}");
                }
                if !b.ctl.busy() && b.shared.state() == State::Idle && b.ctl.pending_moves() == 0 {
                    break;
                }
                if b.text.contains("ALARM:2") {
                    break;
                }
            }
            let planned = b.ctl.planned_steps();
            for i in 0..3 {
                prop_assert!(planned[i] <= 0 && planned[i] as f64 >= -travel[i] * 100.0, "{text}: {planned:?}");
            }
            if b.take().contains("ALARM:2") {
                b.byte(0x18);
                b.take();
                prop_assert_eq!(b.line("$X"), "[MSG:Caution: Unlocked]\r\nok\r\n");
            }
        }
    }
}

#[test]
fn hard_limit_drops_the_queue_and_locks_until_reset() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    assert_eq!(b.line("G1 X50 F30000"), "ok\r\n");
    assert_eq!(b.line("G1 X0"), "ok\r\n");
    b.run_ms(50);
    // The firmware's limit interrupt halted the step timer; the idle loop tells the controller.
    b.ctl.hard_limit(&mut b.tx);
    assert_eq!(b.take(), "ALARM:1\r\n[MSG:Reset to continue]\r\n");
    b.run_ms(100);
    let at = b.shared.positions();
    b.run_ms(100);
    assert_eq!(b.shared.positions(), at, "queue dropped");
    assert_eq!(b.ctl.pending_moves(), 0);
    assert!(!b.ctl.byte(b'G', &mut b.tx), "nothing read until Ctrl-X");
    assert!(b.status().starts_with("<Alarm|"));
    b.byte(0x18);
    assert!(b.take().ends_with("[MSG:'$H'|'$X' to unlock]\r\n"));
    assert_eq!(b.line("G0 X1"), "error:9\r\n");
}

/// Ctrl-X right after a hard limit, the engine still in its cut move (the firmware's step timer
/// is stopped until the Ctrl-X rebuilds its output): the banner and the unlock hint, no
/// ALARM:3 (the controller is in alarm already, as Grbl's reset after a hard limit), the pass
/// tells the shell it took a Ctrl-X, and the position is the engine's once it has stopped.
#[test]
fn ctrl_x_after_a_hard_limit_keeps_the_alarm_without_alarm_3() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    assert_eq!(b.line("G1 X50 F30000"), "ok\r\n");
    b.run_ms(50);
    b.ctl.hard_limit(&mut b.tx);
    assert_eq!(b.take(), "ALARM:1\r\n[MSG:Reset to continue]\r\n");
    assert_eq!(b.shared.state(), ddastep::motion::shared::State::Run);
    b.actions.clear();
    b.byte(0x18);
    assert_eq!(b.take(), "\r\nGrbl 1.1h ['$' for help]\r\n[MSG:'$H'|'$X' to unlock]\r\n");
    assert!(b.actions.last().unwrap().reset);
    b.run_ms(5);
    assert!(b.actions.iter().skip(1).all(|a| !a.reset));
    let at = b.shared.positions();
    assert!(at[0] > 0 && at[0] < 50 * 250, "{at:?}");
    assert!(b.status().starts_with("<Alarm|"));
    assert_eq!(b.line("$X"), "[MSG:Caution: Unlocked]\r\nok\r\n");
    b.run_ms(5);
    assert_eq!(b.shared.positions(), at);
}
