//! Driving the ddastep engine from your own code, on the host: seed 001's per-motor
//! `step_move(id, steps, freq)` and the paper's 5:3:2 move, one call each.
//!
//! `cargo run --example step_move --target host-tuple` plans 5000:3000:2000 steps with the
//! fastest motor at 50 kHz, runs the real engine tick by tick through the library's model of
//! TIM2 (`ddastep::motion::tim2_model`), and prints the first step edges (the BSRR words the
//! step interrupt would store) and the final counts; then one motor alone back to 0.
//!
//! On a board, the same pieces run in two interrupts and the idle loop (see the crate docs):
//! the TIM2 update interrupt stores `word()` into GPIOB's BSRR and preloads the ARR that
//! `tick()` returns, the compare event stores `step_off()`, and the idle loop calls
//! `Feeder::service`.

use ddastep::board::{pin_map, PinMap};
use ddastep::motion::engine::Engine;
use ddastep::motion::moves::Move;
use ddastep::motion::ramp::{RampConfig, RampSlot, Shape};
use ddastep::motion::ring::MoveRing;
use ddastep::motion::shared::{Shared, State};
use ddastep::motion::tim2_model::{apply_bsrr, Edge, TimerSim};
use ddastep::motion::timing::Timing;
use ddastep::planning::feeder::Feeder;
use ddastep::planning::lookahead::Buffer;
use ddastep::{AXIS_NAMES, TIMER_HZ};

/// Motors in this example (X, Y, Z; the firmware runs up to 7).
const N: usize = 3;

/// The engine with everything it needs, as the firmware sets it up, and the timer model.
struct Motors {
    shared: &'static Shared<N>,
    feeder: Feeder<'static, N>,
    engine: Engine<'static, N>,
    timer: TimerSim,
    pins: PinMap<N>,
}

/// What one call did: the non-zero BSRR words in order (time in timer ticks, word), the step
/// edges (time, axis, forward) and the net steps per motor.
struct Run {
    words: Vec<(u64, u32)>,
    edges: Vec<(u64, usize, bool)>,
    counts: [i64; N],
}

impl Motors {
    /// Ramps from 1 kHz to at most 60 kHz at 2 MHz/s (trapezoid); 0.5 µs pulses, 1 µs
    /// direction setup. The pieces live as long as the program (a firmware keeps them in
    /// statics).
    fn new() -> Self {
        let shared: &'static Shared<N> = Box::leak(Box::new(Shared::new()));
        let slot: &'static RampSlot = Box::leak(Box::new(RampSlot::new()));
        {
            let mut profile = slot.try_write().expect("a new slot is free");
            profile.ramp.build(RampConfig { v0: 1000, vmax: 60_000, accel: 2_000_000, shape: Shape::Trapezoid }).expect("ramp table");
            profile.timing = Timing::new(36, 72, 144);
        }
        let ring: &'static mut MoveRing<N> = Box::leak(Box::new(MoveRing::new()));
        let (producer, consumer) = ring.split();
        let pins = pin_map::<N>(0, 0);
        let lookahead: &'static mut Buffer<N> = Box::leak(Box::new(Buffer::new()));
        Motors {
            shared,
            feeder: Feeder::new(producer, lookahead, shared, slot, pins),
            engine: Engine::new(shared, consumer, slot, pins),
            timer: TimerSim::new(),
            pins,
        }
    }

    /// Seed 001's call: motor `id` moves `steps` (negative: backwards) at `freq` steps/s.
    fn step_move(&mut self, id: usize, steps: i64, freq: u32) -> Run {
        let mut all = [0; N];
        all[id] = steps;
        self.move_steps(all, freq)
    }

    /// All motors at once, in one straight line: the one with the most steps at `freq`, the
    /// others in exact ratio (Bresenham slaves of the same timer).
    fn move_steps(&mut self, steps: [i64; N], freq: u32) -> Run {
        let mv = Move::new(steps, freq).expect("a valid move");
        self.feeder.push(mv).expect("room in the queue");
        let mut run = Run { words: Vec::new(), edges: Vec::new(), counts: [0; N] };
        let mut odr = 0u16;
        let mut last = false;
        loop {
            // the idle loop's part: hand planned moves to the engine
            self.feeder.service();
            // one TIM2 update event: the word stored at it, then the tick (next word, ARR)
            let Edge { t, word } = self.timer.update(&mut self.engine);
            odr = apply_bsrr(odr, word);
            if word != 0 {
                run.words.push((t, word));
            }
            for axis in 0..N {
                if word & self.pins.step_on[axis] != 0 {
                    let forward = odr & (1 << ddastep::board::DIR_PINS[axis]) == 0;
                    run.edges.push((t, axis, forward));
                    run.counts[axis] += if forward { 1 } else { -1 };
                }
            }
            // the compare event ends the pulses
            odr = apply_bsrr(odr, self.engine.step_off());
            if last {
                return run;
            }
            // idle: the word the last tick computed is stored at one more event
            last = self.feeder.pending() == 0 && self.shared.state() == State::Idle;
        }
    }
}

fn show(name: &str, run: &Run, first: usize) {
    println!("{name}: the first {first} BSRR words with steps or direction changes");
    for &(t, word) in run.words.iter().take(first) {
        let mut what = String::new();
        for (k, e) in run.edges.iter().filter(|e| e.0 == t).enumerate() {
            what.push_str(if k == 0 { "step" } else { "," });
            what.push_str(&format!(" {}{}", AXIS_NAMES[e.1], if e.2 { '+' } else { '-' }));
        }
        if what.is_empty() {
            what.push_str("direction pins only");
        }
        println!("  {:>12.3} µs  BSRR {word:#010x}  {what}", t as f64 * 1e6 / TIMER_HZ as f64);
    }
    let counts: Vec<String> = (0..N).map(|a| format!("{} {}", AXIS_NAMES[a], run.counts[a])).collect();
    let end = run.edges.last().map_or(0.0, |e| e.0 as f64 / TIMER_HZ as f64);
    println!("{name}: counts {} (last step at {end:.4} s)", counts.join(" "));
}

fn main() {
    let mut motors = Motors::new();
    let paper = motors.move_steps([5000, 3000, 2000], 50_000);
    show("5:3:2", &paper, 8);
    let back = motors.step_move(0, -5000, 50_000);
    show("step_move(0, -5000, 50000)", &back, 3);
    println!("positions {:?}", motors.shared.positions());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_532_move_ends_on_exact_counts_in_the_papers_pattern() {
        let mut motors = Motors::new();
        let run = motors.move_steps([5000, 3000, 2000], 50_000);
        assert_eq!(run.counts, [5000, 3000, 2000]);
        assert_eq!(motors.shared.positions(), [5000, 3000, 2000]);
        // Every master step carries Y or Z: Y at master steps 1, 3, 5 of each 5, Z at 2, 4.
        let at = |axis: usize| run.edges.iter().filter(|e| e.1 == axis).map(|e| e.0).collect::<Vec<_>>();
        let (x, y, z) = (at(0), at(1), at(2));
        assert_eq!((x[0], x[1], x[2]), (y[0], z[0], y[1]));
        let back = motors.step_move(0, -5000, 50_000);
        assert_eq!(back.counts, [-5000, 0, 0]);
        assert_eq!(motors.shared.positions(), [0, 3000, 2000]);
    }
}
