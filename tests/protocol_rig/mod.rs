//! A host bench for the Grbl front end: the real controller, queue, engine and TIM2 model,
//! driven the way the firmware shell drives them (realtime bytes split off, 1 ms polls).
#![allow(dead_code)]

use ddastep::board::pin_map;
use ddastep::controller::{Actions, Controller};
use ddastep::engine::Engine;
use ddastep::protocol::{realtime, Out, Realtime};
use ddastep::queue::{Feeder, Move, Shared, State};
use ddastep::ramp::RampSlot;
use ddastep::settings::Settings;
use ddastep::sim::TimerSim;
use ddastep::TICKS_PER_MS;
use heapless::spsc::Queue;

/// A TX ring: bytes beyond `cap` are dropped, as the firmware's would be.
pub struct Tx {
    pub buf: Vec<u8>,
    pub cap: usize,
}

impl Out for Tx {
    fn put(&mut self, b: &[u8]) {
        let n = b.len().min(self.cap - self.buf.len());
        self.buf.extend_from_slice(&b[..n]);
    }
    fn room(&self) -> usize {
        self.cap - self.buf.len()
    }
}

/// A motor with a quadrature encoder on one axis, as TIM3 and the firmware's SysTick see it:
/// the count follows the axis's position `lag_ms` milliseconds late, times `counts_per_step`,
/// minus the counts slipped so far; the controller gets the library's own 16-bit extension.
pub struct EncoderModel {
    pub axis: usize,
    pub counts_per_step: f64,
    pub lag_ms: usize,
    /// Counts lost so far (missed steps × counts per step).
    pub slipped: f64,
    history: std::collections::VecDeque<i32>,
    sampler: ddastep::encoder::count::Sampler,
}

impl EncoderModel {
    pub fn new(axis: usize, counts_per_step: f64, lag_ms: usize) -> Self {
        EncoderModel { axis, counts_per_step, lag_ms, slipped: 0.0, history: Default::default(), sampler: Default::default() }
    }
}

pub struct Bench<const N: usize> {
    /// An encoder read before every poll, when set.
    pub encoder: Option<EncoderModel>,
    pub shared: &'static Shared<N>,
    pub ctl: Controller<'static, N>,
    pub engine: Engine<'static, N>,
    pub timer: TimerSim,
    pub tx: Tx,
    /// Everything the controller wrote since the last `take`.
    pub text: String,
    pub now_ms: u32,
    pub actions: Vec<Actions>,
    /// Highest master rate seen (steps/s) and drivers seen disabled while stepping.
    pub peak_hz: u32,
    pub stepped_while_disabled: bool,
    pub enabled: bool,
}

impl<const N: usize> Bench<N> {
    pub fn new(settings: Settings) -> Self {
        let shared: &'static Shared<N> = Box::leak(Box::new(Shared::new()));
        let slot: &'static RampSlot = Box::leak(Box::new(RampSlot::new()));
        let q: &'static mut Queue<Move<N>, 16> = Box::leak(Box::new(Queue::new()));
        let (prod, cons) = q.split();
        let engine = Engine::new(shared, cons, slot, pin_map::<N>(0, 0));
        let ctl = Controller::new(Feeder::new(prod, shared), shared, slot, settings);
        let mut b = Bench {
            encoder: None,
            shared,
            ctl,
            engine,
            timer: TimerSim::new(),
            tx: Tx { buf: Vec::new(), cap: 4096 },
            text: String::new(),
            now_ms: 0,
            actions: Vec::new(),
            peak_hz: 0,
            stepped_while_disabled: false,
            enabled: false,
        };
        b.ctl.welcome(&mut b.tx);
        b.drain();
        b
    }

    pub fn with_defaults() -> Self {
        Self::new(Settings::BENCH)
    }

    /// The UART sends what is in the TX ring.
    pub fn drain(&mut self) {
        self.text.push_str(&String::from_utf8_lossy(&self.tx.buf));
        self.tx.buf.clear();
    }

