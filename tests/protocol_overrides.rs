//! Grbl 1.1 override bytes (0x90–0x9D): the percentages in `Ov:`, applied to the program moves
//! planned after the byte (feed for G1/G2/G3, rapid for G0), never to jogs (as Grbl).

mod protocol_rig;

use protocol_rig::Bench;

/// `Ov:feed,rapid,spindle` from a status report.
fn ov(status: &str) -> Option<String> {
    status.split(['|', '>']).find_map(|f| f.strip_prefix("Ov:")).map(str::to_string)
}

/// Peak master rate (steps/s) of one line run to idle.
fn peak(b: &mut Bench<3>, line: &str) -> u32 {
    b.peak_hz = 0;
    assert_eq!(b.line(line), "ok\r\n", "{line}");
    b.run_to_idle(60_000);
    b.peak_hz
}

#[test]
fn override_bytes_step_and_clamp_as_grbl() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    for _ in 0..15 {
        b.byte(0x91); // +10 % each, up to 200 %
    }
    b.byte(0x94); // −1 %
    b.byte(0x96); // rapid 50 %
    for _ in 0..30 {
        b.byte(0x9B); // spindle −10 % each, down to 10 %
    }
    b.byte(0x98); // not an override: nothing changes
    let o = b.shared.overrides();
    assert_eq!((o.feed, o.rapid, o.spindle), (199, 50, 10));
    // A changed override is shown in the next report, or the one after when `WCO:` is due in
    // that one (Grbl never sends both in one report).
    let (first, second) = (b.status(), b.status());
    assert_eq!(ov(&first).or(ov(&second)).as_deref(), Some("199,50,10"), "{first}{second}");
    b.byte(0x90);
    b.byte(0x95);
    b.byte(0x99);
    let o = b.shared.overrides();
    assert_eq!((o.feed, o.rapid, o.spindle), (100, 100, 100));
}

#[test]
fn feed_and_rapid_overrides_scale_new_program_moves_but_not_jogs() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    assert_eq!(b.line("G91"), "ok\r\n");
    // 100 steps/mm: F600 is 10 mm/s, 1 kHz on X.
    let plain = peak(&mut b, "G1 X20 F600");
    assert_eq!(plain, 1000);
    for _ in 0..10 {
        b.byte(0x91);
    }
    assert_eq!(b.shared.overrides().feed, 200);
    assert_eq!(peak(&mut b, "G1 X20 F600"), 2 * plain);
    // Jogs run at their own F whatever the feed override.
    assert_eq!(peak(&mut b, "$J=G91 X20 F600"), plain);
    // The axes' max rates still bind: $110 = 36 000 mm/min is 60 kHz.
    assert_eq!(peak(&mut b, "G1 X400 F30000"), 60_000);
    // Rapid 25 %: a G0 runs at a quarter of the axis limit.
    b.byte(0x97);
    assert_eq!(peak(&mut b, "G0 X400"), 15_000);
    b.byte(0x95);
    assert_eq!(peak(&mut b, "G0 X-400"), 60_000);
    assert_eq!(b.shared.positions()[0], 100 * (20 + 20 + 20 + 400 + 400 - 400));
}
