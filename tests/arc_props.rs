//! Arcs (G2/G3) against their invariants: random arcs in the three planes, IJK and R forms,
//! through the real interpreter and planner; and Grbl's error numbers for bad arcs.

use ddastep::planning::arc::{plane_axes, Arc, Segments};
use ddastep::grbl::gcode::{parse, Modal};
use ddastep::planning::planner::{to_steps, Planner};
use ddastep::error::Error;
use ddastep::grbl::settings::Settings;
use proptest::prelude::*;
use std::f64::consts::PI;

/// Interprets `line` at `pos` after `setup` lines (modal words), returning the arc.
fn arc_of(setup: &str, line: &str, pos: [f64; 3]) -> Result<Arc<3>, Error> {
    let pos = pos.map(|v| v as f32);
    let mut m = Modal::RESET;
    for l in setup.split_whitespace() {
        m = m.interpret::<3>(&parse::<3>(l.as_bytes())?, &pos)?.0;
    }
    let (_, fx) = m.interpret::<3>(&parse::<3>(line.as_bytes())?, &pos)?;
    Ok(fx.arc.expect("an arc"))
}

/// Distance from `p` to the segment `a`–`b` (2-D).
fn dist_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 == 0.0 { 0.0 } else { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0) };
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}

/// Checks every chord of `seg` against the true arc; returns the chord ends. (The library
/// computes in `f32`, as Grbl; the checks widen its values to `f64`, which is exact.)
///
/// Tolerances: 1e-9 of the arc's scale when the library ran in f64; f32 rounds each
/// coordinate to 6e-8 of its size and each angle to 6e-8 of the travel (a few of those per
/// chord end), so 1e-6 of the scale (0.5 µm on a 300 mm arc at 200 mm, below a step of 4 µm).
fn check_chords(arc: &Arc<3>, start: [f64; 3], seg: Segments<3>, tol: f64) -> Vec<[f64; 3]> {
    let start = start.map(|v| v as f32 as f64);
    let (a, b) = arc.axes();
    let c = arc.center().map(f64::from);
    let r = arc.radius() as f64;
    let travel = arc.travel() as f64;
    let target = arc.target().map(f64::from);
    let chords = seg.chords();
    let ends: Vec<[f64; 3]> = seg.map(|e| e.map(f64::from)).collect();
    assert_eq!(ends.len() as u32, chords);
    assert_eq!(ends.last().unwrap(), &target, "last chord ends on the target, bit for bit");
    let n = ends.len() as f64;
    let lin = 3 - a - b;
    let mut prev = start;
    for (i, p) in ends.iter().enumerate() {
        let k = (i + 1) as f64;
        if i + 1 < ends.len() {
            // On the circle, at the angle k/n of the travel; the helix axis in proportion.
            let ang = travel * k / n;
            let (s0, s1) = (start[a] - c[0], start[b] - c[1]);
            let want = [c[0] + s0 * ang.cos() - s1 * ang.sin(), c[1] + s0 * ang.sin() + s1 * ang.cos()];
            let scale = 1e-6 * (1.0 + r + c[0].abs() + c[1].abs());
            assert!((p[a] - want[0]).abs() < scale && (p[b] - want[1]).abs() < scale, "chord end {i}: {p:?} vs {want:?}");
            let want_lin = start[lin] + (target[lin] - start[lin]) * k / n;
            assert!((p[lin] - want_lin).abs() < 1e-6 * (1.0 + start[lin].abs() + target[lin].abs()));
        }
        // The true arc between the two ends stays within tol of the chord.
        let a0 = (prev[b] - c[1]).atan2(prev[a] - c[0]);
        let span = travel / n;
        for j in 0..=16 {
            let t = a0 + span * j as f64 / 16.0;
            let q = [c[0] + r * t.cos(), c[1] + r * t.sin()];
            let d = dist_to_segment(q, [prev[a], prev[b]], [p[a], p[b]]);
            // The last chord may end up to the IJK radius mismatch off the circle.
            // (The f32 chord ends' own error, as above.)
            let slack = if i + 1 == ends.len() { 1e-6 * (1.0 + r) } else { 0.0 } + 1e-6 * (1.0 + r + c[0].abs() + c[1].abs());
            assert!(d <= tol + slack, "chord {i}: {d} from the arc (tol {tol}, r {r})");
        }
        prev = *p;
    }
    ends
}

