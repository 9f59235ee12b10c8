//! Arcs, `$12` and G93 through the real controller, planner and engine (host bench).

mod protocol_rig;

use ddastep::board::pin_map;
use ddastep::planning::inverse_time;
use ddastep::grbl::settings::Settings;
use ddastep::TIMER_HZ;
use proptest::prelude::*;
use protocol_rig::{replies, Bench};

/// Runs `ms` milliseconds like `Bench::tick_ms`, recording the time of every update event
/// that steps an axis.
fn run_recording(b: &mut Bench<3>, ms: u32, steps: &mut Vec<u64>) {
    let mask = pin_map::<3>(0, 0).step_on.iter().fold(0, |m, s| m | s);
    for _ in 0..ms {
        b.now_ms += 1;
        let end = b.now_ms as u64 * ddastep::TICKS_PER_MS as u64;
        while b.timer.now() < end {
            let e = b.timer.update(&mut b.engine);
            if e.word & mask != 0 {
                steps.push(e.t);
            }
        }
        let a = b.ctl.poll(b.now_ms, &mut b.tx);
        b.enabled = a.enable;
        b.drain();
    }
}

#[test]
fn a_job_with_arcs_in_two_planes_ends_exactly() {
    let mut b = Bench::<3>::with_defaults();
    let job = [
        "G21 G90 G17 G94",
        "G0 X10 Y0 Z2",
        "G1 Z-1 F600",
        "G2 X0 Y10 I-10 J0 F1200",  // quarter circle
        "G3 X-10 Y0 R10",           // quarter, R form
        "G2 X-10 Y0 I10 J0 Z-2",    // full helical circle
        "G18 G2 X0 Z-12 R10",       // XZ plane
        "G19 G3 Y5 Z-7 J0 K5",      // YZ plane
        "G17 G0 Z5",
        "G0 X0 Y0",
    ];
    for l in job {
        let r = b.line(l);
        assert_eq!(replies(&r), (1, 0), "{l}: {r}");
    }
    b.run_to_idle(60_000);
    // 100 steps/mm: the last point is (0, 0, 5).
    assert_eq!(b.shared.positions(), [0, 0, 500]);
    assert_eq!(b.ctl.planned_steps(), [0, 0, 500]);
}

#[test]
fn a_bad_arc_changes_nothing_queued() {
    let mut b = Bench::<3>::with_defaults();
    assert_eq!(replies(&b.line("G1 X50 F3000")), (1, 0));
    let pending = b.ctl.pending_moves();
    let planned = b.ctl.planned_steps();
    for (line, err) in [
        ("G2 X60 Y10 I4", "error:33"),
        ("G2 X60 R1", "error:34"),
        ("G2 X60", "error:35"),
        ("G2 Z3 I1", "error:32"),
        ("G2 I1", "error:26"),
        ("G3 X50 Y0 R5", "error:33"),
        ("G2 X60 I5 R5", "error:36"),
        ("G1 X60 R5", "error:36"),
        ("G2 X2000000 I5", "error:33"),
        ("G2 X50 I-1000000", "error:33"),
    ] {
        let r = b.line(line);
        assert!(r.starts_with(err), "{line}: {r}");
        assert_eq!(b.ctl.pending_moves(), pending);
        assert_eq!(b.ctl.planned_steps(), planned);
    }
    b.run_to_idle(10_000);
    assert_eq!(b.shared.positions(), [5000, 0, 0]);
    // The modal state is untouched too: a G1 without F still has the last feed.
    assert_eq!(replies(&b.line("G1 X0")), (1, 0));
}

#[test]
fn arc_tolerance_is_a_real_setting() {
    let mut b = Bench::<3>::with_defaults();
    assert!(b.line("$$").contains("$12=0.002\r\n"));
    assert_eq!(replies(&b.line("$12=0.05")), (1, 0));
    assert!(b.line("$$").contains("$12=0.050\r\n"));
    assert!(b.line("$12=0").starts_with("error:3"));
    assert!(b.line("$12=-1").starts_with("error:4"));
    let image = b.ctl.settings().to_bytes();
    assert_eq!(Settings::from_bytes(&image).arc_tolerance, 0.05);
    // A coarser tolerance: fewer chords, so fewer moves through the queue for one circle.
    let moves = |tol: &str| {
        let mut b = Bench::<3>::with_defaults();
        b.line(&format!("$12={tol}"));
        let before = b.shared.moves_done();
        b.line("G2 X0 Y0 I5 F6000");
        b.run_to_idle(20_000);
        assert_eq!(b.shared.positions(), [0, 0, 0]);
        b.shared.moves_done().wrapping_sub(before)
    };
    let (fine, coarse) = (moves("0.002"), moves("0.5"));
    assert!(fine > 4 * coarse && coarse >= 2, "fine {fine} coarse {coarse}");
}

#[test]
fn modes_report_arcs_and_inverse_time() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G93 G2 X0 Y0 I1 F60");
    assert!(b.line("$G").starts_with("[GC:G2 G54 G17 G21 G90 G93"), "{}", b.line("$G"));
    b.line("G94");
    assert!(b.line("G1 X1").starts_with("error:22"), "G93 to G94 leaves no feed");
    b.run_to_idle(10_000);
}

