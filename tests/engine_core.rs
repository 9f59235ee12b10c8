//! Step engine on the host: exact counts, the paper's 5:3:2, direction setup, feed hold,
//! immediate stop, slow rates (period extension).

mod common;

use common::Rig;
use ddastep::motion::moves::{Move, MoveError};
use ddastep::motion::shared::State;
use ddastep::motion::ramp::{RampConfig, RampError, RampTable, Shape};
use ddastep::motion::timing::Timing;
use ddastep::TIMER_HZ;

#[test]
fn paper_532_exact_counts_pattern_and_cruise() {
    let mut rig = Rig::<3>::trapezoid(1000, 60_000, 2_000_000);
    rig.push([5000, 3000, 2000], 50_000);
    rig.run_to_idle(1_000_000);
    assert_eq!(rig.net_steps(), [5000, 3000, 2000]);
    assert_eq!(rig.shared.positions(), [5000, 3000, 2000]);
    // The pattern: per 5 master steps, Y at 1,3,5 and Z at 2,4.
    let mut per_master: Vec<u32> = Vec::new();
    for s in &rig.steps {
        if s.axis == 0 {
            per_master.push(1);
        } else {
            *per_master.last_mut().unwrap() |= 1 << s.axis;
        }
    }
    assert_eq!(per_master.len(), 5000);
    for (k, m) in per_master.iter().enumerate() {
        let expect = if k % 5 % 2 == 0 { 0b011 } else { 0b101 };
        assert_eq!(*m, expect, "master step {}", k + 1);
    }
    // Cruise: the middle of the move runs at 50 kHz ± 0.5 % (averaged over 1000 steps).
    let t = rig.times(0);
    let mid = &t[2000..3000];
    let rate = 999.0 * TIMER_HZ as f64 / (mid[999] - mid[0]) as f64;
    assert!((rate - 50_000.0).abs() < 250.0, "cruise {rate}");
}

#[test]
fn direction_setup_is_honoured_on_every_change() {
    let timing = Timing::new(216, 720, 144); // 3 µs pulse, 10 µs setup
    let mut rig = Rig::<2>::new(
        RampConfig { v0: 2000, vmax: 100_000, accel: 500_000, shape: Shape::Trapezoid },
        timing,
    );
    let moves = [[300, -20], [-300, 20], [5, 5], [-1, -1], [400, 0], [-400, -399]];
    for m in moves {
        rig.push(m, 80_000);
    }
    rig.run_to_idle(1_000_000);
    let want: [i64; 2] = moves.iter().fold([0, 0], |a, m| [a[0] + m[0], a[1] + m[1]]);
    assert_eq!(rig.net_steps(), want);
    let mut checked = 0;
    for s in &rig.steps {
        let d = s.dir_changed_at.expect("dir written before the first step");
        assert!(s.t - d >= 720, "step at {} only {} ticks after dir", s.t, s.t - d);
        checked += 1;
    }
    assert!(checked > 1000);
    // And no two step edges of one axis closer than the minimum period.
    for a in 0..2 {
        let t = rig.times(a);
        assert!(t.windows(2).all(|w| w[1] - w[0] >= 216 * 2));
    }
}

#[test]
fn feed_hold_pauses_and_resume_finishes_exactly() {
    let mut rig = Rig::<3>::trapezoid(500, 40_000, 100_000);
    rig.push([20_000, -7_000, 3], 40_000);
    for _ in 0..3000 {
        rig.update();
    }
    rig.shared.set_hold(true);
    let mut held_at = None;
    for _ in 0..200_000 {
        rig.update();
        if rig.shared.state() == State::Held {
            held_at = Some(rig.times(0).len());
            break;
        }
    }
    let held_at = held_at.expect("hold completes");
    // Held: no steps for a while.
    for _ in 0..5000 {
        rig.update();
    }
    let after = rig.times(0).len();
    assert!(after <= held_at + 1, "master steps while held: {held_at} -> {after}");
    let pos = rig.shared.positions();
    assert!(pos[0] > 0 && pos[0] < 20_000, "paused mid-move at {pos:?}");
    // The deceleration went down the table: the last steps before the pause are slow.
    let t = rig.times(0);
    let last = t[t.len() - 1] - t[t.len() - 2];
    assert!(last > (TIMER_HZ / 2_000) as u64, "stopped from speed: last period {last}");
    rig.shared.set_hold(false);
    rig.run_to_idle(1_000_000);
    assert_eq!(rig.net_steps(), [20_000, -7_000, 3]);
    assert_eq!(rig.shared.positions(), [20_000, -7_000, 3]);
}