fn letter(axis: usize) -> char {
    ['X', 'Y', 'Z'][axis]
}

/// Half an f32 ulp, relative (the library reads and computes in f32, as Grbl).
const EPS32: f64 = f32::EPSILON as f64 / 2.0;

/// How far off π a sweep may be for rounding to push an R arc's chord past the diameter (see
/// the `ArcRadiusError` arm below): r·δ²/4 ≤ the chord's error, with a factor of 2 margin. In
/// f64 that error was the 6 decimals' 0.71 µm; in f32 add the words' own rounding (coordinates
/// up to `m` mm, 4 roundings of their size) and that of 4r² - d² (8 ulps of r², as Grbl's).
fn near_half_window(r: f64, m: f64) -> f64 {
    ((5.7e-6 + 2.0 * 4.0 * 4.0 * EPS32 * m) / r + 2.0 * 8.0 * EPS32).sqrt().max(1e-3)
}

/// The travel's error (rad) from f32 (nothing in f64): the words' rounding (4 roundings of
/// coordinates up to `m` mm) turns the ends by that over r; an R arc's center moves along the
/// chord's bisector by the error of 4r² - d² (8 ulps of r², plus the chord's) over 2·r·δ, δ its
/// sweep's distance from a half circle.
fn f32_travel_slack(r: f64, m: f64, radius_form: bool, sweep: f64) -> f64 {
    let coord = 4.0 * EPS32 * m;
    let near = if radius_form { (8.0 * EPS32 * r * r + 4.0 * r * coord) / (2.0 * r * r * (sweep - PI).abs().max(1e-9)) } else { 0.0 };
    2.0 * (coord / r + near)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn random_arcs_end_exactly_and_stay_within_tolerance(
        plane in 17u8..=19,
        r in 0.05f64..300.0,
        a0 in -PI..PI,
        sweep in 0.001f64..(2.0 * PI),
        cw in any::<bool>(),
        full in prop::bool::weighted(0.1),
        radius_form in any::<bool>(),
        helix in -50.0f64..50.0,
        sx in -200.0f64..200.0, sy in -200.0f64..200.0, sz in -200.0f64..200.0,
        tol in prop::sample::select(vec![0.0005, 0.002, 0.01, 0.1, 1.0]),
    ) {
        let (a, b) = plane_axes(plane);
        let lin = 3 - a - b;
        let round6 = |v: f64| (v * 1e6).round() / 1e6;
        let start = [round6(sx), round6(sy), round6(sz)];
        let sweep = if full && !radius_form { 2.0 * PI } else { sweep };
        let c = [start[a] - r * a0.cos(), start[b] - r * a0.sin()];
        let end_angle = if cw { a0 - sweep } else { a0 + sweep };
        // The target and offsets have 6 decimals, as a CAM post writes them.
        let mut target = start;
        if !(full && !radius_form) {
            target[a] = round6(c[0] + r * end_angle.cos());
            target[b] = round6(c[1] + r * end_angle.sin());
        }
        target[lin] = round6(start[lin] + helix);
        let words = format!("{}{:.6}{}{:.6}{}{:.6}", letter(a), target[a], letter(b), target[b], letter(lin), target[lin]);
        let center = if radius_form {
            let r_word = if sweep > PI { -r } else { r };
            format!("R{r_word:.6}")
        } else {
            let (i, j) = (round6(c[0] - start[a]), round6(c[1] - start[b]));
            let names = ['I', 'J', 'K'];
            format!("{}{i:.6}{}{j:.6}", names[a], names[b])
        };
        let line = format!("G{}{words}{center}F1000", if cw { 2 } else { 3 });
        // The largest coordinate the arc's words and center reach, mm (f32 resolves it to 6e-8).
        let m = start.iter().chain(&target).chain(&c).fold(r, |m, v| m.max(v.abs() + r));
        let setup = format!("G{plane} G90");
        let arc = match arc_of(&setup, &line, start) {
            Ok(arc) => arc,
            // An R arc whose rounded words put the chord just beyond the diameter: rounding
            // moves the target by up to 0.71 µm, and a half circle's chord falls short of 2r by
            // r·δ²/4 for a sweep δ off π, so a small radius needs a wider window than 1e-3.
            Err(Error::ArcRadiusError) if radius_form && (sweep - PI).abs() < near_half_window(r, m) => return Ok(()),
            // A rounded R form so close to the start that the target equals it.
            Err(Error::InvalidTarget) if radius_form && target == start => return Ok(()),
            Err(e) => panic!("{line}: {e:?}"),
        };
        // Direction and extent: G2 turns negative, G3 positive, as far as asked.
        prop_assert_eq!(arc.travel() < 0.0, cw, "{}", line);
        let near_half = radius_form && (sweep - PI).abs() < near_half_window(r, m);
        let tiny = r * sweep < 1e-4;
        if !near_half && !tiny {
            // 1e-4 rad, plus what f32 needs (see f32_travel_slack).
            prop_assert!((arc.travel().abs() as f64 - sweep).abs() < 1e-4 + f32_travel_slack(r, m, radius_form, sweep), "{} travel {} want {}", line, arc.travel(), sweep);
        }
        let seg = arc.segments(tol);
        let ends = check_chords(&arc, start, seg, tol as f64);
        // Step counts: the chords as planned moves add up to the whole arc's steps.
        let lim = Settings::BENCH.planner_limits::<3>(60_000);
        let mut p = Planner::<3>::new();
        let start = start.map(|v| v as f32);
        p.set_position(&start.map(Some), &lim).unwrap();
        let mut sum = [0i64; 3];
        for e in &ends {
            if let Some(pl) = p.line(&e.map(|v| v as f32), Some(1000.0), &lim).unwrap() {
                for (s, d) in sum.iter_mut().zip(pl.mv.steps()) {
                    *s += *d as i64;
                }
            }
        }
        let spm = |k: usize| Settings::BENCH.steps_per_mm[k];
        // The target as the library read it from the words (the nearest f32 to each).
        let target = *arc.target();
        let want: [i64; 3] = std::array::from_fn(|k| to_steps(target[k], spm(k)).unwrap() - to_steps(start[k], spm(k)).unwrap());
        prop_assert_eq!(sum, want);
        prop_assert_eq!(p.position_mm(), &target);
    }
}

