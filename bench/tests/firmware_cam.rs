//! Firmware in the loop: a CAM-style job with arcs on the emulated Blue Pill (rapids, cuts,
//! arcs in two planes, a helical full circle), checked against the ideal path.

mod firmware_rig;

use ddastep_bench::emu::HZ;
use firmware_rig::*;

/// The job: (line, what the ideal path travels on X, Y, Z in mm for that line).
const JOB: [(&str, [f64; 3]); 11] = [
    ("G21 G90 G17 G94", [0.0; 3]),
    ("$12=0.01", [0.0; 3]),
    ("G0 X20 Y0 Z5", [20.0, 0.0, 5.0]),
    ("G1 Z-1 F1200", [0.0, 0.0, 6.0]),
    ("G1 X30 F3000", [10.0, 0.0, 0.0]),
    // Quarter circle CCW about (20, 0): X 30 → 20, Y 0 → 10.
    ("G3 X20 Y10 I-10 J0", [10.0, 10.0, 0.0]),
    // R form, back to (30, 0) clockwise about (20, 0).
    ("G2 X30 Y0 R10", [10.0, 10.0, 0.0]),
    // Full circle about (20, 0), descending 1 mm: X and Y each travel 4r.
    ("G2 X30 Y0 I-10 J0 Z-2", [40.0, 40.0, 1.0]),
    // ZX plane: half circle about (X20, Z-2) to X10; clockwise seen from +Y passes Z = 8.
    ("G18 G2 X10 Z-2 I-10 K0", [20.0, 0.0, 20.0]),
    ("G17 G0 Z5", [0.0, 0.0, 7.0]),
    ("G0 X0 Y0", [10.0, 0.0, 0.0]),
];

#[test]
fn cam_job_with_arcs_runs_without_error_and_ends_exactly() {
    let mut b = boot();
    for (line, _) in JOB {
        let r = reply(&mut b, line);
        assert!(r.contains("ok") && !r.contains("error"), "{line}: {r}");
    }
    wait_idle(&mut b, 30.0);
    let s = steps(&b);
    // Ends exactly at (0, 0, 5).
    assert_eq!(net(&s)[..3], [0, 0, 500]);
    assert!(status(&mut b).contains("MPos:0.000,0.000,5.000"), "{}", status(&mut b));
    // Every axis's pulses match the ideal path's travel: chord ends are rounded to whole steps,
    // so each turning point of an axis may cost it up to a step each way.
    let mut ideal = [0.0f64; 3];
    for (_, t) in JOB {
        for a in 0..3 {
            ideal[a] += t[a] * 100.0;
        }
    }
    let mut gross = [0i64; 3];
    for st in &s {
        gross[st.axis] += 1;
    }
    eprintln!("steps per axis {gross:?}, ideal path {ideal:?}");
    for a in 0..3 {
        assert!((gross[a] as f64 - ideal[a]).abs() <= 8.0, "axis {a}: {} steps, ideal path {}", gross[a], ideal[a]);
    }
    assert_eq!(b.report().overruns, 0);
    assert!(b.fault().is_none());
}

#[test]
fn laser_m4_pwm_duty_follows_the_step_rate_through_a_ramp() {
    let mut b = boot();
    // Laser mode; a slow ramp (10^4 steps/s², 1 kHz to 5 kHz in 0.4 s) so the ramp is long
    // against the 1 ms poll and the 1 ms PWM period.
    for line in ["$32=1", "$120=100", "$121=100", "$122=100", "M8", "G1 F3000 M4 S1000", "G1 X30"] {
        ok(&mut b, line);
    }
    wait_idle(&mut b, 5.0);
    let x: Vec<u64> = steps(&b).iter().filter(|s| s.axis == 0).map(|s| s.cycle).collect();
    assert_eq!(x.len(), 3000);
    let pwm = b.pwm_changes().to_vec();
    assert!(pwm.iter().all(|c| (c.hz - 1000.0).abs() < 0.1), "1 kHz PWM");
    let ms = HZ / 1000;
    let (first, last) = (x[0], *x.last().unwrap());
    let (mut checked, mut ramp, mut worst) = (0, 0, 0.0f64);
    for c in pwm.iter().filter(|c| c.cycle > first + 3 * ms && c.cycle + 3 * ms < last) {
        // The X step rate over the last four step periods before the change (the poll reads
        // the engine's rate, the compare register takes it at the next PWM period).
        let k = x.partition_point(|&t| t <= c.cycle);
        if k < 5 {
            continue;
        }
        let k = k - 1;
        let rate = 4.0 * HZ as f64 / (x[k] - x[k - 4]) as f64;
        let want = (rate / 5000.0).min(1.0);
        assert!((c.duty - want).abs() <= 0.02, "at {} ms: duty {:.3}, rate {rate:.0} Hz", c.cycle / ms, c.duty);
        worst = worst.max((c.duty - want).abs());
        checked += 1;
        if c.duty > 0.3 && c.duty < 0.9 {
            ramp += 1;
        }
    }
    eprintln!("{checked} duty changes while moving, largest difference from rate/cruise {worst:.4}");
    // The ramps spend ≈ 600 ms between 30 % and 90 % duty. The engine changes the rate at its
    // first step after each ramp millisecond and the idle loop polls once per SysTick ms: two
    // 1 ms clocks that drift, so a poll now and then sees two changes at once or none. Most
    // milliseconds must still bring a new duty (each one checked against the rate above).
    assert!(ramp > 420, "{ramp} duty steps on the ramps ({checked} checked)");
    assert_eq!(b.pwm_changes().last().unwrap().duty, 0.0, "laser off once stopped");
    let sp = b.report().spindle;
    assert!((sp.max_duty - 1.0).abs() < 1e-9, "full power at cruise: {sp:?}");
    assert_eq!(sp.pin_rises, [1, 1, 1, 0], "spindle enable, M4 direction, flood; no mist");
    ok(&mut b, "M5 M9");
    b.run_seconds(0.01).unwrap();
    for (pin, name) in ddastep_bench::emu::TOOL_PINS {
        assert!(!b.output(ddastep_bench::emu::Port::A, pin), "{name} off after M5 M9");
    }
}
