//! Properties of the engine over random moves, ramps and feed holds, simulated tick by tick
//! with time accumulated from the returned periods.

mod common;

use common::Rig;
use ddastep::motion::moves::Move;
use ddastep::motion::shared::State;
use ddastep::motion::ramp::{RampConfig, RampTable, Shape};
use ddastep::TIMER_HZ;
use proptest::prelude::*;

const TICKS: f64 = TIMER_HZ as f64;

/// A random ramp whose acceleration fits the table, and a cruise rate for the move.
fn ramp_and_cruise() -> impl Strategy<Value = (u32, u32, u32, u32)> {
    (1u32..5_000, 2_000u32..490_000, 0.05f64..0.5, 0.0f64..1.2).prop_map(|(v0, span, t, c)| {
        let vmax = v0 + span;
        // Ramp time t·1.0 s (fits the 512-entry table).
        let accel = ((span as f64 / t).ceil() as u32).max(1);
        let cruise = ((vmax as f64 * c) as u32).clamp(1, vmax);
        (v0, vmax, accel, cruise)
    })
}

/// Steps per axis: up to 7 axes, up to ±10^6, bounded so a case stays fast.
fn steps7() -> impl Strategy<Value = [i64; 7]> {
    (1i64..1_000_000, prop::array::uniform7(-1.0f64..1.0), 1usize..=7).prop_map(|(m, r, n)| {
        let mut s = [0i64; 7];
        for i in 0..n {
            s[i] = (m as f64 * r[i]) as i64;
        }
        if s.iter().all(|&x| x == 0) {
            s[0] = m;
        }
        s
    })
}