#[test]
fn long_arcs_do_not_drift() {
    // 1 m radius, 0.1 µm tolerance: ~7000 chords; every end stays on the circle.
    let arc = arc_of("", "G3X0Y0I1000F100", [0.0, 0.0, 0.0]).unwrap();
    let seg = arc.segments(0.0001);
    assert!(seg.chords() > 7000, "{}", seg.chords());
    let ends = check_chords(&arc, [0.0, 0.0, 0.0], seg, 0.0001);
    assert_eq!(ends.last().unwrap(), &[0.0, 0.0, 0.0]);
}

#[test]
fn segment_count_follows_the_tolerance() {
    // r = 10, tol = 0.002: φmax = 4·asin(√0.0001) = 0.04 rad; a full circle needs ⌈2π/0.04⌉
    // (158) chords, or one more from the bound on asin.
    let arc = arc_of("", "G2X0Y0I10F100", [0.0, 0.0, 0.0]).unwrap();
    let ideal = (2.0 * PI / (4.0 * 0.01f64.asin())).ceil() as u32;
    let n = arc.segments(0.002).chords();
    assert!(n == ideal || n == ideal + 1, "{n} chords, ideal {ideal}");
    // A coarse tolerance: 0.5 on r = 10 (x = 0.158): within 0.1 % of the ideal count.
    let ideal = 2.0 * PI / (4.0 * (0.025f64).sqrt().asin());
    let n = arc.segments(0.5).chords() as f64;
    assert!(n >= ideal && n <= (ideal * 1.001).ceil(), "{n} chords, ideal {ideal}");
    // 1e-12 rad in f64; the f32 travel is 2π less the f32 atan2, to about an ulp of 2π.
    assert!((arc.travel() as f64 + 2.0 * PI).abs() < 1e-6);
    // A tolerance above the diameter still turns at most a half circle per chord.
    assert_eq!(arc.segments(50.0).chords(), 2);
}

