//! S-curves (`$41=1`) on the host engine: every ramp leg through the seeds' logistic, walked
//! at a / k on the trapezoid's table (`ramp/scurve.rs`). Chains of moves on one axis whose
//! master is the table (a whole entry per ms: the linear walk accelerates at the table's `A`,
//! the S peaks at `k·A`).

mod common;

use common::Rig;
use ddastep::motion::ramp::{peak_slope, RampConfig, Shape, FLEX_DEFAULT};
use ddastep::motion::shared::State;
use ddastep::TIMER_HZ;
use proptest::prelude::*;

const V0: u32 = 2000;

/// Rates (Hz) of every step period of axis 0 and the chain's rig after it ran (a hold and its
/// resume, or a feed override, at update `at`).
fn run(accel: u32, moves: &[(i64, u32)], hold_at: Option<u64>) -> (Vec<f64>, Rig<1>) {
    run_with(accel, moves, hold_at, None)
}

fn run_with(accel: u32, moves: &[(i64, u32)], hold_at: Option<u64>, ovr: Option<(u64, u8)>) -> (Vec<f64>, Rig<1>) {
    let cfg = RampConfig { v0: V0, vmax: 60_000, accel, shape: Shape::SCurve };
    let mut rig = Rig::<1>::new(cfg, Rig::<1>::FAST);
    for &(s, hz) in moves {
        rig.push([s], hz);
    }
    if let Some((at, feed)) = ovr {
        for _ in 0..at {
            rig.update();
        }
        let mut o = rig.shared.overrides();
        o.feed = feed;
        rig.shared.set_overrides(o);
    }
    if let Some(at) = hold_at {
        for _ in 0..at {
            rig.update();
        }
        rig.shared.set_hold(true);
        for _ in 0..2_000_000 {
            rig.update();
            if rig.shared.state() == State::Held {
                break;
            }
        }
        rig.shared.set_hold(false);
    }
    rig.run_to_idle(50_000_000);
    let t = rig.times(0);
    let r = t.windows(2).map(|w| TIMER_HZ as f64 / (w[1] - w[0]) as f64).collect();
    (r, rig)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Exact counts; the rate never changes by more than the S's peak acceleration allows in
    /// a millisecond (`k·A`, plus a table step where a cruise between entries is reached), so
    /// never faster than the move's own acceleration; the first change of a ramp from rest is
    /// gentle (no jerk step); the chain ends within a table step of its start rate.
    #[test]
    fn s_chains_are_exact_and_never_steeper_than_their_acceleration(
        accel in 150_000u32..2_000_000,
        moves in prop::collection::vec((1i64..4000, 3000u32..60_000), 1..4),
        dirs in any::<u8>(),
    ) {
        let moves: Vec<(i64, u32)> = moves.iter().enumerate().map(|(i, &(s, hz))| (if dirs >> i & 1 == 1 { -s } else { s }, hz)).collect();
        let (r, rig) = run(accel, &moves, None);
        prop_assert_eq!(rig.net_steps()[0], moves.iter().map(|m| m.0).sum::<i64>());
        let k = peak_slope(FLEX_DEFAULT) as f64;
        let per_ms = accel as f64 / 1000.0;
        let bound = k * per_ms + per_ms;
        for (i, w) in r.windows(2).enumerate() {
            // (Periods up to 1 ms: one ramp millisecond between two steps at most.)
            if w[0] >= 1000.0 && w[1] >= 1000.0 {
                prop_assert!((w[1] - w[0]).abs() <= bound * 1.02 + 1.0, "step {}: {} -> {} Hz, bound {} Hz/ms", i, w[0], w[1], bound);
            }
        }
        // The first change from rest: the S's slow start (at most about k/2 of the walk's
        // step, `s(1/n)·n` for an n-ms leg).
        if let Some(first) = r.iter().position(|&x| (x - r[0]).abs() > 0.5) {
            prop_assert!(r[first] - r[0] <= 0.6 * k * per_ms + 1.0, "first change {} -> {} Hz ({} Hz/ms)", r[0], r[first], per_ms);
        }
        // The table's bottom entry is V0 + A·½ ms; one table step is A·1 ms (rates dither by
        // a few hertz around a period's 1/16 tick: 0.2 %).
        let last = *r.last().unwrap_or(&(V0 as f64));
        prop_assert!(last <= (V0 as f64 + per_ms * 1.5) * 1.002 + 1.0, "ends at {} Hz", last);
    }

    /// One move with a ramp of at least 12 ms: an S, not a line. It starts and ends its way up
    /// gently (the first and last changes a fraction of the linear walk's `A·1 ms`) and peaks
    /// at about `k·A` (the trapezoid: `A` throughout).
    #[test]
    fn a_long_ramp_is_an_s(accel in 150_000u32..2_000_000, extra in 12u32..40, steps in 20_000i64..40_000) {
        let per_ms = accel as f64 / 1000.0;
        let cruise = (V0 as f64 + per_ms * extra as f64).min(59_000.0) as u32;
        prop_assume!(cruise as f64 >= V0 as f64 + per_ms * 12.0);
        let (r, rig) = run(accel, &[(steps, cruise)], None);
        prop_assert_eq!(rig.net_steps()[0], steps);
        // The distinct rates of the way up, in order (each held for a ramp millisecond).
        let mut up: Vec<f64> = Vec::new();
        for &x in &r {
            if up.last().is_none_or(|&l| x > l + 0.5) {
                up.push(x);
            }
            if x >= cruise as f64 * 0.999 {
                break;
            }
        }
        let d: Vec<f64> = up.windows(2).map(|w| w[1] - w[0]).collect();
        let k = peak_slope(FLEX_DEFAULT) as f64;
        let steepest = d.iter().cloned().fold(0.0, f64::max);
        prop_assert!(d[0] <= 0.35 * per_ms, "first change {} Hz, A·1 ms {} Hz: {:?}", d[0], per_ms, d);
        prop_assert!(steepest >= 0.75 * k * per_ms && steepest <= k * per_ms * 1.02 + 1.0, "steepest {} Hz, k·A·1 ms {} Hz: {:?}", steepest, k * per_ms, d);
    }

    /// A feed override anywhere in an S chain: a new leg to the new cruise, as steep as any
    /// other, and every step exactly once.
    #[test]
    fn s_override_walks_to_the_new_cruise_as_an_s(
        accel in 150_000u32..2_000_000,
        moves in prop::collection::vec((1i64..4000, 3000u32..60_000), 1..4),
        at in 10u64..20_000, feed in 10u8..=200,
    ) {
        let (r, rig) = run_with(accel, &moves, None, Some((at, feed)));
        prop_assert_eq!(rig.net_steps()[0], moves.iter().map(|m| m.0).sum::<i64>());
        let bound = (peak_slope(FLEX_DEFAULT) as f64 + 1.0) * accel as f64 / 1000.0;
        for (i, w) in r.windows(2).enumerate() {
            if w[0] >= 1000.0 && w[1] >= 1000.0 {
                prop_assert!((w[1] - w[0]).abs() <= bound * 1.02 + 1.0, "step {}: {} -> {} Hz, bound {} Hz/ms", i, w[0], w[1], bound);
            }
        }
    }

    /// A feed hold anywhere in an S chain, and the resume: every step made exactly once.
    #[test]
    fn s_hold_and_resume_keep_counts_exact(
        accel in 150_000u32..2_000_000,
        moves in prop::collection::vec((1i64..4000, 3000u32..60_000), 1..4),
        hold_at in 10u64..20_000,
    ) {
        let (_, rig) = run(accel, &moves, Some(hold_at));
        prop_assert_eq!(rig.net_steps()[0], moves.iter().map(|m| m.0).sum::<i64>());
        prop_assert_eq!(rig.shared.positions()[0] as i64, moves.iter().map(|m| m.0).sum::<i64>());
    }
}
