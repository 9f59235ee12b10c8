//! The Grbl 1.1 line protocol end to end: bytes in, replies out, moves through the real engine.

mod protocol_rig;

use ddastep::motion::shared::State;
use ddastep::grbl::settings::Settings;
use protocol_rig::{replies, Bench};

#[test]
fn banner_empty_lines_comments_and_line_endings() {
    let mut b = Bench::<3>::with_defaults();
    assert_eq!(b.take(), "\r\nGrbl 1.1h ['$' for help]\r\n");
    // \n, \r, \r\n are one line each; an empty line or a comment-only line is `ok`.
    b.send("\n\r\r\n(just a comment)\n; another\n  \t \n");
    assert_eq!(b.take(), "ok\r\n".repeat(6));
    assert_eq!(b.line("g21 (mm) g90 ; absolute"), "ok\r\n");
    assert_eq!(b.line("$G"), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
    assert_eq!(b.line("N10 G1 F250.5 S0 T1 M5 M9"), "ok\r\n");
    assert_eq!(b.line("$G"), "[GC:G1 G54 G17 G21 G90 G94 M5 M9 T1 F251 S0]\r\nok\r\n");
}

#[test]
fn errors_use_grbl_numbers_and_change_nothing() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    let cases = [
        ("X", 2),
        ("1", 1),
        ("G1 X1", 22),
        ("X--5", 2),
        ("XNaN", 2),
        ("X1e999", 20),
        ("G0 G1 X1", 24),
        ("G20 G21", 21),
        ("X1 X2", 25),
        ("F-5", 4),
        ("G1.5", 23),
        ("G2 X1 Y1 I1", 22),
        ("G2 X1 Y1 I3 F100", 33),
        ("G38.1 Z-1 F100", 20),
        ("G38.2 F100", 26),
        ("A1", 20),
        ("M6 T1", 20),
        ("G4", 28),
        ("G92", 26),
        ("G0 X1 P2", 36),
        ("G80 X1", 31),
        ("X1000001", 33),
        ("X999999999999999", 33),
        ("X1234567890123456", 2),
        ("$H", 5),
        ("$96=1", 3),
        ("$100", 3),
        ("$100=abc", 2),
        ("$0=0.1", 6),
        ("$100=-1", 4),
        ("$J=G91 X1", 22),
        ("$J=G0 X1 F100", 16),
        ("$J=G91 X1 F100 S5", 36),
        ("$J=G92 X1 F100", 16),
        ("$J G91 X1 F100", 3),
        ("G10 L2 P7 X0", 29),
        ("G10 L3 P1 X0", 20),
        ("G10 L2 P1", 26),
        ("G10 X0", 28),
        ("G10 L20 P1 X0 G0", 24),
        ("G80 G53 X0", 30),
        ("G43.1 X1", 37),
        ("G43.1 Z1 Y1", 37),
        ("G43 Z1", 20),
        ("G92.2 X0", 20),
        ("G59.1", 23),
        ("G28.2", 20),
        ("G54 G55", 21),
        ("G92 G28 X0", 24),
        ("G0 X1 L2", 36),
        ("$N2=G0", 3),
        ("$I=", 0),
        ("T300", 38),
        ("N99999999", 27),
    ];
    for (line, code) in cases.into_iter().filter(|c| c.1 != 0) {
        assert_eq!(b.line(line), format!("error:{code}\r\n"), "{line}");
    }
    b.run_ms(5);
    assert_eq!(b.shared.positions(), [0, 0, 0]);
    assert_eq!(b.line("$G"), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
}

#[test]
fn garbage_bytes_and_overlong_lines_are_errors_not_panics() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    let long = "X1".repeat(100); // 200 characters
    assert_eq!(b.line(&long), "error:11\r\n");
    // Exactly 128 kept characters is fine; comments and spaces do not count.
    let fits = format!("G0{}", "0".repeat(124)) + "X0 (comment) ";
    assert_eq!(b.line(&fits), "ok\r\n");
    let over = format!("G0{}", "0".repeat(125)) + "X0";
    assert_eq!(b.line(&over), "error:11\r\n");
    // Bytes the shell would never pass on still get a clean error.
    for raw in [&[0xFFu8, b'\n'][..], &[b'G', 0x80, b'1', b'\n'], &[0x7F, b'\n'], &[b'X', 0, b'1', b'\n']] {
        b.take();
        for &c in raw {
            assert!(b.ctl.byte(c, &mut b.tx));
        }
        b.finish();
        let t = b.take();
        assert!(t == "error:1\r\n" || t == "ok\r\n" && raw.contains(&0), "{raw:?} -> {t:?}");
    }
    // \0 is dropped like any control byte, so "X\01" is X1: a G0 move of 1 mm.
    b.run_to_idle(1000);
    assert_eq!(b.shared.positions(), [100, 0, 0]);
}