#[test]
fn immediate_stop_keeps_position_equal_to_pulses() {
    let mut rig = Rig::<2>::trapezoid(1000, 50_000, 300_000);
    rig.push([100_000, 50_000], 50_000);
    rig.push([-100_000, 0], 50_000);
    for _ in 0..7777 {
        rig.update();
    }
    rig.feeder.abort();
    rig.run_to_idle(10_000);
    let pos = rig.shared.positions();
    assert_eq!([pos[0] as i64, pos[1] as i64], rig.net_steps());
    assert!(pos[0] > 0 && pos[0] < 100_000);
    // Nothing more comes: the second move was dropped.
    for _ in 0..2000 {
        rig.update();
    }
    assert_eq!(rig.shared.positions(), pos);
    // The queue works again afterwards.
    rig.push([10, 0], 5000);
    rig.run_to_idle(100_000);
    assert_eq!(rig.shared.positions()[0], pos[0] + 10);
}

#[test]
fn one_step_per_second_uses_period_extension() {
    let mut rig = Rig::<1>::trapezoid(1, 10, 1000);
    rig.push([4], 1);
    rig.run_to_idle(100_000);
    let t = rig.times(0);
    assert_eq!(t.len(), 4);
    for w in t.windows(2) {
        let hz = TIMER_HZ as f64 / (w[1] - w[0]) as f64;
        assert!((hz - 1.0).abs() < 0.005, "rate {hz}");
    }
}

#[test]
fn slow_cruise_below_start_rate_runs_flat() {
    let mut rig = Rig::<1>::trapezoid(2000, 20_000, 50_000);
    rig.push([50], 700);
    rig.run_to_idle(100_000);
    let t = rig.times(0);
    for w in t.windows(2) {
        let p = (w[1] - w[0]) as f64;
        assert!((p - TIMER_HZ as f64 / 700.0).abs() <= 1.0, "period {p}");
    }
}

#[test]
fn bad_configuration_is_a_typed_error() {
    let mut t: RampTable = RampTable::new();
    let cfg = |v0, vmax, accel| RampConfig { v0, vmax, accel, shape: Shape::Trapezoid };
    assert_eq!(t.build(cfg(100, 1000, 0)), Err(RampError::ZeroAccel));
    assert_eq!(t.build(cfg(1000, 100, 10)), Err(RampError::VmaxBelowV0));
    assert_eq!(t.build(cfg(0, 100, 10)), Err(RampError::RateOutOfRange));
    assert_eq!(t.build(cfg(1, 2_000_000, 10)), Err(RampError::RateOutOfRange));
    match t.build(cfg(100, 100_000, 1000)) {
        Err(RampError::TooLong { reachable_vmax }) => {
            assert!(reachable_vmax < 100 + 1000 * ddastep::motion::ramp::RAMP_LEN as u32 / 1000 + 1);
            t.build(cfg(100, reachable_vmax, 1000)).expect("reachable vmax fits");
        }
        other => panic!("{other:?}"),
    }
    assert!(t.len() <= ddastep::motion::ramp::RAMP_LEN);
    assert_eq!(Move::<3>::new([0, 0, 0], 100), Err(MoveError::ZeroLength));
    assert_eq!(Move::<2>::new([1 << 31, 0], 100), Err(MoveError::TooManySteps));
    assert_eq!(Move::<2>::new([i64::MIN, 0], 100), Err(MoveError::TooManySteps));
    assert_eq!(Move::<1>::new([5], 0), Err(MoveError::RateOutOfRange));
    assert_eq!(Move::<1>::new([5], 1_000_001), Err(MoveError::RateOutOfRange));
    assert!(Move::<1>::new([-(i32::MAX as i64)], 1_000_000).is_ok());
}

