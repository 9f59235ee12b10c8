//! Host benchmark of `Engine::tick` for 1, 3 and 7 axes at cruise.
//!
//! Host nanoseconds are only a regression signal; the MCU figure (modeled cycles) comes from
//! the virtual bench (`cargo sim -- --sweep`, bench/RESULTS.md).

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use ddastep::board::pin_map;
use ddastep::motion::engine::Engine;
use ddastep::motion::moves::Move;
use ddastep::motion::shared::Shared;
use ddastep::planning::feeder::Feeder;
use ddastep::motion::ramp::{RampConfig, RampSlot, Shape};
use ddastep::motion::timing::Timing;
use ddastep::motion::ring::MoveRing;

/// Ticks through `n` long moves on `N` axes, measuring each tick.
fn bench_axes<const N: usize>(c: &mut Criterion, name: &str) {
    let shared: &'static Shared<N> = Box::leak(Box::new(Shared::new()));
    let slot: &'static RampSlot = Box::leak(Box::new(RampSlot::new()));
    {
        let mut p = slot.try_write().expect("parked");
        let cfg = RampConfig { v0: 1000, vmax: 500_000, accel: 1_000_000, shape: Shape::Trapezoid };
        p.ramp.build(cfg).expect("table");
        p.timing = Timing::new(36, 72, 144);
    }
    let q: &'static mut MoveRing<N> = Box::leak(Box::new(MoveRing::new()));
    let (prod, cons) = q.split();
    let mut feeder = Feeder::new(prod, Box::leak(Box::new(ddastep::planning::lookahead::Buffer::new())), shared, slot, pin_map::<N>(0, 0));
    let mut engine = Engine::new(shared, cons, slot, pin_map::<N>(0, 0));
    let steps: [i64; N] = core::array::from_fn(|i| 1_000_000_000 / (i as i64 + 2) * 2 - i as i64);
    feeder.push(Move::new(steps, 400_000).expect("move")).expect("room");
    // Get past the ramp so the measurement is the cruise path.
    for _ in 0..100_000 {
        engine.tick();
    }
    c.bench_function(name, |b| {
        b.iter(|| {
            black_box(engine.word());
            black_box(engine.tick())
        })
    });
}

fn ticks(c: &mut Criterion) {
    bench_axes::<1>(c, "tick 1 axis");
    bench_axes::<3>(c, "tick 3 axes");
    bench_axes::<7>(c, "tick 7 axes");
}

criterion_group!(benches, ticks);
criterion_main!(benches);