#[test]
fn status_report_shows_state_position_and_feed() {
    let mut b = Bench::<3>::with_defaults();
    // The first report after a reset carries WCO (Grbl's refresh counters start at zero).
    assert_eq!(b.status(), "<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>\r\n");
    assert_eq!(b.line("G1 X100 Y-50.5 F6000"), "ok\r\n");
    b.run_ms(300);
    let s = b.status();
    assert!(s.starts_with("<Run|MPos:"), "{s}");
    // Ov: comes in the report after the one with WCO:, then every 20th while busy.
    assert!(s.ends_with("|Ov:100,100,100>\r\n"), "{s}");
    // 6000 mm/min along the path: cruise reached after 1 ms of ramp at most.
    let fs: f64 = s.split("FS:").nth(1).unwrap().split(',').next().unwrap().parse().unwrap();
    assert!((fs - 6000.0).abs() < 60.0, "{s}");
    b.run_to_idle(5000);
    assert_eq!(b.status(), "<Idle|MPos:100.000,-50.500,0.000|FS:0,0>\r\n");
    assert_eq!(b.shared.positions(), [10_000, -5050, 0]);
}

#[test]
fn settings_list_change_and_refuse_while_moving() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    let list = b.line("$$");
    assert!(list.starts_with("$0=3.000\r\n$1=25\r\n$2=0\r\n"), "{list}");
    assert!(list.contains("$29=5.000\r\n$30=1000\r\n"));
    assert!(list.contains("$40=1000\r\n$41=0\r\n$42=3\r\n$87=0\r\n$88=1.000\r\n$89=0\r\n$97=20\r\n"));
    assert!(list.contains("$98=0\r\n$99=1.000\r\n$100=100.000\r\n"));
    assert!(list.contains("$6=0\r\n$10=1\r\n$11=0.010\r\n"));
    assert!(list.ends_with("$132=1000.000\r\n$580=0\r\n$581=0\r\n$582=4\r\nok\r\n"), "{list}");
    assert!(!list.contains("$103"));
    assert_eq!(replies(&list), (1, 0));

    assert_eq!(b.line("$100=200"), "ok\r\n");
    b.tick_ms();
    assert!(b.actions.iter().any(|a| a.save));
    assert!(b.line("$$").contains("$100=200.000\r\n"));
    assert_eq!(b.ctl.settings().steps_per_mm[0], 200.0);
    // X at 200 steps/mm: 1 mm is 200 steps.
    assert_eq!(b.line("G0 X1"), "ok\r\n");
    b.run_ms(2);
    assert_eq!(b.line("$100=100"), "error:8\r\n");
    assert_eq!(b.line("$$"), "error:8\r\n");
    b.run_to_idle(1000);
    assert_eq!(b.shared.positions(), [200, 0, 0]);
    // Direction invert needs the pin map rebuilt: the shell is told to rebuild the step output.
    b.actions.clear();
    assert_eq!(b.line("$3=5"), "ok\r\n");
    b.tick_ms();
    assert!(b.actions.iter().any(|a| a.reinit && a.save));
    // A shorter pulse: CCR1 gets the new width.
    b.actions.clear();
    assert_eq!(b.line("$0=2"), "ok\r\n");
    b.run_ms(2);
    assert!(b.actions.iter().any(|a| a.pulse_ticks == Some(144)), "{:?}", b.actions);
    // 2 µs: the low time after the latest falling edge binds the rate.
    let limit = 72_000_000 / (ddastep::motion::timing::HANDLER_FALL_TICKS + 144);
    assert!(b.line("$I").contains(&format!("[MSG:max step rate {limit} Hz]")));
}

