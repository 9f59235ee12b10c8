//! A host rig around the real engine: queue, shared state, ramp slot, timer model, pin decoding.
#![allow(dead_code)]

use ddastep::board::{pin_map, PinMap};
use ddastep::motion::engine::Engine;
use ddastep::motion::moves::Move;
use ddastep::motion::shared::{Shared, State};
use ddastep::planning::feeder::Feeder;
use ddastep::motion::ramp::{RampConfig, RampSlot, Shape};
use ddastep::motion::tim2_model::{apply_bsrr, Edge, TimerSim};
use ddastep::motion::timing::Timing;
use ddastep::motion::ring::MoveRing;

/// One step edge of one axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepEdge {
    pub t: u64,
    pub axis: usize,
    pub positive: bool,
    /// Time of the last direction-pin change of this axis before this step.
    pub dir_changed_at: Option<u64>,
}

pub struct Rig<const N: usize> {
    pub shared: &'static Shared<N>,
    pub slot: &'static RampSlot,
    pub feeder: Feeder<'static, N>,
    pub engine: Engine<'static, N>,
    pub timer: TimerSim,
    pub pins: PinMap<N>,
    pub odr: u16,
    pub steps: Vec<StepEdge>,
    pub updates: u64,
    dir_change: [Option<u64>; N],
    pub last_edge: Option<Edge>,
}

impl<const N: usize> Rig<N> {
    pub fn new(cfg: RampConfig, timing: Timing) -> Self {
        Self::with_profile(|p| {
            p.ramp.build(cfg).expect("ramp builds");
            p.timing = timing;
            // `$41=1`: every leg through the curve (`$582`'s default).
            if cfg.shape == Shape::SCurve {
                p.scurve = ddastep::motion::ramp::SCurve::build(ddastep::motion::ramp::FLEX_DEFAULT);
            }
        })
    }

    /// A rig whose profile (table in path units, timing) comes from Grbl settings.
    pub fn with_settings(s: &ddastep::grbl::settings::Settings) -> Self {
        Self::with_profile(|p| {
            s.build_profile(N, p);
        })
    }

    fn with_profile(build: impl FnOnce(&mut ddastep::motion::ramp::Profile)) -> Self {
        let shared: &'static Shared<N> = Box::leak(Box::new(Shared::new()));
        let slot: &'static RampSlot = Box::leak(Box::new(RampSlot::new()));
        let dual = {
            let mut p = slot.try_write().expect("fresh slot is parked");
            build(&mut p);
            p.timing.dual
        };
        let q: &'static mut MoveRing<N> = Box::leak(Box::new(MoveRing::new()));
        let (prod, cons) = q.split();
        // Dual-edge timing (`$580`) runs the engine on the dual-edge pin map, as the firmware.
        let pins = if dual { pin_map::<N>(0, 0).dual_edge() } else { pin_map::<N>(0, 0) };
        let engine = Engine::new(shared, cons, slot, pins);
        let mut odr = 0u16;
        // Dir pins start low ("positive"), step pins low.
        odr = apply_bsrr(odr, pins.step_off);
        Rig {
            shared,
            slot,
            feeder: Feeder::new(prod, Box::leak(Box::new(ddastep::planning::lookahead::Buffer::new())), shared, slot, pins),
            engine,
            timer: TimerSim::new(),
            pins,
            odr,
            steps: Vec::new(),
            updates: 0,
            dir_change: [None; N],
            last_edge: None,
        }
    }

    /// Timing of the trapezoid rigs: 0.5 µs pulses, 1 µs direction setup, 500 kHz at most.
    pub const FAST: Timing = Timing::new(36, 72, 144);

    pub fn trapezoid(v0: u32, vmax: u32, accel: u32) -> Self {
        Self::new(RampConfig { v0, vmax, accel, shape: Shape::Trapezoid }, Self::FAST)
    }

    pub fn push(&mut self, steps: [i64; N], cruise_hz: u32) {
        let mv = Move::new(steps, cruise_hz).expect("valid move");
        self.feeder.push(mv).expect("queue has room");
    }

    /// One update event: decode the word into step edges and direction changes.
    pub fn update(&mut self) -> Edge {
        // The feeder hands moves over as the firmware's idle loop would (between ticks).
        self.feeder.service();
        let e = self.timer.update(&mut self.engine);
        self.updates += 1;
        let after = apply_bsrr(self.odr, e.word);
        for a in 0..N {
            // Any store to the direction pin (even one that leaves it as it was) counts.
            if e.word & (self.pins.dir_pos[a] | self.pins.dir_neg[a]) != 0 {
                self.dir_change[a] = Some(e.t);
            }
        }
        for a in 0..N {
            // A step: the pin goes active (single-edge) or changes level (dual-edge).
            let stepped = if self.pins.dual { (after ^ self.odr) as u32 & self.pins.step_on[a] != 0 } else { e.word & self.pins.step_on[a] != 0 };
            if stepped {
                let dbit = 1u16 << ddastep::board::DIR_PINS[a];
                // (`$3`: positive is the level `dir_pos` sets.)
                let pos_high = self.pins.dir_pos[a] & 0xFFFF != 0;
                self.steps.push(StepEdge {
                    t: e.t,
                    axis: a,
                    positive: (after & dbit != 0) == pos_high,
                    dir_changed_at: self.dir_change[a],
                });
            }
        }
        // The compare event puts the step pins back before the next update.
        self.odr = apply_bsrr(after, self.pins.step_off);
        self.last_edge = Some(e);
        e
    }

    /// Rebuilds the output at rest with `pins`, as the firmware's `output::rebuild`: the step
    /// pins to their idle level, the engine and the feeder take the map.
    pub fn rebuild(&mut self, pins: PinMap<N>) {
        self.odr = apply_bsrr(self.odr, pins.idle_word());
        self.engine.rebuild(pins, self.odr as u32);
        self.feeder.set_pins(pins);
        self.pins = pins;
    }

    /// Runs until the engine is idle with nothing queued (or `max_updates` pass).
    pub fn run_to_idle(&mut self, max_updates: u64) {
        let start = self.updates;
        loop {
            self.update();
            if self.feeder.pending() == 0 && self.shared.state() == State::Idle {
                // One more update writes the last computed word.
                self.update();
                break;
            }
            assert!(self.updates - start < max_updates, "engine did not finish");
        }
    }

    /// Net steps per axis seen on the pins.
    pub fn net_steps(&self) -> [i64; N] {
        let mut n = [0i64; N];
        for s in &self.steps {
            n[s.axis] += if s.positive { 1 } else { -1 };
        }
        n
    }

    /// Master-step times of `axis`.
    pub fn times(&self, axis: usize) -> Vec<u64> {
        self.steps.iter().filter(|s| s.axis == axis).map(|s| s.t).collect()
    }
}

impl<const N: usize> Rig<N> {
    /// The same rig with its engine filling DMA buffers of entries at most `max_tick` long
    /// (the firmware's DMA burst mode) instead of running tick by tick.
    pub fn into_burst(self, max_tick: u32) -> BurstRig<N> {
        let burst = ddastep::motion::burst::Burst::new(self.engine, self.shared, max_tick);
        BurstRig { shared: self.shared, feeder: self.feeder, burst, pins: self.pins }
    }
}

/// A rig whose engine fills DMA buffers ([`Rig::into_burst`]).
pub struct BurstRig<const N: usize> {
    pub shared: &'static Shared<N>,
    pub feeder: Feeder<'static, N>,
    pub burst: ddastep::motion::burst::Burst<'static, N>,
    pub pins: PinMap<N>,
}
