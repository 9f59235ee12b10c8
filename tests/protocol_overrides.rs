//! Grbl 1.1 override bytes (0x90–0x9D) through the library's realtime dispatch.

mod protocol_rig;

use ddastep::queue::Overrides;
use protocol_rig::Bench;

#[test]
fn override_bytes_step_and_clamp_like_grbl() {
    let mut b = Bench::<3>::with_defaults();
    assert_eq!(b.shared.overrides(), Overrides { feed: 100, rapid: 100, spindle: 100 });
    for _ in 0..3 {
        b.byte(0x91);
    }
    b.byte(0x94);
    assert_eq!(b.shared.overrides().feed, 129);
    for _ in 0..20 {
        b.byte(0x91);
    }
    assert_eq!(b.shared.overrides().feed, 200);
    for _ in 0..30 {
        b.byte(0x92);
    }
    assert_eq!(b.shared.overrides().feed, 10);
    b.byte(0x90);
    b.byte(0x97);
    b.byte(0x9A);
    b.byte(0x9D);
    assert_eq!(b.shared.overrides(), Overrides { feed: 100, rapid: 25, spindle: 109 });
    b.byte(0x96);
    assert_eq!(b.shared.overrides().rapid, 50);
    b.byte(0x95);
    b.byte(0x99);
    assert_eq!(b.shared.overrides(), Overrides::NONE);
    // Override bytes never reach the line: the next line is untouched.
    b.take();
    assert_eq!(b.line("G91"), "ok\r\n");
}

#[test]
fn feed_override_scales_new_g1_moves_and_rapid_override_g0() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G91 G1 X20 F6000");
    b.run_to_idle(5000);
    let near = |hz: u32, want: u32| (hz as f64 - want as f64).abs() <= want as f64 * 0.002;
    assert!(near(b.peak_hz, 10_000), "{}", b.peak_hz);
    for _ in 0..5 {
        b.byte(0x92);
    }
    b.peak_hz = 0;
    b.line("G1 X20");
    b.run_to_idle(5000);
    assert!(near(b.peak_hz, 5_000), "{}", b.peak_hz);
    b.byte(0x96);
    b.peak_hz = 0;
    b.line("G0 X20");
    b.run_to_idle(5000);
    assert!(near(b.peak_hz, 30_000), "G0 at 50 % of 60 kHz: {}", b.peak_hz);
    assert_eq!(b.shared.positions(), [6000, 0, 0]);
}