#[test]
fn seven_axes_list_and_move() {
    let mut b = Bench::<7>::with_defaults();
    b.take();
    let list = b.line("$$");
    assert!(list.contains("$106=100.000\r\n") && list.contains("$136=1000.000\r\n"));
    assert_eq!(b.line("G1 X1 Y-2 Z3 A4 B-5 C6 U0.07 F3000"), "ok\r\n");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [100, -200, 300, 400, -500, 600, 7]);
    let s = b.status();
    assert_eq!(s, "<Idle|MPos:1.000,-2.000,3.000,4.000,-5.000,6.000,0.070|FS:0,0|WCO:0.000,0.000,0.000,0.000,0.000,0.000,0.000>\r\n");
    assert_eq!(b.line("G0 V1"), "error:20\r\n");
}

#[test]
fn build_info_names_us_and_the_rate_limit() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    // 3 µs pulses: the period floor is 2 × 216 ticks plus the store latency.
    let limit = 72_000_000 / (2 * 216 + ddastep::motion::timing::STORE_LATENCY_TICKS);
    assert_eq!(
        b.line("$I"),
        format!(
            "[VER:1.1h.ddastep:]\r\n[OPT:VMH+,{},128]\r\n[MSG:max step rate {limit} Hz]\r\n\
             [MSG:ramp 1000-103923 Hz 2000000 Hz/s trapezoid]\r\nok\r\n",
            protocol_rig::BLOCKS
        )
    );
    // Slow accel on every axis: the table (path units, twice the largest acceleration,
    // 20 000 /s²) cannot reach the axes' top (√3 × 600 mm/s) within its length: either the
    // top is lowered to what fits (and `$I` says so) or the table is made steeper.
    for l in ["$120=100", "$121=100", "$122=100"] {
        assert_eq!(b.line(l), "ok\r\n");
    }
    b.run_ms(2);
    let info = b.line("$I");
    let len = ddastep::motion::ramp::RAMP_LEN as u64;
    let ramp = info.lines().find(|l| l.starts_with("[MSG:ramp ")).expect("ramp line");
    let nums: Vec<u64> = ramp["[MSG:ramp ".len()..]
        .split(|c: char| !c.is_ascii_digit())
        .filter(|w| !w.is_empty())
        .map(|w| w.parse().unwrap())
        .collect();
    let (v0, vmax, accel) = (nums[0], nums[1], nums[2]);
    assert_eq!(v0, 1000, "{info}");
    assert!((vmax - v0) * 1000 <= accel * len, "the ramp fits in the table: {info}");
    if vmax < 103_923 {
        assert_eq!(ramp, format!("[MSG:ramp 1000-{} Hz 20000 Hz/s trapezoid (table-limited)]", 1000 + 20 * len - 1));
    } else {
        assert_eq!(vmax, 103_923, "{info}");
        assert!(accel > 20_000, "{info}");
    }
    assert!(b.line("$#").starts_with("[G54:0.000,0.000,0.000]\r\n[G55:"));
    assert_eq!(b.line("$"), "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]\r\nok\r\n");
}

#[test]
fn restore_defaults() {
    let mut b = Bench::<3>::with_defaults();
    assert_eq!(b.line("$110=500").lines().last(), Some("ok"));
    // Grbl resets after a restore: the banner follows the `ok`.
    assert_eq!(b.line("$RST=$"), "[MSG:Restoring defaults]\r\nok\r\n\r\nGrbl 1.1h ['$' for help]\r\n");
    assert_eq!(*b.ctl.settings(), Settings::DEFAULT);
}

