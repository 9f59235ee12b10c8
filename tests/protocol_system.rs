//! Grbl's `$` commands beyond settings: `$C`, `$SLP`, `$N`, `$I=`, `$RST=`, the axis count
//! (`$42`), and stop semantics (Ctrl-X from a completed hold is no alarm).

mod protocol_rig;

use ddastep::grbl::settings::Settings;
use protocol_rig::Bench;

const BANNER: &str = "\r\nGrbl 1.1h ['$' for help]\r\n";

#[test]
fn check_mode_parses_without_motion_and_leaving_it_resets() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    assert_eq!(b.line("$C"), "[MSG:Enabled]\r\nok\r\n");
    assert!(b.status().starts_with("<Check|"));
    for line in ["G21 G91", "G1 X10 F100", "G4 P100", "G10 L20 P1 X0", "M0", "G0 Y5"] {
        assert_eq!(b.line(line), "ok\r\n", "{line}");
    }
    assert_eq!(b.line("G64"), "error:20\r\n", "errors as usual");
    assert_eq!(b.line("M2"), "[MSG:Pgm End]\r\nok\r\n");
    b.run_ms(20);
    assert_eq!(b.shared.positions(), [0, 0, 0], "nothing moved");
    assert_eq!(b.ctl.pending_moves(), 0);
    assert_eq!(b.line("$J=G91X1F100"), "error:8\r\n");
    assert_eq!(b.line("$C"), format!("[MSG:Disabled]\r\nok\r\n{BANNER}"));
    assert!(b.status().starts_with("<Idle|MPos:0.000,0.000,0.000|"));
    assert!(b.line("$#").starts_with("[G54:0.000,0.000,0.000]"), "check-mode G10 not kept");
    assert!(b.actions.iter().all(|a| !a.save), "nothing stored");
    assert_eq!(b.line("$G"), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
    // Not from alarm or while moving.
    b.line("G0 X1");
    assert_eq!(b.line("$C"), "error:8\r\n");
}

#[test]
fn sleep_takes_nothing_until_a_reset_which_leaves_alarm() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    b.line("G0 X1");
    b.run_to_idle(1000);
    assert_eq!(b.line("$SLP"), "[MSG:Sleeping]\r\nok\r\n");
    b.run_ms(2);
    assert!(!b.enabled, "drivers off");
    assert!(b.status().starts_with("<Sleep|"));
    assert!(!b.ctl.byte(b'G', &mut b.tx), "no line bytes taken while asleep");
    b.byte(0x18);
    assert_eq!(b.take(), format!("{BANNER}[MSG:'$H'|'$X' to unlock]\r\n"));
    assert!(b.status().starts_with("<Alarm|MPos:1.000,"));
    assert_eq!(b.line("$X"), "[MSG:Caution: Unlocked]\r\nok\r\n");
}

#[test]
fn startup_lines_are_checked_stored_listed_and_run_after_reset() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    assert_eq!(b.line("$N"), "$N0=\r\n$N1=\r\nok\r\n");
    assert_eq!(b.line("$N0=G20 G91"), "ok\r\n");
    assert_eq!(b.line("$N1=G64"), "error:20\r\n");
    assert_eq!(b.line("$N1=G54 F100"), "ok\r\n");
    assert_eq!(b.line(&format!("$N1={}", "X1".repeat(40))), "error:14\r\n");
    assert_eq!(b.line("$N"), "$N0=G20G91\r\n$N1=G54F100\r\nok\r\n");
    b.byte(0x18);
    b.run_ms(2);
    assert_eq!(b.take(), format!("{BANNER}>G20G91:ok\r\n>G54F100:ok\r\n"));
    // F is kept (and shown, as Grbl does) in mm/min: F100 in G20 is 2540.
    assert_eq!(b.line("$G"), "[GC:G0 G54 G17 G20 G91 G94 M5 M9 T0 F2540 S0]\r\nok\r\n");
    assert_eq!(b.line("$I=MY MILL"), "ok\r\n");
    let info = b.line("$I");
    assert!(info.starts_with(&format!("[VER:1.1h.ddastep:MYMILL]\r\n[OPT:VMH+,{},128]\r\n", protocol_rig::BLOCKS)), "{info}");
    // $RST=* clears them all (and resets); $RST=# only the coordinates.
    b.line("G10 L2 P1 X3");
    assert_eq!(b.line("$RST=#"), format!("[MSG:Restoring defaults]\r\nok\r\n{BANNER}>G20G91:ok\r\n>G54F100:ok\r\n"));
    assert!(b.line("$#").starts_with("[G54:0.000,"));
    assert_eq!(b.line("$RST=*"), format!("[MSG:Restoring defaults]\r\nok\r\n{BANNER}"));
    assert_eq!(b.line("$N"), "$N0=\r\n$N1=\r\nok\r\n");
    assert_eq!(*b.ctl.settings(), Settings::DEFAULT);
    assert_eq!(b.line("$RST=X"), "error:3\r\n");
}

