//! Property: a generated pulse train written as a bench VCD and read back through the checker
//! yields the generated counts, net steps, minimum widths, dir setup and hold, ratio and slave
//! deviation (computed here by brute force).

use ddastep_la::capture::Capture;
use ddastep_la::synth::{self, AxisTrace, Pulse};
use ddastep_la::{reduce, Analyzer, AxisChannels, Config, Report};
use proptest::prelude::*;

/// One generated axis: pulses as (low gap before, width), dir start and toggle offsets.
#[derive(Clone, Debug)]
struct AxisPlan {
    pulses: Vec<(u64, u64)>,
    dir_start: bool,
    toggles: Vec<u64>,
}

// a random axis: up to 40 pulses, times in multiples of `unit` ns; a coarse unit makes edges
// of different axes, and dir toggles and steps, share timestamps often
fn axis_plan(unit: u64) -> impl Strategy<Value = AxisPlan> {
    (
        prop::collection::vec((1u64..40, 1u64..20), 0..40),
        any::<bool>(),
        prop::collection::btree_set(1u64..1_000, 0..6),
    )
        .prop_map(move |(pulses, dir_start, toggles)| AxisPlan {
            pulses: pulses
                .into_iter()
                .map(|(gap, width)| (gap * unit, width * unit))
                .collect(),
            dir_start,
            toggles: toggles.into_iter().map(|t| t * unit).collect(),
        })
}

// one to four axes sharing a time unit of 1 ns or 50 ns
fn plans() -> impl Strategy<Value = Vec<AxisPlan>> {
    prop_oneof![Just(1u64), Just(50u64)]
        .prop_flat_map(|unit| prop::collection::vec(axis_plan(unit), 1..5))
}

// the trace of a plan: pulses back to back after their gaps
fn trace(name: &str, plan: &AxisPlan) -> AxisTrace {
    let mut t = 0;
    let pulses = plan
        .pulses
        .iter()
        .map(|&(gap, width)| {
            let rise_ns = t + gap;
            t = rise_ns + width;
            Pulse {
                rise_ns,
                width_ns: width,
            }
        })
        .collect();
    AxisTrace {
        name: name.to_string(),
        dir_start: plan.dir_start,
        dir_toggles_ns: plan.toggles.clone(),
        pulses,
    }
}

// dir level at `t`, toggles at `t` included (dir applies before steps)
fn dir_at(axis: &AxisTrace, t: u64) -> bool {
    axis.dir_start ^ (axis.dir_toggles_ns.iter().filter(|&&d| d <= t).count() % 2 == 1)
}

/// What the checker must find for one axis.
#[derive(Debug, PartialEq)]
struct Expected {
    steps: u64,
    net: i64,
    min_high: Option<f64>,
    min_low: Option<f64>,
    setup: Option<f64>,
    hold: Option<f64>,
}

// the answers for one axis, straight from the trace
fn expected(axis: &AxisTrace) -> Expected {
    let rises: Vec<u64> = axis.pulses.iter().map(|p| p.rise_ns).collect();
    let min = |v: Vec<u64>| v.into_iter().min().map(|x| x as f64);
    let lows = axis
        .pulses
        .windows(2)
        .map(|w| w[1].rise_ns - (w[0].rise_ns + w[0].width_ns))
        .collect();
    let setups = rises
        .iter()
        .enumerate()
        .filter_map(|(i, &r)| {
            let after = if i == 0 { None } else { Some(rises[i - 1]) };
            let last = axis
                .dir_toggles_ns
                .iter()
                .filter(|&&d| d <= r && after.is_none_or(|a| d > a))
                .max()?;
            Some(r - last)
        })
        .collect();
    let holds = axis
        .dir_toggles_ns
        .iter()
        .filter_map(|&d| rises.iter().filter(|&&r| r < d).max().map(|r| d - r))
        .collect();
    Expected {
        steps: rises.len() as u64,
        net: rises
            .iter()
            .map(|&r| if dir_at(axis, r) { 1 } else { -1 })
            .sum(),
        min_high: min(axis.pulses.iter().map(|p| p.width_ns).collect()),
        min_low: min(lows),
        setup: min(setups),
        hold: min(holds),
    }
}

// max |s - k·c/M| at each master rise, after all edges of that timestamp
fn brute_deviation(axes: &[AxisTrace], master: usize, slave: usize) -> f64 {
    let (m, c) = (
        axes[master].pulses.len() as f64,
        axes[slave].pulses.len() as f64,
    );
    axes[master]
        .pulses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let s = axes[slave]
                .pulses
                .iter()
                .filter(|q| q.rise_ns <= p.rise_ns)
                .count() as f64;
            (s - (k + 1) as f64 * c / m).abs()
        })
        .fold(0.0, f64::max)
}

// write, read back and check
fn run(axes: &[AxisTrace]) -> Report {
    let mut vcd = Vec::new();
    synth::write_vcd(axes, 400_000, &mut vcd).unwrap();
    let mut capture =
        Capture::from_reader(Box::new(std::io::Cursor::new(vcd)), None, None).unwrap();
    let channels = capture.info().channels.clone();
    let find = |n: String| channels.iter().position(|c| *c == n);
    let config = Config::new(
        axes.iter()
            .map(|a| {
                AxisChannels::new(
                    &a.name,
                    find(format!("{}_STEP", a.name)).unwrap(),
                    find(format!("{}_DIR", a.name)),
                )
            })
            .collect(),
    );
    let mut analyzer = Analyzer::new(config).unwrap();
    capture.stream(&mut analyzer).unwrap();
    analyzer.finish()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn generated_trains_read_back(plans in plans()) {
        let names = ["X", "Y", "Z", "U"];
        let axes: Vec<AxisTrace> = plans.iter().zip(names).map(|(p, n)| trace(n, p)).collect();
        let report = run(&axes);
        for (axis, got) in axes.iter().zip(&report.axes) {
            let want = expected(axis);
            let found = Expected {
                steps: got.steps,
                net: got.net_steps,
                min_high: got.min_high_ns,
                min_low: got.min_low_ns,
                setup: got.min_dir_setup_ns,
                hold: got.min_dir_hold_ns,
            };
            prop_assert_eq!(found, want, "axis {}", axis.name);
        }
        let counts: Vec<u64> = axes.iter().map(|a| a.pulses.len() as u64).collect();
        prop_assert_eq!(&report.ratio, &reduce(&counts));
        let master = (0..counts.len()).filter(|&i| counts[i] > 0).max_by(|&a, &b| counts[a].cmp(&counts[b]).then(b.cmp(&a)));
        prop_assert_eq!(report.master, master);
        if let Some(m) = master {
            for s in (0..axes.len()).filter(|&s| s != m) {
                let got = report.axes[s].max_deviation_steps.unwrap();
                prop_assert!((got - brute_deviation(&axes, m, s)).abs() < 1e-9, "slave {}: {}", s, got);
            }
        }
        prop_assert_eq!(report.glitches, 0);
    }
}