#[test]
fn feed_hold_and_resume_keep_every_step() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G1 X200 Y100 F12000");
    b.run_ms(200);
    b.send("!");
    b.tick_ms();
    assert!(b.status().starts_with("<Hold:1|"));
    b.run_ms(200);
    let held = b.status();
    assert!(held.starts_with("<Hold:0|MPos:"), "{held}");
    let at = b.shared.positions();
    b.run_ms(50);
    assert_eq!(b.shared.positions(), at, "nothing moves while held");
    assert_eq!(b.line("$100=50"), "error:8\r\n");
    b.send("~");
    b.run_to_idle(10_000);
    assert_eq!(b.shared.positions(), [20_000, 10_000, 0]);
    assert_eq!(b.shared.state(), State::Idle);
}

#[test]
fn dwell_waits_for_the_queue_then_the_time() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G1 X10 F6000"); // 100 ms at cruise
    b.send("G4 P0.25\n");
    let t0 = b.now_ms;
    assert!(b.ctl.busy(), "the dwell holds its line");
    // The next line waits (in the RX ring) behind the dwell.
    b.send("G0 Y1\n");
    b.finish();
    let t = b.now_ms - t0;
    assert!((350..400).contains(&t), "dwell ended after {t} ms");
    assert_eq!(replies(&b.take()), (2, 0));
    b.run_to_idle(1000);
    assert_eq!(b.shared.positions(), [1000, 100, 0]);
}

#[test]
fn g92_offsets_work_coordinates_and_leaves_the_machine_position() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G0 X5");
    // G92 takes effect at once (Grbl: parser state), while X is still on its way.
    assert_eq!(b.line("G92 X0 Y10"), "ok\r\n");
    assert!(b.ctl.pending_moves() > 0);
    b.run_to_idle(1000);
    assert_eq!(b.shared.positions(), [500, 0, 0]);
    assert!(b.line("$#").contains("[G92:5.000,-10.000,0.000]\r\n"));
    b.line("$10=0");
    assert!(b.status().starts_with("<Idle|WPos:0.000,10.000,0.000|"));
    b.line("G0 X1 Y0");
    b.run_to_idle(1000);
    assert_eq!(b.shared.positions(), [600, -1000, 0]);
    b.line("G92.1");
    b.line("G91 G0 X-1 Y-1");
    b.run_to_idle(1000);
    assert_eq!(b.shared.positions(), [500, -1100, 0]);
    assert_eq!(b.ctl.planned_steps(), [500, -1100, 0]);
}

#[test]
fn inches_and_relative_moves() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G20 G91 G1 X1 Y-0.5 F100");
    b.line("X1");
    b.line("G21 G90 Z-3.333");
    b.run_to_idle(20_000);
    assert_eq!(b.shared.positions(), [5080, -1270, -333]);
}

#[test]
fn soft_reset_while_moving_raises_alarm_3() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G1 X100 F6000");
    b.line("G1 X0");
    b.run_ms(100);
    b.send("G1 X5"); // a partial line, dropped by the reset
    b.byte(0x18);
    let t = b.take();
    assert_eq!(t, "ALARM:3\r\n\r\nGrbl 1.1h ['$' for help]\r\n[MSG:'$H'|'$X' to unlock]\r\n");
    b.run_ms(5);
    let at = b.shared.positions();
    assert!(at[0] > 0 && at[0] < 10_000);
    assert_eq!(b.ctl.pending_moves(), 0);
    assert!(b.status().starts_with("<Alarm|"));
    assert_eq!(b.line("G0 X0"), "error:9\r\n");
    assert_eq!(b.line("$G"), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
    assert_eq!(b.line("$X"), "[MSG:Caution: Unlocked]\r\nok\r\n");
    assert_eq!(b.line("G91 G0 X1"), "ok\r\n");
    b.run_to_idle(1000);
    assert_eq!(b.shared.positions(), [at[0] + 100, 0, 0]);
    // A reset while idle is no alarm.
    b.byte(0x18);
    assert_eq!(b.take(), "\r\nGrbl 1.1h ['$' for help]\r\n");
    assert!(b.status().starts_with("<Idle|"));
}

