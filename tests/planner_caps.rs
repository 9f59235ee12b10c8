//! Every move reaches its own cap, whatever the axes it does not move are set to (issue 25,
//! item 2): random `$100+i`, `$110+i` and `$120+i` per axis, a random straight move on a
//! random set of axes through the real planner, feeder and step engine (host models), in
//! interrupt and DMA timing. Its master cruises at the smaller of its moving axes' max rates
//! converted to its path (`min $110+i / |unitᵢ|` times its master's steps per mm of path) and
//! the engine's cap for its slave count (`Timing::max_rate_for`, what `$I` prints for one
//! axis), and every axis makes exactly its steps.

mod common;

use common::Rig;
use ddastep::grbl::settings::Settings;
use ddastep::motion::ramp::{Profile, RampTable, IDX_ONE};
use ddastep::motion::shared::State;
use ddastep::motion::timing::Timing;
use ddastep::planning::lookahead::walk_of;
use ddastep::planning::planner::Planner;
use proptest::prelude::*;

const N: usize = 7;
const TICKS: f64 = 72e6;
/// Master steps the move may have at most (the host engine runs one update per step).
const MAX_STEPS: f64 = 2_000_000.0;

#[derive(Clone, Debug)]
struct Case {
    spm: [f64; N],
    rate: [f64; N],
    accel: [f64; N],
    /// Moving axes' direction weights (0: the axis does not move).
    dir: [f64; N],
    dma: bool,
    pulse_us: f64,
}

/// Log-uniform in `lo..hi`.
fn log(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..hi.ln()).prop_map(f64::exp)
}

fn case() -> impl Strategy<Value = Case> {
    (
        prop::array::uniform7(log(1.0, 20_000.0)),
        prop::array::uniform7(log(600.0, 1_000_000.0)),
        prop::array::uniform7(log(1_000.0, 10_000_000.0)),
        prop::array::uniform7(prop_oneof![2 => Just(0.0), 1 => 0.05f64..1.0, 1 => -1.0f64..-0.05]),
        0usize..N,
        prop::bool::weighted(0.4),
        any::<bool>(),
        prop_oneof![Just(0.3), Just(1.0), Just(3.0)],
    )
        .prop_map(|(spm, rate, accel, mut dir, first, alone, dma, pulse_us)| {
            // At least one axis moves; a lone axis in 40 % of the cases.
            if alone {
                dir = core::array::from_fn(|i| if i == first { 1.0 } else { 0.0 });
            }
            if dir.iter().all(|d| *d == 0.0) {
                dir[first] = 1.0;
            }
            Case { spm, rate, accel, dir, dma, pulse_us }
        })
}

fn settings(c: &Case) -> Settings {
    let mut s = Settings { dma_burst: c.dma, axes: N as u8, ..Settings::DEFAULT };
    s.pulse_us = c.pulse_us as f32;
    for i in 0..N {
        s.steps_per_mm[i] = c.spm[i] as f32;
        s.max_rate[i] = c.rate[i] as f32;
        s.accel[i] = c.accel[i] as f32;
    }
    s
}

/// What the move should cruise at (master steps/s) and its master's acceleration
/// (steps/s²), from its rounded steps, in f64.
fn expected(s: &Settings, c: &Case, steps: &[i64; N]) -> (f64, f64) {
    let d: Vec<f64> = (0..N).map(|i| steps[i] as f64 / s.steps_per_mm[i] as f64).collect();
    let len = d.iter().map(|x| x * x).sum::<f64>().sqrt();
    let master = steps.iter().map(|x| x.unsigned_abs()).max().unwrap() as f64;
    let share = master / len;
    let moving: Vec<usize> = (0..N).filter(|&i| steps[i] != 0).collect();
    let path = moving.iter().map(|&i| s.max_rate[i] as f64 / 60.0 / (d[i].abs() / len)).fold(f64::INFINITY, f64::min);
    let accel = moving.iter().map(|&i| c.accel[i] / (d[i].abs() / len)).fold(f64::INFINITY, f64::min);
    let cap = s.timing().max_rate_for(moving.len() as u32 - 1) as f64;
    ((path * share).min(cap), accel * share)
}

/// Runs `target` (mm, from the origin) as a G0 through the rig; returns the move's steps.
fn run(rig: &mut Rig<N>, s: &Settings, target: &[f32; N]) -> [i64; N] {
    let lim = s.planner_limits::<N>(Settings::wanted_vmax(s, N));
    let mut p = Planner::<N>::new();
    let planned = p.line(target, None, &lim).unwrap().expect("a move");
    rig.feeder.push(planned.mv).expect("room");
    let mut updates = 0u64;
    loop {
        rig.update();
        updates += 1;
        if rig.feeder.pending() == 0 && rig.shared.state() == State::Idle {
            rig.update();
            break;
        }
        assert!(updates < 20_000_000, "move did not finish");
    }
    planned.mv.steps().map(i64::from)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn every_move_reaches_its_own_cap(c in case()) {
        let s = settings(&c);
        // The move's size: a unit direction in mm, scaled so the master reaches cruise with
        // room: twice the walk up the whole table at the move's own walk rate (an upper bound
        // of its ramp, whatever the table's resolution), at least 4000 steps.
        let norm = c.dir.iter().map(|x| x * x).sum::<f64>().sqrt();
        let unit: [f64; N] = core::array::from_fn(|i| c.dir[i] / norm);
        let share = (0..N).map(|i| unit[i].abs() * c.spm[i]).fold(0.0, f64::max);
        let approx: [i64; N] = core::array::from_fn(|i| (unit[i] * c.spm[i] * 1e3).round() as i64);
        let (f, a) = expected(&s, &c, &approx);
        let mut p: Profile = Profile { ramp: RampTable::new(), timing: Timing::UNSET, per_mm: 0.0, scurve: ddastep::motion::ramp::SCurve::OFF };
        s.build_profile(N, &mut p);
        let (_, walk_q) = walk_of(share as f32, (a / share) as f32, p.per_mm, p.ramp.config().accel as f32);
        let ramp_s = (p.ramp.len() as f64 + 2.0) / (walk_q as f64 / IDX_ONE as f64) / 1000.0;
        let master = 2.0 * f * ramp_s * 1.1 + 4_000.0;
        // (A move whose walk up the table is too long for the step budget is left out.)
        prop_assume!(master <= MAX_STEPS);
        let len_mm = master / share;
        let target: [f32; N] = core::array::from_fn(|i| (unit[i] * len_mm) as f32);
        let mut rig = Rig::<N>::with_settings(&s);
        let steps = run(&mut rig, &s, &target);
        // Exact counts: every axis at round(target × steps/mm), in f32 as the planner takes it.
        let want: [i64; N] = core::array::from_fn(|i| (target[i] * s.steps_per_mm[i]).round() as i64);
        prop_assert_eq!(steps, want);
        prop_assert_eq!(rig.net_steps(), want);
        prop_assert_eq!(rig.shared.positions().map(i64::from), want);
        // The cruise: the master's fastest mean rate over 64 steps (the period's sixteenths
        // dither within 16).
        let (want_hz, _) = expected(&s, &c, &steps);
        let m = (0..N).max_by_key(|&i| steps[i].unsigned_abs()).unwrap();
        let t = rig.times(m);
        let fastest = t.windows(65).map(|w| w[64] - w[0]).min().unwrap();
        let hz = 64.0 * TICKS / fastest as f64;
        prop_assert!((hz - want_hz).abs() <= want_hz * 1e-3, "cruise {hz:.1} Hz, want {want_hz:.1} (axis {m}, {} steps)", t.len());
    }
}
