//! The safety door as Grbl 1.1 (built with its door input, no parking): opening it stops the
//! motion with a feed hold (`Door:2`), then switches spindle and coolant off (`Door:1` while
//! open, `Door:0` once closed); `~` resumes only with the door closed, after the spindle's
//! 4 s restart delay (`Door:3`); the move then ends exactly where it was going. 0x84 is the
//! same door from the serial line; `Pn:D` shows the input; `$X`/`$H` with the door open get
//! error:13; a jog is cancelled; a homing cycle fails with ALARM:7.

mod protocol_rig;

use ddastep::motion::shared::State;
use ddastep::grbl::settings::Settings;
use protocol_rig::Bench;

fn state(b: &mut Bench<3>) -> String {
    let s = b.status();
    s.trim_start_matches('<').split(['|', '>']).next().unwrap_or("").to_string()
}

/// The state word and the `FS:` feed of a status report.
fn state_feed(b: &mut Bench<3>) -> (String, f64) {
    let s = b.status();
    let feed = s.split(['|', '>']).find_map(|f| f.strip_prefix("FS:")).and_then(|f| f.split(',').next()?.parse().ok());
    (s.trim_start_matches('<').split(['|', '>']).next().unwrap_or("").to_string(), feed.unwrap_or_else(|| panic!("{s}")))
}

/// The spindle's enable pin in the last poll's actions.
fn spindle_on(b: &Bench<3>) -> bool {
    b.actions.last().is_some_and(|a| a.spindle.enable)
}

#[test]
fn door_stops_the_move_and_the_spindle_and_resumes_only_when_closed() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    let spm = b.ctl.settings().steps_per_mm[0] as f64;
    assert_eq!(b.line("M3 S1000"), "ok\r\n");
    assert_eq!(b.line("G1 X20 F600"), "ok\r\n");
    b.run_ms(300);
    assert_eq!(state(&mut b), "Run");
    assert!(spindle_on(&b));

    b.door_open = true;
    b.run_ms(1);
    let (st, feed) = state_feed(&mut b);
    assert!(st == "Door:2" && feed > 0.0, "decelerating: {st} FS:{feed}");
    assert!(spindle_on(&b), "the spindle runs until the motion has stopped");
    b.run_ms(1000);
    assert_eq!(state_feed(&mut b), ("Door:1".into(), 0.0), "stopped: the feed is 0 (Grbl)");
    assert!(!spindle_on(&b), "spindle off while the door is open");
    assert!(b.status().contains("|Pn:D"), "the door input shows in Pn:");
    let stopped = b.shared.positions();
    assert!(stopped[0] > 0 && stopped[0] < (20.0 * spm) as i32, "{stopped:?}");

    // `~` with the door open does nothing; `$X` gets error:13.
    b.byte(b'~');
    b.run_ms(200);
    assert_eq!(state(&mut b), "Door:1");
    assert_eq!(b.shared.positions(), stopped);
    assert_eq!(b.line("$X"), "error:13\r\n");

    b.door_open = false;
    b.run_ms(2);
    assert_eq!(state_feed(&mut b), ("Door:0".into(), 0.0), "closed, ready to resume");
    assert!(!b.status().contains("Pn:"));
    assert!(!spindle_on(&b));

    b.byte(b'~');
    b.run_ms(2);
    assert_eq!(state(&mut b), "Door:3", "restoring: spindle first");
    assert!(spindle_on(&b));
    b.run_ms(3900);
    assert_eq!(b.shared.positions(), stopped, "motion waits for the spindle's 4 s");
    assert_eq!(state_feed(&mut b), ("Door:3".into(), 0.0));
    b.run_ms(200);
    assert_eq!(state(&mut b), "Run");
    b.run_to_idle(10_000);
    assert_eq!(b.shared.positions()[0], (20.0 * spm) as i32, "the move ends where it was going");
    assert!(spindle_on(&b));
}

#[test]
fn door_byte_from_idle_waits_for_a_cycle_start() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    b.run_ms(2);
    b.byte(0x84);
    b.run_ms(2);
    // No input wired (the pin reads closed): straight to Door:0.
    assert_eq!(state(&mut b), "Door:0");
    // Lines are taken during the door state; the motion waits.
    assert_eq!(b.line("G0 X1"), "ok\r\n");
    b.run_ms(100);
    assert_eq!(b.shared.positions(), [0; 3]);
    b.byte(b'~');
    b.run_ms(1);
    assert_ne!(state(&mut b), "Door:3", "nothing to restore: no delay");
    b.run_to_idle(5_000);
    assert_eq!(state(&mut b), "Idle");
    assert!(b.shared.positions()[0] > 0);
}

#[test]
fn door_during_a_jog_cancels_it() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    b.run_ms(2);
    assert_eq!(b.line("$J=G91 X50 F1000"), "ok\r\n");
    b.run_ms(200);
    assert_eq!(state(&mut b), "Jog");
    b.door_open = true;
    b.run_ms(1000);
    assert_eq!(state(&mut b), "Door:1");
    assert_eq!(b.ctl.pending_moves(), 0, "the jog's queue is flushed");
    assert_ne!(b.shared.state(), State::Run);
    b.door_open = false;
    b.run_ms(2);
    b.byte(b'~');
    b.run_ms(5);
    assert_eq!(state(&mut b), "Idle");
    let at = b.shared.positions();
    b.run_ms(200);
    assert_eq!(b.shared.positions(), at, "the jog does not come back");
}

#[test]
fn door_opened_during_homing_is_alarm_7() {
    let mut s = Settings { homing: true, axes: 3, ..Settings::BENCH };
    s.homing_seek = 3000.0;
    s.homing_feed = 100.0;
    let mut b = Bench::<3>::new(s);
    b.switches = (0..3).map(|i| (i, 10_000, true)).collect();
    b.take();
    b.send("$H\n");
    b.run_ms(50);
    assert_eq!(state(&mut b), "Home");
    b.door_open = true;
    b.run_ms(50);
    let out = b.take();
    assert!(out.contains("ALARM:7"), "{out}");
    assert_eq!(state(&mut b), "Alarm");
    // Still open: `$H` and `$X` get error:13.
    assert_eq!(b.line("$H"), "error:13\r\n");
    assert_eq!(b.line("$X"), "error:13\r\n");
}
