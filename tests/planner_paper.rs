//! The seed paper's experiment through the G-code front end: X:Y:Z = 5000:3000:2000 steps
//! with the master at 50 kHz (defaults), and the same shape at 200 kHz (settings lines).

#[path = "protocol_rig/mod.rs"]
mod protocol_rig;

use ddastep::grbl::settings::Settings;
use protocol_rig::Bench;

/// F (mm/min) that runs X at `x_hz` on a 50:30:20 move at 100 steps/mm: the path is
/// √3800/50 times X's length, so F = x_hz / 100 · 60 · √3800 / 50.
fn feed_for(x_hz: f64) -> f64 {
    x_hz / 100.0 * 60.0 * 3800f64.sqrt() / 50.0
}

/// A bench with default settings, banner read.
fn bench() -> Bench<3> {
    let mut b = Bench::<3>::new(Settings::BENCH);
    b.take();
    b
}

#[test]
fn paper_532_at_50_khz_with_defaults() {
    assert_eq!(format!("{:.3}", feed_for(50_000.0)), "36986.484");
    let mut b = bench();
    assert_eq!(b.line("G91 G1 X50 Y30 Z20 F36986.484"), "ok\r\n");
    b.run_to_idle(2000);
    assert_eq!(b.shared.positions(), [5000, 3000, 2000]);
    assert_eq!(b.peak_hz, 50_000, "the master cruises at exactly 50 kHz");
    assert!(!b.stepped_while_disabled);
    // Again, backwards: G91 keeps adding.
    assert_eq!(b.line("X-50 Y-30 Z-20"), "ok\r\n");
    b.run_to_idle(2000);
    assert_eq!(b.shared.positions(), [0, 0, 0]);
}

#[test]
fn a_faster_feed_is_held_at_the_axis_limit() {
    // F 40 000 would want 54 kHz on X; X's $110 = 36 000 mm/min allows 60 kHz, so it runs;
    // with $110 = 30 000 (50 kHz) it is held at 50 kHz.
    let mut b = bench();
    b.line("$110=30000");
    b.line("G91 G1 X50 Y30 Z20 F40000");
    b.run_to_idle(2000);
    assert_eq!(b.peak_hz, 50_000);
    // The table's top is the fastest axis (Y, Z still 60 kHz): a G0 is held at X's limit.
    b.peak_hz = 0;
    b.line("G0 X-50 Y-30 Z-20");
    b.run_to_idle(2000);
    assert_eq!(b.peak_hz, 50_000);
    assert_eq!(b.shared.positions(), [0, 0, 0]);
}

#[test]
fn paper_532_at_200_khz() {
    assert_eq!(format!("{:.3}", feed_for(200_000.0)), "147945.936");
    let mut b = bench();
    for l in ["$0=1", "$110=150000", "$111=150000", "$112=150000", "$120=100000", "$121=100000", "$122=100000"] {
        assert_eq!(b.line(l), "ok\r\n", "{l}");
    }
    b.run_ms(2);
    let info = b.line("$I");
    // 1 µs pulses (as bench/demo/fast_532.gcode): the period floor is a low time of 1 µs
    // after the latest falling edge (twice the pulse plus the store latency and the step
    // handler's cost stay below it).
    let limit = 72_000_000 / (ddastep::motion::timing::HANDLER_FALL_TICKS + 72);
    assert!(limit >= 200_000, "{limit}");
    assert!(info.contains(&format!("[MSG:max step rate {limit} Hz]")), "{info}");
    // The table is in path units (100 steps/mm): up to √3 × 2500 mm/s, at twice the
    // largest acceleration; each move walks and scales it to its own limits.
    assert!(info.contains("[MSG:ramp 1000-433012 Hz 20000000 Hz/s trapezoid]"), "{info}");
    assert_eq!(b.line("G91 G1 X50 Y30 Z20 F147945.936"), "ok\r\n");
    b.run_to_idle(2000);
    assert_eq!(b.shared.positions(), [5000, 3000, 2000]);
    assert_eq!(b.peak_hz, 200_000);
    // Ten times longer at a tenth of the acceleration: a long cruise at 200 kHz.
    for l in ["$120=10000", "$121=10000", "$122=10000"] {
        b.line(l);
    }
    b.run_ms(2);
    b.peak_hz = 0;
    assert_eq!(b.line("G1 X500 Y300 Z200"), "ok\r\n");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [55_000, 33_000, 22_000]);
    assert_eq!(b.peak_hz, 200_000);
}

#[test]
fn default_pulse_width_caps_the_master_at_its_pulse_limit() {
    // 3 µs pulses need 6 µs plus the store latency: asking for 200 kHz runs at the
    // documented limit (142.9 kHz).
    let limit = 72_000_000 / (2 * 216 + ddastep::motion::timing::STORE_LATENCY_TICKS);
    let mut b = bench();
    for l in ["$110=150000", "$111=150000", "$112=150000", "$120=100000", "$121=100000", "$122=100000"] {
        b.line(l);
    }
    b.run_ms(2);
    let info = b.line("$I");
    assert!(info.contains(&format!("[MSG:max step rate {limit} Hz]")), "{info}");
    b.line("G91 G1 X50 Y30 Z20 F147945.936");
    b.run_to_idle(2000);
    assert_eq!(b.shared.positions(), [5000, 3000, 2000]);
    assert!(b.peak_hz <= limit && b.peak_hz as f64 > limit as f64 * 0.997, "{}", b.peak_hz);
}