/// Runs one G93 line and returns (first step, last step) in timer ticks.
fn g93_duration(settings: Settings, line: &str) -> (u64, u64, Bench<3>) {
    let mut b = Bench::<3>::new(settings);
    assert_eq!(replies(&b.line("G93")), (1, 0));
    let mut steps = Vec::new();
    b.send(line);
    b.send("\n");
    let mut ms = 0;
    while b.ctl.busy() || b.ctl.pending_moves() > 0 || b.shared.state() != ddastep::motion::shared::State::Idle {
        run_recording(&mut b, 10, &mut steps);
        ms += 10;
        assert!(ms < 200_000);
    }
    run_recording(&mut b, 2, &mut steps);
    assert_eq!(replies(&b.take()), (1, 0));
    (steps[0], *steps.last().unwrap(), b)
}

/// The ramp the engine walks for a move of `steps` (per axis) on the settings `s` and the
/// table `cfg`, from its geometry: the master's steps per mm of path and the path acceleration
/// every moving axis allows (`min $120+i / |unitᵢ|`), as Grbl limits a move.
fn master_ramp(s: &Settings, steps: [u32; 3], cfg: &ddastep::motion::ramp::RampConfig) -> inverse_time::MasterRamp {
    let d: Vec<f64> = (0..3).map(|i| steps[i] as f64 / s.steps_per_mm[i] as f64).collect();
    let len = d.iter().map(|v| v * v).sum::<f64>().sqrt();
    let accel = (0..3).filter(|&i| steps[i] != 0).map(|i| s.accel[i] as f64 * len / d[i]).fold(f64::MAX, f64::min);
    let master = *steps.iter().max().unwrap() as f64;
    // (S-curve: walked as the trapezoid at a / k, whose time its legs keep.)
    let accel = accel / s.s_slope() as f64;
    inverse_time::MasterRamp::new((master / len) as f32, accel as f32, s.per_mm(3), cfg)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// G93: the move takes 1/F minutes, measured from its first to its last step, within one
    /// step period at the slowest rate plus the ramp table's 1 ms granularity.
    #[test]
    fn g93_moves_last_one_over_f_minutes(
        x in 1u32..3000, y in 0u32..3000, z in 0u32..100,
        seconds in 0.05f64..3.0, scurve in any::<bool>(),
    ) {
        // Both shapes: the S's ramps are in the closed form (seed 002's "N pulses in time T").
        let shape = if scurve { ddastep::motion::ramp::Shape::SCurve } else { ddastep::motion::ramp::Shape::Trapezoid };
        let s = Settings { shape, ..Settings::BENCH };
        let line = format!("G1 X{}.{:02} Y-{}.{:02} Z{}.{:02} F{:.9}", x / 100, x % 100, y / 100, y % 100, z / 100, z % 100, 1.0 / (seconds / 60.0));
        let (first, last, b) = g93_duration(s, &line);
        let master = x.max(y).max(z) as u64;
        let ramp = master_ramp(&s, [x, y, z], &b.ctl.ramped().cfg);
        // (The library computes in f32, as Grbl: 1e-9 s when it ran in f64; f32 resolves a
        // duration to 6e-8 of itself, and the solver's few operations to a few of those: 2e-6
        // of the time, far below the ramp table's 1 ms.)
        let v = inverse_time::cruise_hz(master, seconds as f32, &ramp);
        let feasible = (inverse_time::duration_s(master, v, &ramp) as f64 - seconds).abs() < 2e-6 * seconds;
        // Faster than the axes allow ($110 = 60 kHz on every axis): Grbl's clamp to the max
        // rate; shorter than the ramp allows: the fastest triangle. Either runs longer.
        let v = v.min(60_000.0);
        let expected = inverse_time::duration_s(master, v, &ramp) as f64;
        prop_assert!(feasible || expected > seconds);
        prop_assert!(!feasible || (expected - seconds).abs() < 2e-6 * seconds);
        // The first step marks the end of the first step period: add that period back.
        let measured = (last - first) as f64 / TIMER_HZ as f64 + 1.0 / v.max(ramp.v0) as f64;
        let err = (measured - expected).abs();
        let period = 1.0 / ramp.v0.min(v) as f64;
        prop_assert!(err <= period + 1e-3, "{}: measured {} s, expected {} s, asked {} s (cruise {} Hz)", line, measured, expected, seconds, v);
    }
}

#[test]
fn g93_time_too_short_is_clamped_to_the_max_rate() {
    // 100 mm in 0.1 s would need 60 000 mm/min on X: the move runs at X's 36 000 mm/min.
    let (first, last, b) = g93_duration(Settings::BENCH, "G1 X100 F600");
    let measured = (last - first) as f64 / TIMER_HZ as f64;
    let ramp = master_ramp(&Settings::BENCH, [10_000, 0, 0], &b.ctl.ramped().cfg);
    let at_max = inverse_time::duration_s(10_000, 60_000.0, &ramp) as f64;
    assert!((measured - at_max).abs() < 2e-3, "measured {measured} s, at the max rate {at_max} s");
    assert!(measured > 0.1 + 0.05);
}

#[test]
fn g93_arc_lasts_one_over_f_minutes() {
    // A full circle of r = 10 in 2 s at $12=0.1 (23 chords): the chords share the time.
    let s = Settings { arc_tolerance: 0.1, ..Settings::BENCH };
    let (first, last, b) = g93_duration(s, "G2 X0 Y0 I10 F30");
    let measured = (last - first) as f64 / TIMER_HZ as f64;
    assert_eq!(b.shared.positions(), [0, 0, 0]);
    // Each chord starts and ends at rest (G93 moves do not join: their time is solved for
    // that); what the engine adds between two moves (up to one idle tick, 0.5 ms) comes on top.
    let chords = 23.0;
    assert!(measured >= 2.0 - 2e-3 && measured <= 2.0 + chords * 0.5e-3 + 2e-3, "measured {measured} s");
}
