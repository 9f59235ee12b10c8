//! Firmware in the loop: a CAM-style job with arcs on the emulated Blue Pill (rapids, cuts,
//! arcs in two planes, a helical full circle), checked against the ideal path.

mod fil;

use fil::*;

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