#[test]
fn stop_from_a_completed_hold_keeps_position_and_gives_no_alarm() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    b.line("G1 X100 F6000");
    b.line("G1 X0");
    b.run_ms(300);
    b.send("!");
    b.run_ms(300);
    assert!(b.status().starts_with("<Hold:0|"));
    let at = b.shared.positions();
    b.byte(0x18);
    assert_eq!(b.take(), BANNER, "no ALARM:3 from Hold:0 (CNCjs/UGS Stop)");
    b.run_ms(20);
    assert_eq!(b.shared.positions(), at);
    assert_eq!(b.ctl.pending_moves(), 0);
    assert!(b.status().starts_with("<Idle|"));
    assert_eq!(b.ctl.planned_steps(), at.map(i64::from));
    assert_eq!(b.line("G91 G0 X1"), "ok\r\n");
    b.run_to_idle(1000);
    assert_eq!(b.shared.positions()[0], at[0] + 100);
    // While still decelerating (Hold:1) it is a reset during motion: ALARM:3.
    b.line("G1 X100 F6000");
    b.run_ms(300);
    b.send("!");
    b.tick_ms();
    assert!(b.status().starts_with("<Hold:1|"));
    b.byte(0x18);
    assert!(b.take().starts_with("ALARM:3\r\n"));
}

#[test]
fn axis_count_setting_governs_reports_listing_and_words() {
    let mut b = Bench::<7>::new(Settings::DEFAULT);
    b.take();
    assert!(b.status().starts_with("<Idle|MPos:0.000,0.000,0.000|"), "XYZ by default");
    let list = b.line("$$");
    assert!(list.contains("$102=250.000\r\n") && !list.contains("$103"));
    assert_eq!(b.line("G0 A1"), "error:20\r\n");
    assert_eq!(b.line("$J=G91 A0 F100"), "error:20\r\n");
    assert_eq!(b.line("$42=8"), "error:3\r\n");
    assert_eq!(b.line("$42=2"), "error:3\r\n");
    assert_eq!(b.line("$103=80"), "error:3\r\n");
    assert_eq!(b.line("$42=4"), "ok\r\n");
    assert!(b.line("$$").contains("$103=250.000\r\n"));
    assert_eq!(b.line("$103=80"), "ok\r\n");
    assert_eq!(b.line("G0 A1"), "ok\r\n");
    b.run_to_idle(5000);
    assert!(b.status().starts_with("<Idle|MPos:0.000,0.000,0.000,1.000|"));
    assert!(b.line("$#").starts_with("[G54:0.000,0.000,0.000,0.000]\r\n"));
    assert_eq!(b.shared.positions()[3], 80);
}

#[test]
fn safe_defaults_are_grbls() {
    let s = Settings::DEFAULT;
    assert_eq!((s.steps_per_mm[0], s.max_rate[0], s.accel[0], s.axes), (250.0, 500.0, 10.0, 3));
    let mut b = Bench::<3>::new(s);
    b.take();
    // 10 mm at the 500 mm/min cap: about 1.2 s plus the ramps.
    b.line("G0 X10");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [2500, 0, 0]);
    assert!(b.peak_hz <= 2084, "{} Hz", b.peak_hz);
}