#[test]
fn s_curve_table_is_the_trapezoids() {
    // `$41=1` keeps the table linear: the S is each leg mapped through the curve in the ramp
    // half (`ramp/scurve.rs`).
    let cfg = RampConfig { v0: 500, vmax: 50_000, accel: 400_000, shape: Shape::Trapezoid };
    let (mut t, mut s): (RampTable, RampTable) = (RampTable::new(), RampTable::new());
    t.build(cfg).unwrap();
    s.build(RampConfig { shape: Shape::SCurve, ..cfg }).unwrap();
    assert_eq!(t.periods(), s.periods());
}

#[test]
fn dithering_makes_the_average_cruise_rate_exact() {
    // 47 kHz is 1531.9 ticks: no whole period gives it; the average over 16 000 steps must.
    let mut rig = Rig::<1>::trapezoid(47_000, 47_000, 1_000);
    rig.push([20_000], 47_000);
    rig.run_to_idle(1_000_000);
    let t = rig.times(0);
    let periods: std::collections::BTreeSet<u64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    assert_eq!(periods.into_iter().collect::<Vec<_>>(), vec![1531, 1532]);
    let span = (t[18_000] - t[2_000]) as f64;
    let exact = 16_000.0 * TIMER_HZ as f64 / 47_000.0;
    // Periods are kept to 1/16 tick, so the average is exact to 1/32 tick per period (here
    // 0.002 %), plus one tick at the ends; rounding to whole ticks alone would be off by 0.006 %.
    assert!((span - exact).abs() <= 16_000.0 / 32.0 + 1.0, "{span} vs {exact}");
}

#[test]
fn positions_mid_move_equal_pulses_written_plus_the_pending_word() {
    let mut rig = Rig::<4>::trapezoid(1000, 80_000, 400_000);
    rig.push([-9_001, 4_000, 7_777, -3], 60_000);
    rig.push([500, -4_000, 0, 3], 30_000);
    let mut checked = 0;
    for i in 0..40_000u32 {
        rig.update();
        if i % 997 == 0 {
            let mut want = rig.net_steps();
            // The word already computed for the next edge is counted too.
            let pending = rig.engine.word();
            let pos = rig.shared.positions();
            for a in 0..4 {
                if pending & rig.pins.step_on[a] != 0 {
                    want[a] += if pos[a] as i64 > want[a] { 1 } else { -1 };
                }
            }
            assert_eq!(pos.map(|p| p as i64), want, "update {i}");
            checked += 1;
        }
    }
    assert!(checked > 30);
    rig.run_to_idle(1_000_000);
    assert_eq!(rig.shared.positions(), [-8_501, 0, 7_777, 0]);
}

/// A ramp pass preempted between its look at the ring and its store of the primed successor
/// can store, after the step half entered that successor, the move now running. The step
/// half takes only the slot after the running one: each move runs once, the queue ends
/// (before, the running move was entered again, its slot freed twice, and the ring's head
/// passed its tail: the engine replayed stale slots and the feeder saw a full ring for good,
/// the 10^5-line USB stream's stall).
#[test]
fn a_stale_primed_successor_is_not_entered() {
    let mut rig = Rig::<2>::trapezoid(1000, 60_000, 2_000_000);
    let moves = [[3, 1], [1, 0], [2, 2], [1, 1], [4, -1], [1, 0], [-2, 1], [1, 0]];
    for m in moves {
        rig.push(m, 50_000);
    }
    let start = rig.updates;
    loop {
        // At every edge, as if each ramp pass had been preempted so.
        rig.engine.stale_succ();
        rig.update();
        if rig.feeder.pending() == 0 && rig.shared.state() == State::Idle {
            rig.update();
            break;
        }
        assert!(rig.updates - start < 100_000, "engine did not finish");
    }
    let want = moves.iter().fold([0, 0], |a, m| [a[0] + m[0], a[1] + m[1]]);
    assert_eq!(rig.net_steps(), want);
    assert_eq!(rig.shared.positions(), [want[0] as i32, want[1] as i32]);
}
