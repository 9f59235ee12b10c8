//! Firmware in the loop: Grbl's feed override bytes on the emulated board change the running
//! move's step rate, measured from the pins, through the ramp (no jump), and `Ov:` shows them.

mod firmware_rig;

use ddastep::grbl::settings::Settings;
use ddastep::grbl::store::Stored;
use ddastep_bench::emu::{Board, HZ};
use firmware_rig::*;

/// X steps per second between two cycle counts, from the pins.
fn x_rate(s: &[Step], from: u64, to: u64) -> f64 {
    let n = s.iter().filter(|s| s.axis == 0 && s.cycle >= from && s.cycle < to).count();
    n as f64 * HZ as f64 / (to - from) as f64
}

/// The X rate over the 10 ms windows from `from`, steps/s.
fn windows(s: &[Step], from: u64, n: u64) -> Vec<f64> {
    (0..n).map(|k| x_rate(s, from + k * HZ / 100, from + (k + 1) * HZ / 100)).collect()
}

/// The `Ov:` field of the next report, or the one after (`WCO:` may take its place once).
fn ov(b: &mut Board) -> String {
    let (first, second) = (status(b), status(b));
    let field = |s: &str| s.split(['|', '>']).find_map(|f| f.strip_prefix("Ov:")).map(str::to_string);
    field(&first).or(field(&second)).unwrap_or_else(|| panic!("no Ov: in {first} {second}"))
}

#[test]
fn feed_override_bytes_change_the_running_step_rate() {
    // 1000 mm/s² at 100 steps/mm: X's master accelerates at 100 Hz per ms.
    let mut s = Settings::BENCH;
    s.accel = [1000.0; ddastep::MAX_AXES];
    let mut b = boot_with(Some(Stored::from(s)));
    // 100 mm/s: 10 kHz, reached after 90 ms (from the table's 1 kHz start); 3 s of motion.
    ok(&mut b, "G91 G1 X300 F6000");
    b.run_seconds(0.3).unwrap();
    let t = b.cycles();
    b.run_seconds(0.1).unwrap();
    let r100 = x_rate(&steps(&b), t, b.cycles());
    assert!((r100 - 10_000.0).abs() < 50.0, "100 %: {r100} Hz");

    // +50 %: 15 kHz after the 50 ms X's acceleration needs, ramping 1 kHz per 10 ms.
    let t = b.cycles();
    b.serial_send(&[0x91; 5]);
    b.run_seconds(0.2).unwrap();
    let w = windows(&steps(&b), t, 20);
    eprintln!("150 %: {:?}", w.iter().map(|r| r.round() as i64).collect::<Vec<_>>());
    assert!(w[0] > 10_050.0 && w[0] < 11_500.0, "acts within a few ms, without a jump: {w:?}");
    assert!(w.windows(2).all(|p| p[1] - p[0] < 1_300.0), "never faster than the acceleration: {w:?}");
    let r150 = x_rate(&steps(&b), t + HZ / 10, b.cycles());
    assert!((r150 - 15_000.0).abs() < 75.0, "150 %: {r150} Hz");
    assert_eq!(ov(&mut b), "150,100,100");

    // −100 %: 5 kHz after 100 ms.
    let t = b.cycles();
    b.serial_send(&[0x92; 10]);
    b.run_seconds(0.25).unwrap();
    let w = windows(&steps(&b), t, 20);
    eprintln!("50 %: {:?}", w.iter().map(|r| r.round() as i64).collect::<Vec<_>>());
    assert!(w.windows(2).all(|p| p[0] - p[1] < 1_300.0), "never faster than the acceleration: {w:?}");
    let r50 = x_rate(&steps(&b), t + 3 * HZ / 20, b.cycles());
    assert!((r50 - 5_000.0).abs() < 25.0, "50 %: {r50} Hz");
    assert_eq!(ov(&mut b), "50,100,100");

    b.serial_send(&[0x90]);
    wait_idle(&mut b, 10.0);
    assert_eq!(net(&steps(&b)), [30_000, 0, 0, 0, 0, 0, 0], "counts exact");
    assert_eq!(b.report().overruns, 0);
}