    /// Returns and forgets the output so far.
    pub fn take(&mut self) -> String {
        self.drain();
        std::mem::take(&mut self.text)
    }

    /// One millisecond: the engine runs, then the serial task polls.
    pub fn tick_ms(&mut self) {
        let before = self.shared.positions();
        self.now_ms += 1;
        let end = self.now_ms as u64 * TICKS_PER_MS as u64;
        while self.timer.now() < end {
            self.timer.update(&mut self.engine);
            self.peak_hz = self.peak_hz.max(self.shared.rate_hz());
        }
        if self.shared.positions() != before && !self.enabled {
            self.stepped_while_disabled = true;
        }
        if let Some(e) = &mut self.encoder {
            e.history.push_back(self.shared.positions()[e.axis]);
            while e.history.len() > e.lag_ms + 1 {
                e.history.pop_front();
            }
            let counts = (e.history[0] as f64 * e.counts_per_step - e.slipped).floor() as i64;
            let (count, window) = e.sampler.sample(counts as u16);
            self.ctl.encoder(count, window, &mut self.tx);
        }
        let a = self.ctl.poll(self.now_ms, &mut self.tx);
        self.enabled = a.enable;
        self.actions.push(a);
        self.drain();
    }

    pub fn run_ms(&mut self, ms: u32) {
        for _ in 0..ms {
            self.tick_ms();
        }
    }

    /// One received byte, as the RX interrupt and the serial task treat it; waits (in 1 ms
    /// steps) while the controller holds a line.
    pub fn byte(&mut self, b: u8) {
        match realtime(b) {
            Some(Realtime::Status) => self.ctl.status_request(),
            Some(Realtime::Hold) => self.shared.set_hold(true),
            Some(Realtime::Resume) => self.shared.set_hold(false),
            Some(Realtime::Reset) => {
                self.ctl.soft_reset(&mut self.tx);
                self.drain();
            }
            Some(Realtime::JogCancel) => self.ctl.jog_cancel(),
            Some(Realtime::Extended(x)) => self.shared.set_overrides(self.shared.overrides().apply(x)),
            None => {
                let mut waited = 0;
                while !self.ctl.byte(b, &mut self.tx) {
                    self.tick_ms();
                    waited += 1;
                    assert!(waited < 600_000, "line held for 10 min");
                }
                self.drain();
            }
        }
    }

    pub fn send(&mut self, s: &str) {
        for &b in s.as_bytes() {
            self.byte(b);
        }
    }

    /// Sends a line and returns the replies up to its `ok`/`error` (running the machine
    /// while it is held).
    pub fn line(&mut self, s: &str) -> String {
        self.send(s);
        self.send("\n");
        self.finish();
        self.take()
    }

    /// Runs until the held line, if any, is accepted.
    pub fn finish(&mut self) {
        let mut waited = 0;
        while self.ctl.busy() {
            self.tick_ms();
            waited += 1;
            assert!(waited < 600_000, "line held for 10 min");
        }
    }

    /// Runs until the queue is empty, no line is held and the engine is idle.
    pub fn run_to_idle(&mut self, max_ms: u32) {
        for _ in 0..max_ms {
            self.tick_ms();
            if !self.ctl.busy() && self.shared.state() == State::Idle && self.queue_empty() {
                return;
            }
        }
        panic!("not idle after {max_ms} ms: {:?}", self.shared.state());
    }

    fn queue_empty(&self) -> bool {
        // Nothing pending: every pushed move finished (or the bench never pushed one).
        self.ctl.pending_moves() == 0
    }

    pub fn status(&mut self) -> String {
        self.take();
        self.ctl.status_request();
        self.tick_ms();
        self.take()
    }
}

/// Counts `ok` and `error:` replies.
pub fn replies(text: &str) -> (usize, usize) {
    let oks = text.lines().filter(|l| l.trim_end() == "ok").count();
    let errs = text.lines().filter(|l| l.starts_with("error:")).count();
    (oks, errs)
}
