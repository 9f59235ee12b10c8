//! Look-ahead properties on the host: random chains of moves through the real planner,
//! feeder (look-ahead + prepared moves) and step engine, checked against limits computed here
//! independently (Grbl's junction-deviation formula).

mod common;

use common::Rig;
use ddastep::planning::planner::{Limits, Planner};
use ddastep::motion::shared::State;
use ddastep::grbl::settings::Settings;
use proptest::prelude::*;

const N: usize = 7;
const TICKS: f64 = 72e6;

#[derive(Clone, Debug)]
struct Chain {
    axes: usize,
    spm: [f64; N],
    rate: [f64; N],
    accel: [f64; N],
    /// Targets (mm, absolute) and feeds (mm/min; None for G0).
    moves: Vec<([f64; N], Option<f64>)>,
}

fn chain() -> impl Strategy<Value = Chain> {
    (1usize..=N, 2usize..=50).prop_flat_map(|(axes, n)| {
        (
            prop::array::uniform7(20.0f64..200.0),
            prop::array::uniform7(1_200.0f64..12_000.0),
            prop::array::uniform7(100.0f64..3_000.0),
            // A heading that turns by a random angle each move, lengths 0.1–4 mm.
            prop::collection::vec((prop::array::uniform7(-1.0f64..1.0), 0.1f64..4.0, prop::option::weighted(0.9, 300.0f64..6_000.0)), n),
            0.0f64..1.0,
        )
            .prop_map(move |(spm, rate, accel, steps, smooth)| {
                let mut pos = [0.0f64; N];
                let mut dir = [0.0f64; N];
                let mut moves = Vec::new();
                for (d, len, feed) in steps {
                    // Blend the old heading with a random one: small turns mostly.
                    let mut v = [0.0f64; N];
                    for i in 0..axes {
                        v[i] = dir[i] * smooth * 3.0 + d[i];
                    }
                    let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-9);
                    for i in 0..axes {
                        dir[i] = v[i] / norm;
                        pos[i] = ((pos[i] + dir[i] * len) * 1000.0).round() / 1000.0;
                    }
                    moves.push((pos, feed));
                }
                Chain { axes, spm, rate, accel, moves }
            })
    })
}

fn settings(c: &Chain) -> Settings {
    let mut s = Settings::DEFAULT;
    for i in 0..N {
        s.steps_per_mm[i] = c.spm[i] as f32;
        s.max_rate[i] = c.rate[i] as f32;
        s.accel[i] = c.accel[i] as f32;
    }
    s
}

/// Grbl's junction speed limit (mm/s), from the two moves' unit vectors.
fn grbl_junction(a: &[f64; N], b: &[f64; N], accel: &[f64; N], dev: f64) -> f64 {
    let cos: f64 = -(0..N).map(|i| a[i] * b[i]).sum::<f64>();
    if cos > 0.999999 {
        return 0.0;
    }
    if cos < -0.999999 {
        return f64::INFINITY;
    }
    let ju: Vec<f64> = (0..N).map(|i| b[i] - a[i]).collect();
    let n = ju.iter().map(|x| x * x).sum::<f64>().sqrt();
    let acc = (0..N).filter(|&i| ju[i].abs() / n > 1e-9).map(|i| accel[i] / (ju[i].abs() / n)).fold(f64::INFINITY, f64::min);
    let s = (0.5 * (1.0 - cos)).sqrt();
    (acc * dev * s / (1.0 - s)).sqrt()
}

/// One planned move as the test sees it: steps, unit vector, share and nominal speed.
struct Seen {
    steps: [i64; N],
    unit: [f64; N],
    share: f64,
    nominal: f64,
}

fn plan(c: &Chain, s: &Settings, lim: &Limits<N>) -> Vec<Seen> {
    let mut p = Planner::<N>::new();
    let mut out = Vec::new();
    for (target, feed) in &c.moves {
        let Some(pl) = p.line(&target.map(|v| v as f32), feed.map(|f| f as f32), lim).unwrap() else { continue };
        let steps = pl.mv.steps().map(i64::from);
        let d: Vec<f64> = (0..N).map(|i| steps[i] as f64 / s.steps_per_mm[i] as f64).collect();
        let len = d.iter().map(|x| x * x).sum::<f64>().sqrt();
        let master = steps.iter().map(|x| x.unsigned_abs()).max().unwrap() as f64;
        // The nominal path speed: the cruise rate over the master's share of the path.
        let nominal = ddastep::motion::ramp::hz_of_period(pl.mv.cruise()) as f64 / (master / len);
        out.push(Seen { steps, unit: core::array::from_fn(|i| d[i] / len), share: master / len, nominal });
        let _ = &pl;
    }
    out
}

