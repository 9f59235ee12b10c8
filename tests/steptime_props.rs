//! Properties of the step interrupt's self-measurement (`ddastep::steptime`): whatever the
//! interleaving of step-interrupt records, 1 ms ticks and `$I` reports, every recorded entry is
//! reported exactly once (after a tick has seen it), busy cycles add up, and each report's
//! min ≤ mean ≤ max lie within what was recorded.

use ddastep::steptime::StepTime;
use proptest::prelude::*;

#[derive(Clone, Debug)]
enum Op {
    Record(u32),
    Tick,
    Take,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![6 => (1u32..5000).prop_map(Op::Record), 2 => Just(Op::Tick), 1 => Just(Op::Take)]
}

proptest! {
    #[test]
    fn every_entry_is_reported_once(ops in prop::collection::vec(op(), 1..300)) {
        let t = StepTime::new();
        let (mut recorded, mut busy) = (0u64, 0f64);
        let (mut reported, mut reported_busy) = (0u64, 0f64);
        let (mut lo, mut hi) = (u32::MAX, 0u32);
        for o in ops.iter().chain([Op::Tick, Op::Take].iter()) {
            match *o {
                Op::Record(c) => {
                    t.record(c);
                    recorded += 1;
                    busy += c as f64;
                    lo = lo.min(c);
                    hi = hi.max(c);
                }
                Op::Tick => t.tick_ms(),
                Op::Take => {
                    if let Some(r) = t.take() {
                        prop_assert!(r.entries > 0);
                        prop_assert!(r.min as f32 <= r.mean * 1.0001 && r.mean <= r.max as f32 * 1.0001, "{r:?}");
                        prop_assert!(r.min >= lo && r.max <= hi, "{r:?}");
                        prop_assert!(r.peak_load >= 0.0 && r.load >= 0.0);
                        reported += r.entries;
                        reported_busy += r.mean as f64 * r.entries as f64;
                    }
                }
            }
        }
        prop_assert_eq!(reported, recorded);
        prop_assert!((reported_busy - busy).abs() <= busy * 1e-5 + 1.0, "{} vs {}", reported_busy, busy);
    }
}