#[test]
fn drivers_enable_before_motion_and_idle_off_after_delay() {
    let mut b = Bench::<3>::with_defaults();
    b.run_ms(3);
    assert!(!b.enabled, "$1=25: off at boot");
    b.line("G0 X1");
    b.run_to_idle(1000);
    assert!(!b.stepped_while_disabled);
    assert!(b.enabled);
    b.run_ms(24);
    assert!(b.enabled);
    b.run_ms(3);
    assert!(!b.enabled, "off 25 ms after idle");
    // Enable pin: active low, so high when disabled.
    assert!(b.actions.last().unwrap().enable_pin_high);
    b.line("M17");
    b.run_ms(100);
    assert!(b.enabled, "M17 holds them on");
    b.line("G0 X0 M18");
    assert!(!b.enabled, "M18 after the move");
    assert_eq!(b.shared.positions(), [0, 0, 0]);
    b.line("$1=255");
    b.run_ms(3);
    b.line("G0 X1");
    b.run_ms(500);
    assert!(b.enabled, "$1=255: always on");
    assert!(!b.stepped_while_disabled);
}

#[test]
fn m0_pauses_m2_ends() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G0 X1");
    assert_eq!(b.line("M0"), "ok\r\n");
    b.line("G0 X2");
    b.run_ms(50);
    assert!(b.status().starts_with("<Hold:0|MPos:1.000,"));
    b.send("~");
    b.run_to_idle(1000);
    assert_eq!(b.shared.positions(), [200, 0, 0]);
    b.line("G91 G0 X1");
    assert_eq!(b.line("M30"), "[MSG:Pgm End]\r\nok\r\n");
    assert_eq!(b.line("$G"), "[GC:G1 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
}

#[test]
fn flash_write_comes_before_the_next_line_moves() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    // Both lines already in the RX ring: the second waits until the poll that asks for the save.
    let mut rx: Vec<u8> = b"$100=200\nG0 X1\n".to_vec();
    let mut taken = 0;
    while taken < rx.len() && b.ctl.byte(rx[taken], &mut b.tx) {
        taken += 1;
    }
    assert_eq!(taken, 9, "stops after the settings line");
    assert_eq!(b.take(), "");
    b.tick_ms();
    let a = *b.actions.last().unwrap();
    assert!(a.save && !a.reinit);
    assert_eq!(b.take(), "ok\r\n");
    assert_eq!(b.ctl.pending_moves(), 0, "no move before the flash write");
    rx.drain(..taken);
    for c in rx {
        assert!(b.ctl.byte(c, &mut b.tx));
    }
    b.finish();
    b.run_to_idle(1000);
    assert_eq!(b.shared.positions(), [200, 0, 0]);
    assert!(b.actions.iter().filter(|a| a.save).count() == 1);
}

#[test]
fn axes_beyond_the_count_do_not_scale_the_table() {
    // A 7-axis firmware set to 3 axes ($42) keeps a finer steps/mm on its unused A axis: the
    // table's path units come from X, Y, Z only, and so must the planner's clamp to its top.
    let mut b = Bench::<7>::with_defaults();
    b.take();
    assert_eq!(b.line("$103=1000"), "ok\r\n");
    assert_eq!(b.line("$42=3"), "ok\r\n");
    b.run_ms(2);
    b.peak_hz = 0;
    assert_eq!(b.line("G91 G0 X100"), "ok\r\n");
    b.run_to_idle(10_000);
    assert_eq!(b.shared.positions()[0], 10_000);
    assert_eq!(b.peak_hz, 60_000, "X's $110 = 36 000 mm/min at 100 steps/mm");
}