/// Analytic duration of a stop-to-stop trapezoid (s) of `l` steps.
fn analytic_time(l: f64, v0: f64, vc: f64, a: f64) -> f64 {
    if vc <= v0 {
        return l / vc;
    }
    let t_acc = (vc - v0) / a;
    let s_acc = (v0 + vc) / 2.0 * t_acc;
    if 2.0 * s_acc <= l {
        2.0 * t_acc + (l - 2.0 * s_acc) / vc
    } else {
        let vp = (v0 * v0 + a * l).sqrt();
        2.0 * (vp - v0) / a
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 40, ..ProptestConfig::default() })]

    #[test]
    fn moves_are_exact_in_count_ratio_and_time((v0, vmax, accel, cruise) in ramp_and_cruise(),
                                                 steps in steps7()) {
        let counts: Vec<u64> = steps.iter().map(|s| s.unsigned_abs()).collect();
        let m = *counts.iter().max().unwrap();
        // Keep the simulated time (and so the test time) bounded.
        prop_assume!(m as f64 / cruise as f64 <= 60.0);
        let mut rig = Rig::<7>::trapezoid(v0, vmax, accel);
        let table_vmax = vmax;
        rig.push(steps, cruise);
        rig.run_to_idle(u64::MAX);

        // Exact counts and directions, on the pins and in the position counters.
        prop_assert_eq!(rig.net_steps(), steps);
        let pos = rig.shared.positions();
        prop_assert_eq!(pos.map(|p| p as i64), steps);

        // Slaves within ½ step of the ideal line at every master step.
        let master = ddastep::motion::interp::master_axis(&counts.iter().map(|&c| c as u32).collect::<Vec<_>>());
        let mut k = 0u64;
        let mut done = [0u64; 7];
        let mut by_time = rig.steps.iter().peekable();
        while let Some(s) = by_time.next() {
            done[s.axis] += 1;
            let same_edge = by_time.peek().is_some_and(|n| n.t == s.t);
            if !same_edge {
                k = done[master];
                for a in 0..7 {
                    let dev = 2 * (m as i128 * done[a] as i128 - k as i128 * counts[a] as i128);
                    prop_assert!(dev.unsigned_abs() <= m as u128,
                        "axis {} made {} of {} at master step {} of {}", a, done[a], counts[a], k, m);
                }
            }
        }
        prop_assert_eq!(k, m);

        // Rates: accelerating steps run the table entry of their millisecond, which is the
        // ideal trapezoid's mean rate there within 0.5 % (or one tick); cruise steps run the
        // cruise rate within 0.5 % (or one tick).
        let t = rig.times(master);
        let t0 = t[0];
        let slaves = counts.iter().filter(|&&c| c > 0).count() as u32 - 1;
        let vc = cruise.min(table_vmax).min(Rig::<7>::FAST.max_rate_for(slaves)) as f64;
        let a = accel as f64;
        let t_acc = if vc > v0 as f64 { (vc - v0 as f64) / a } else { 0.0 };
        let total = analytic_time(m as f64, v0 as f64, vc, a);
        let triangle = 2.0 * t_acc >= total;
        let mut checked = 0;
        for j in 0..t.len().saturating_sub(1) {
            let p = (t[j + 1] - t[j]) as f64;
            let since = (t[j] - t0) as f64 / TICKS;
            let to_end = (t[t.len() - 1] - t[j]) as f64 / TICKS;
            let ideal = if since + 0.001 < t_acc && (!triangle || since + 0.002 < total / 2.0) {
                let w = (since * 1000.0).floor();
                (v0 as f64 + a * (w + 0.5) / 1000.0).min(vc)
            } else if !triangle && since > t_acc + 0.001 && to_end > t_acc + 0.002 {
                vc
            } else {
                continue;
            };
            let p_ideal = TICKS / ideal;
            prop_assert!((p - p_ideal).abs() <= (0.005 * p_ideal).max(1.0) + 1.0,
                "step {} at {:.4} s: period {} vs ideal {:.1} ({} Hz)", j, since, p, p_ideal, ideal);
            checked += 1;
        }
        prop_assert!(checked > 0 || m < 50 || t_acc < 0.002);

        // Whole move time vs the analytic trapezoid: 1 % plus the slowest two periods (the
        // last steps may run at the bottom entry when the mirrored ramp lands a step early).
        let measured = (t[t.len() - 1] - t0) as f64 / TICKS + 1.0 / vc.max(1.0);
        let slack = 0.01 * total + 2.0 / (v0 as f64 + a / 2000.0).min(vc) + 0.002;
        prop_assert!((measured - total).abs() <= slack,
            "move took {:.5} s, analytic {:.5} s (slack {:.5})", measured, total, slack);
    }

    #[test]
    fn feed_hold_and_resume_keep_counts_exact(steps in steps7(), hold_at in 10u64..20_000,
                                               held_for in 0u64..5_000, shape in any::<bool>()) {
        let shape = if shape { Shape::SCurve } else { Shape::Trapezoid };
        let cfg = RampConfig { v0: 800, vmax: 120_000, accel: 800_000, shape };
        let mut rig = Rig::<7>::new(cfg, ddastep::motion::timing::Timing::DEFAULT);
        let steps = steps.map(|s| s / 20); // a few seconds at most
        prop_assume!(steps.iter().any(|&s| s != 0));
        rig.push(steps, 100_000);
        rig.push(steps.map(|s| -s), 60_000);
        for _ in 0..hold_at { rig.update(); }
        rig.shared.set_hold(true);
        for _ in 0..300_000 {
            rig.update();
            if rig.shared.state() == State::Held { break; }
        }
        let frozen = rig.shared.positions();
        for _ in 0..held_for { rig.update(); }
        let after = rig.shared.positions();
        // At most the one word already computed when the hold completed.
        for a in 0..7 { prop_assert!((after[a] - frozen[a]).abs() <= 1); }
        rig.shared.set_hold(false);
        rig.run_to_idle(u64::MAX);
        prop_assert_eq!(rig.net_steps(), [0i64; 7]);
        prop_assert_eq!(rig.shared.positions(), [0i32; 7]);
    }

    #[test]
    fn direction_setup_holds_for_random_move_sequences(moves in prop::collection::vec(
            prop::array::uniform3(-300i64..300), 1..8), setup in 1u32..2000, pulse in 7u32..400) {
        let timing = ddastep::motion::timing::Timing::new(pulse, setup, 144);
        let cfg = RampConfig { v0: 1000, vmax: 200_000, accel: 1_000_000, shape: Shape::Trapezoid };
        let mut rig = Rig::<3>::new(cfg, timing);
        let mut want = [0i64; 3];
        for m in &moves {
            if Move::new(*m, 150_000).is_ok() {
                rig.push(*m, 150_000);
                for a in 0..3 { want[a] += m[a]; }
            }
        }
        rig.run_to_idle(u64::MAX);
        prop_assert_eq!(rig.net_steps(), want);
        for s in &rig.steps {
            let d = s.dir_changed_at.expect("direction written before the first step");
            prop_assert!(s.t - d >= setup as u64);
        }
        for a in 0..3 {
            let t = rig.times(a);
            prop_assert!(t.windows(2).all(|w| w[1] - w[0] >= timing.min_period_ticks as u64));
        }
    }

    /// The engine's two halves out of step (the ramp interrupt runs only every `lag + 1` ticks,
    /// as when the step interrupt leaves it little time near the cap): chains of moves at speed
    /// (look-ahead junctions, direction changes) still end every axis on its exact count, every
    /// move is entered once (the count of moves done is the count pushed), the direction setup
    /// holds, no period is shorter than the timing allows, and a hold still comes to rest and
    /// resumes exactly.
    #[test]
    fn chains_stay_exact_when_the_ramp_half_lags(moves in prop::collection::vec(
            prop::array::uniform3(-3000i64..3000), 1..12), lag in 0u32..60, cruise in 20_000u32..200_000,
            hold_at in prop::option::of(100u64..5_000)) {
        use ddastep::grbl::settings::Settings;
        let mut s = Settings::BENCH;
        s.accel = [200_000.0; ddastep::MAX_AXES];
        let mut rig = Rig::<3>::with_settings(&s);
        rig.engine.set_ramp_lag(lag);
        let timing = s.timing();
        let (mut want, mut n) = ([0i64; 3], 0u32);
        for m in &moves {
            if Move::new(*m, cruise).is_ok() {
                rig.push(*m, cruise);
                n += 1;
                for a in 0..3 { want[a] += m[a]; }
            }
        }
        prop_assume!(n > 0);
        if let Some(h) = hold_at {
            for _ in 0..h { rig.update(); }
            rig.shared.set_hold(true);
            for _ in 0..2_000_000 {
                rig.update();
                if rig.shared.state() == State::Held || rig.shared.state() == State::Idle { break; }
            }
            let frozen = rig.shared.positions();
            for _ in 0..500 { rig.update(); }
            prop_assert_eq!(rig.shared.positions(), frozen, "held still");
            rig.shared.set_hold(false);
        }
        rig.run_to_idle(u64::MAX);
        prop_assert_eq!(rig.net_steps(), want);
        prop_assert_eq!(rig.shared.positions().map(i64::from), want);
        prop_assert_eq!(rig.shared.moves_done(), n);
        for st in &rig.steps {
            let d = st.dir_changed_at.expect("direction written before the first step");
            prop_assert!(st.t - d >= timing.dir_setup_ticks as u64);
        }
        for a in 0..3 {
            let t = rig.times(a);
            prop_assert!(t.windows(2).all(|w| w[1] - w[0] >= timing.min_period_ticks as u64), "axis {}", a);
        }
    }

    /// Dual-edge mode (`$580`): every step is one toggle of its pin, so the toggles per axis are
    /// its step count (net: its signed steps), two toggles of a pin are at least the pulse
    /// (plus the store jitter the firmware allows for) apart, a direction change leads the next
    /// toggle by the setup, and the pins end at the parity of their step counts (the engine's
    /// shadow of their level never drifts).
    #[test]
    fn dual_edge_toggles_once_per_step_and_keeps_the_pulse_apart(moves in prop::collection::vec(
            prop::array::uniform3(-3000i64..3000), 1..6), setup in 1u32..2000, pulse in 15u32..800,
            cruise in 1_000u32..400_000) {
        use ddastep::motion::timing::{Timing, STORE_JITTER_TICKS};
        let timing = Timing::new(pulse, setup, 144).dual_edge(0);
        let cfg = RampConfig { v0: 1000, vmax: 400_000, accel: 20_000_000, shape: Shape::Trapezoid };
        let mut rig = Rig::<3>::new(cfg, timing);
        prop_assert!(rig.pins.dual);
        let (mut want, mut count) = ([0i64; 3], [0usize; 3]);
        for m in &moves {
            if Move::new(*m, cruise).is_ok() {
                rig.push(*m, cruise);
                for a in 0..3 {
                    want[a] += m[a];
                    count[a] += m[a].unsigned_abs() as usize;
                }
            }
        }
        rig.run_to_idle(u64::MAX);
        prop_assert_eq!(rig.net_steps(), want);
        for a in 0..3 {
            let t = rig.times(a);
            prop_assert_eq!(t.len(), count[a], "axis {}", a);
            prop_assert!(t.windows(2).all(|w| w[1] - w[0] >= (pulse + STORE_JITTER_TICKS) as u64), "axis {}", a);
            let bit = 1u16 << ddastep::board::STEP_PINS[a];
            prop_assert_eq!(rig.odr & bit != 0, count[a] % 2 == 1, "axis {} level", a);
        }
        for s in &rig.steps {
            let d = s.dir_changed_at.expect("direction written before the first toggle");
            prop_assert!(s.t - d >= setup as u64);
        }
    }

    #[test]
    fn extreme_inputs_never_panic(v0 in any::<u32>(), vmax in any::<u32>(), accel in any::<u32>(),
                                  s in any::<[i64; 3]>(), hz in any::<u32>(), curve in any::<bool>()) {
        let shape = if curve { Shape::SCurve } else { Shape::Trapezoid };
        let mut t: RampTable = RampTable::new();
        match t.build(RampConfig { v0, vmax, accel, shape }) {
            Ok(()) => {
                prop_assert!(!t.is_empty() && t.len() <= ddastep::motion::ramp::RAMP_LEN);
                prop_assert!(t.periods().windows(2).all(|w| w[1] <= w[0]));
            }
            Err(_) => prop_assert!(t.is_empty()),
        }
        let _ = Move::<3>::new(s, hz);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 40, ..ProptestConfig::default() })]

    /// The step interrupt's fast path (`Stepper::tick_quick`: plain steps with only the checks
    /// a plain step needs) gives exactly what whole ticks give, tick by tick: the same words,
    /// periods, positions and moves; with random chains on 1–7 axes, single- and dual-edge,
    /// a feed hold, feed overrides changing mid-move and the ramp half running late; in both
    /// ramp shapes.
    #[test]
    fn the_step_interrupts_fast_path_equals_whole_ticks(
            moves in prop::collection::vec(prop::array::uniform7(-1500i64..1500), 1..8),
            axes in 1usize..=7, cruise in 1_000u32..400_000, pulse_us in 0.2f32..5.0, dual: bool,
            hold in prop::option::of((0u64..6_000, 1u64..3_000)),
            ovr in prop::option::of((0u64..6_000, 10u8..=200)), lag in 0u32..4, scurve: bool) {
        let mut s = ddastep::grbl::settings::Settings::BENCH;
        // (`$41=1`: every ramp leg an S, holds and overrides included.)
        s.shape = if scurve { Shape::SCurve } else { Shape::Trapezoid };
        s.accel = [300_000.0; ddastep::MAX_AXES];
        s.pulse_us = pulse_us;
        s.dual_edge = dual;
        let mut rigs = [Rig::<7>::with_settings(&s), Rig::<7>::with_settings(&s)];
        let mut want = [0i64; 7];
        for m in &moves {
            let mut m = *m;
            m[axes..].fill(0);
            if Move::new(m, cruise).is_ok() {
                for r in &mut rigs { r.push(m, cruise); }
                for i in 0..7 { want[i] += m[i]; }
            }
        }
        let mut out = [Vec::new(), Vec::new()];
        for (k, r) in rigs.iter_mut().enumerate() {
            r.engine.set_quick(k == 0);
            r.engine.set_ramp_lag(lag);
            let mut done_at = None;
            for t in 0..3_000_000u64 {
                if !r.engine.filler_next() {
                    if let Some((on, len)) = hold {
                        r.shared.set_hold(t >= on && t < on + len);
                    }
                    if let Some((at, feed)) = ovr {
                        if t == at {
                            let mut o = r.shared.overrides();
                            o.feed = feed;
                            r.shared.set_overrides(o);
                        }
                    }
                    r.feeder.service();
                }
                let w = r.engine.word();
                out[k].push((w, r.engine.tick()));
                let idle = r.feeder.pending() == 0 && r.shared.state() == State::Idle
                    && hold.is_none_or(|(on, len)| t >= on + len);
                if idle && done_at.is_none() {
                    done_at = Some(t);
                }
                if done_at.is_some_and(|d| t > d + 1) {
                    break;
                }
            }
            prop_assert!(done_at.is_some(), "rig {} finished", k);
            prop_assert_eq!(r.shared.positions().map(i64::from), want);
        }
        prop_assert_eq!(rigs[0].shared.moves_done(), rigs[1].shared.moves_done());
        if let Some(i) = out[0].iter().zip(&out[1]).position(|(a, b)| a != b) {
            prop_assert!(false, "tick {} differs: fast path {:?}, whole ticks {:?}", i,
                &out[0][i..(i + 4).min(out[0].len())], &out[1][i..(i + 4).min(out[1].len())]);
        }
        prop_assert_eq!(out[0].len(), out[1].len());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// The output rebuilt at rest between moves with any `$2`, `$3` and `$580` (the firmware's
    /// in-place settings): every move's steps and directions exact as the new map says, the
    /// positions kept, and in dual-edge mode every step a toggle from the level the pin had
    /// (no edge lost or added at the change).
    #[test]
    fn rebuilding_at_rest_keeps_counts_and_positions(
        maps in prop::collection::vec((0u8..8, 0u8..8, any::<bool>()), 1..6),
        moves in prop::collection::vec(prop::array::uniform3(-300i64..300), 1..6),
    ) {
        let mut rig = Rig::<3>::trapezoid(1000, 60_000, 2_000_000);
        let mut want = [0i64; 3];
        for (i, mv) in moves.iter().enumerate() {
            let (step_inv, dir_inv, dual) = maps[i % maps.len()];
            let pins = ddastep::board::pin_map::<3>(step_inv, dir_inv);
            rig.rebuild(if dual { pins.dual_edge() } else { pins });
            let from = rig.steps.len();
            if mv.iter().all(|&s| s == 0) {
                continue;
            }
            rig.push(*mv, 20_000);
            rig.run_to_idle(1_000_000);
            let mut net = [0i64; 3];
            for s in &rig.steps[from..] {
                net[s.axis] += if s.positive { 1 } else { -1 };
            }
            prop_assert_eq!(net, *mv, "move {} with {:?}", i, maps[i % maps.len()]);
            for a in 0..3 {
                want[a] += mv[a];
            }
            prop_assert_eq!(rig.shared.positions().map(i64::from), want);
        }
    }
}