#[test]
fn radius_form_picks_grbls_center() {
    // From (0,0) to (10,0) with R5: a half circle; G2 passes above (center (5,0)).
    let arc = arc_of("", "G2X10R5F100", [0.0, 0.0, 0.0]).unwrap();
    assert!((arc.center()[0] - 5.0).abs() < 1e-12 && arc.center()[1].abs() < 1e-6);
    // R10 to (10,0): G2 short way → center below the chord (Grbl's sign), travel under π.
    let arc = arc_of("", "G2X10R10F100", [0.0, 0.0, 0.0]).unwrap();
    assert!(arc.center()[1] < 0.0 && (arc.travel() as f64) > -PI);
    let arc = arc_of("", "G2X10R-10F100", [0.0, 0.0, 0.0]).unwrap();
    assert!(arc.center()[1] > 0.0 && (arc.travel() as f64) < -PI);
    let arc = arc_of("", "G3X10R10F100", [0.0, 0.0, 0.0]).unwrap();
    assert!(arc.center()[1] > 0.0 && arc.travel() > 0.0 && (arc.travel() as f64) < PI);
    // Inches: R and IJK scale like the axes.
    let arc = arc_of("G20", "G2X1I0.5F10", [0.0, 0.0, 0.0]).unwrap();
    // 1e-12 mm in f64; in f32 12.7 itself is 1.9e-7 off, and the radius is a root of a sum
    // of squares: 2 ulps (2e-6 mm).
    assert!((arc.radius() as f64 - 12.7).abs() < 2e-6);
}

#[test]
fn bad_arcs_get_grbls_error_numbers() {
    let o = [0.0, 0.0, 0.0];
    let e = |setup: &str, line: &str| arc_of(setup, line, o).err();
    assert_eq!(e("", "G2X10I5"), Some(Error::UndefinedFeedRate));
    assert_eq!(e("", "G2I5F100"), Some(Error::NoAxisWords));
    assert_eq!(e("", "G2Z5I5F100"), Some(Error::NoAxisWordsInPlane));
    assert_eq!(e("G18", "G2Y5I5F100"), Some(Error::NoAxisWordsInPlane));
    assert_eq!(e("", "G2X10F100"), Some(Error::NoOffsetsInPlane));
    assert_eq!(e("", "G2X10K5F100"), Some(Error::NoOffsetsInPlane));
    assert_eq!(e("G18", "G2X10J5F100"), Some(Error::NoOffsetsInPlane));
    assert_eq!(e("", "G2X10R4.9F100"), Some(Error::ArcRadiusError));
    assert_eq!(e("", "G2X0Y0R5F100"), Some(Error::InvalidTarget)); // R form: no full circle
    assert_eq!(e("", "G2X0Z5R5F100"), Some(Error::InvalidTarget)); // R form: chord of zero
    assert_eq!(e("", "G2X10I4F100"), Some(Error::InvalidTarget)); // radii 4 and 6
    // Radii 0.008 mm apart: refused on r = 5 (over 0.1 %), taken on r = 100 (Grbl's rule).
    assert_eq!(e("", "G2X10I5.004F100"), Some(Error::InvalidTarget));
    assert_eq!(e("", "G2X200I100.004F100"), None);
    assert_eq!(e("", "G2X1I0.5004F100"), None); // 0.0008 mm: within 0.005 mm
    assert_eq!(e("", "G2X10I5R5F100"), Some(Error::UnusedWords));
    assert_eq!(e("", "G2X1E999I5F100"), Some(Error::UnsupportedCommand));
    assert_eq!(e("G93", "G2X10I5"), Some(Error::UndefinedFeedRate));
    // Arc words without an arc.
    let pos = [0.0; 3];
    let run = |s: &str| Modal::RESET.interpret::<3>(&parse::<3>(s.as_bytes()).unwrap(), &pos).err();
    assert_eq!(run("G1X1I1F100"), Some(Error::UnusedWords));
    assert_eq!(run("R5"), Some(Error::UnusedWords));
    assert_eq!(run("G92X0J1"), Some(Error::UnusedWords));
    assert_eq!(run("G93G1X1"), Some(Error::UndefinedFeedRate));
    assert_eq!(run("G93G92X1"), None);
    assert_eq!(run("G93G0X1"), None);
}