/// Runs the planned moves through the rig, pushing as the feeder takes them; calls `each`
/// after every update.
fn run(rig: &mut Rig<N>, c: &Chain, lim: &Limits<N>, mut each: impl FnMut(&mut Rig<N>) -> bool) {
    let mut p = Planner::<N>::new();
    let mut queue: std::collections::VecDeque<_> =
        c.moves.iter().filter_map(|(t, f)| p.line(&t.map(|v| v as f32), f.map(|f| f as f32), lim).unwrap()).map(|pl| pl.mv).collect();
    let mut updates = 0u64;
    loop {
        while let Some(mv) = queue.front() {
            if rig.feeder.push(*mv).is_err() {
                break;
            }
            queue.pop_front();
        }
        rig.update();
        updates += 1;
        if !each(rig) {
            return;
        }
        if queue.is_empty() && rig.feeder.pending() == 0 && rig.shared.state() == State::Idle {
            rig.update();
            return;
        }
        assert!(updates < 50_000_000, "chain did not finish");
    }
}

/// Straight through a junction while accelerating: the next move starts at the speed the walk
/// has reached (the ramp half primes the successor at the walk's index as it moves), so the
/// master's periods keep shrinking up to the peak; a successor primed at an earlier index
/// would start slower. And the successor is handed over before the engine must start the stop
/// it plans at the end of what it has: here the second move's entry is about the speed it
/// could stop from in its own length, so a successor handed over only within the last 8 ms at
/// cruise left the whole move at its entry speed (`$120=120`, and 100 once entry 0 was led).
#[test]
fn accelerating_through_a_junction_keeps_the_speed() {
    for accel in [60.0, 100.0, 120.0, 250.0, 1000.0] {
        let c = Chain { axes: 1, spm: [100.0; N], rate: [12_000.0; N], accel: [accel; N], moves: vec![([2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], Some(12_000.0)), ([4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], Some(12_000.0)), ([6.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], Some(12_000.0))] };
        let s = settings(&c);
        let mut rig = Rig::<N>::with_settings(&s);
        let lim = s.planner_limits::<N>(Settings::wanted_vmax(&s, N));
        run(&mut rig, &c, &lim, |_| true);
        assert_eq!(rig.net_steps()[0], 600);
        let t = rig.times(0);
        let p: Vec<u64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let peak = (0..p.len()).min_by_key(|&i| p[i]).unwrap();
        // The first junction (step 200) comes before the peak: the chain accelerates through it.
        assert!(peak > 220, "$120={accel}: peak at step {peak}: {:?}", &p[180..260]);
        for i in 1..peak {
            // (One tick: the period's sixteenths.)
            assert!(p[i] <= p[i - 1] + 1, "$120={accel}: step {}: period {} after {}", i + 1, p[i], p[i - 1]);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn chains_are_exact_and_respect_junction_and_axis_limits(c in chain()) {
        let s = settings(&c);
        let mut rig = Rig::<N>::with_settings(&s);
        let ramped = Settings::wanted_vmax(&s, N);
        let lim = s.planner_limits::<N>(ramped);
        let seen = plan(&c, &s, &lim);
        prop_assume!(!seen.is_empty());
        let accel: [f64; N] = core::array::from_fn(|i| c.accel[i]);
        let v0_path = s.ramp_start_hz as f64 / s.per_mm(N) as f64;
        // Walk step of the table in path speed (one entry: 2 × max accel per ms).
        let entry = 2.0 * accel.iter().cloned().fold(0.0, f64::max) / 1000.0;
        let mut done = 0usize;
        let mut want = [0i64; N];
        let mut rate_before = 0u32;
        let mut failures = Vec::new();
        run(&mut rig, &c, &lim, |rig| {
            let k = rig.shared.moves_done() as usize;
            if k > done {
                // Exact steps at every move boundary.
                for i in 0..N {
                    want[i] += seen[done].steps[i];
                }
                let pos = rig.shared.positions().map(i64::from);
                if pos != want {
                    failures.push(format!("after move {done}: {pos:?} vs {want:?}"));
                }
                // The junction speed against Grbl's limit, computed here.
                if k < seen.len() {
                    let (a, b) = (&seen[done], &seen[done + 1]);
                    let v = rate_before as f64 / a.share;
                    let limit = grbl_junction(&a.unit, &b.unit, &accel, 0.01).min(a.nominal).min(b.nominal);
                    // The table starts at $40 (a start speed, as before look-ahead); a
                    // deceleration may end up to one walk above its target; and a period
                    // longer than a millisecond holds its speed while the walk goes on (the
                    // speed changes only at steps): up to two periods' worth of walk.
                    let period_ms = 1000.0 / (rate_before.max(1) as f64);
                    let tol = 2.0 * entry * (1.0 + period_ms) + 0.5;
                    if v > limit.max(v0_path + entry) * 1.01 + tol {
                        failures.push(format!("junction {done}: {v:.2} mm/s over {limit:.2} (v0 {v0_path:.2}, entry {entry:.2}, rate {rate_before}, share {:.1})", a.share));
                    }
                }
                done = k;
            }
            rate_before = rig.shared.rate_hz();
            true
        });
        if !failures.is_empty() {
            std::fs::write("/tmp/chain_fail.txt", format!("{c:?}")).ok();
        }
        prop_assert!(failures.is_empty(), "{:?}", &failures[..failures.len().min(5)]);
        prop_assert_eq!(done, seen.len());
        prop_assert_eq!(rig.net_steps(), want);
        // No axis above its max rate in any 1 ms window.
        for a in 0..c.axes {
            let t = rig.times(a);
            let cap = c.rate[a] / 60.0 * c.spm[a] / 1000.0;
            let mut j = 0;
            for i in 0..t.len() {
                while t[i] - t[j] >= 72_000 {
                    j += 1;
                }
                prop_assert!(((i - j + 1) as f64) <= cap * 1.02 + 2.0, "axis {a}: {} steps in 1 ms, cap {cap:.1}", i - j + 1);
            }
        }
    }

    #[test]
    fn a_hold_across_move_boundaries_ends_exactly(c in chain(), at in 0.0f64..1.0) {
        let s = settings(&c);
        let mut rig = Rig::<N>::with_settings(&s);
        let lim = s.planner_limits::<N>(Settings::wanted_vmax(&s, N));
        let seen = plan(&c, &s, &lim);
        prop_assume!(seen.len() >= 2);
        let total: i64 = seen.iter().map(|m| m.steps.iter().map(|x| x.abs()).max().unwrap()).sum();
        let hold_after = ((total as f64 * at) as usize).max(1);
        let mut held_at = None;
        let mut resumed = false;
        let mut t_held = 0u64;
        run(&mut rig, &c, &lim, |rig| {
            let made = rig.steps.len();
            if held_at.is_none() && !rig.shared.hold_requested() && !resumed && made >= hold_after {
                rig.shared.set_hold(true);
            }
            if rig.shared.hold_requested() && rig.shared.state() == State::Held && t_held == 0 {
                t_held = rig.timer.now();
            }
            // The word computed before the hold came to rest is still written at the next edge.
            if t_held != 0 && held_at.is_none() && rig.timer.now() > t_held + (0.002 * TICKS) as u64 {
                held_at = Some(made);
            }
            if let Some(h) = held_at {
                if !resumed && rig.timer.now() > t_held + (0.02 * TICKS) as u64 {
                    assert_eq!(rig.steps.len(), h, "steps while held");
                    rig.shared.set_hold(false);
                    resumed = true;
                }
            }
            true
        });
        let want: [i64; N] = core::array::from_fn(|i| seen.iter().map(|m| m.steps[i]).sum());
        prop_assert_eq!(rig.net_steps(), want);
        prop_assert_eq!(rig.shared.positions().map(i64::from), want);
    }
}
