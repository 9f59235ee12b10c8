//! A host bench for the Grbl front end: the real controller, queue, engine and TIM2 model,
//! driven the way the firmware shell drives them (realtime bytes split off, 1 ms polls).
#![allow(dead_code)]

use ddastep::board::pin_map;
use ddastep::grbl::controller::{Actions, Controller};
use ddastep::motion::engine::Engine;
use ddastep::grbl::reply::Out;
use ddastep::grbl::shell::{dispatch, idle_step, take_inputs, Inputs, Requests};
use heapless::spsc::{Consumer, Producer, Queue};
use ddastep::motion::shared::{Shared, State};
use ddastep::planning::feeder::Feeder;
use ddastep::motion::ramp::RampSlot;
use ddastep::grbl::settings::Settings;
use ddastep::motion::tim2_model::TimerSim;
use ddastep::TICKS_PER_MS;
use ddastep::motion::ring::MoveRing;

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
    /// The last sample: extended count, counts of the window.
    last: (i32, i32),
}

impl EncoderModel {
    pub fn new(axis: usize, counts_per_step: f64, lag_ms: usize) -> Self {
        EncoderModel { axis, counts_per_step, lag_ms, slipped: 0.0, history: Default::default(), sampler: Default::default(), last: (0, 0) }
    }
}

pub struct Bench<const N: usize> {
    /// An encoder read before every poll, when set.
    pub encoder: Option<EncoderModel>,
    /// A probe switch: in contact while axis `.0` is at or below step `.1`. Its input is
    /// offered to the engine's probe check after every timer event (the firmware's EXTI
    /// handler at the step interrupt's priority) and to the controller before every poll.
    pub probe: Option<(usize, i32)>,
    /// The safety door input is active (door open), read by every idle pass.
    pub door_open: bool,
    /// Step positions at the timer events where the probe input changed (contact made/lost).
    pub probe_edges: Vec<[i32; N]>,
    probe_was: bool,
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
    /// Carriage positions, steps: the engine's steps only (a position the controller sets,
    /// as homing does, moves no carriage).
    pub carriage: [i64; N],
    /// Limit switches (axis, carriage position in steps, max end): pressed at or past it.
    /// Their pins reach the controller at each poll; while homing watches an axis, its switch
    /// stops the engine at once (the firmware's limit interrupt).
    pub switches: Vec<(usize, i32, bool)>,
    /// When set, every change of the master rate: (timer ticks, steps/s, moves done).
    pub trace: Option<Vec<(u64, u32, u32)>>,
    /// The RX ring and the requests, as the firmware's USART interrupt leaves them.
    rx_in: Producer<'static, u8>,
    rx_out: Consumer<'static, u8>,
    req: &'static Requests,
}

impl<const N: usize> Bench<N> {
    pub fn new(settings: Settings) -> Self {
        Self::with_stored(settings)
    }

    /// A rig whose controller boots from a persistent image (settings, coordinates, startup
    /// lines, build info), as the firmware does from flash.
    pub fn with_stored(stored: impl Into<ddastep::grbl::store::Stored>) -> Self {
        let shared: &'static Shared<N> = Box::leak(Box::new(Shared::new()));
        let slot: &'static RampSlot = Box::leak(Box::new(RampSlot::new()));
        let q: &'static mut MoveRing<N> = Box::leak(Box::new(MoveRing::new()));
        let (prod, cons) = q.split();
        let engine = Engine::new(shared, cons, slot, pin_map::<N>(0, 0));
        let ctl = Controller::new(Feeder::new(prod, Box::leak(Box::new(ddastep::planning::lookahead::Buffer::new())), shared, slot, pin_map::<N>(0, 0)), shared, slot, stored);
        let rxq: &'static mut Queue<u8, 256> = Box::leak(Box::new(Queue::new()));
        let (rx_in, rx_out) = rxq.split();
        let mut b = Bench {
            encoder: None,
            probe: None,
            door_open: false,
            probe_edges: Vec::new(),
            probe_was: false,
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
            switches: Vec::new(),
            carriage: [0; N],
            trace: None,
            rx_in,
            rx_out,
            req: Box::leak(Box::new(Requests::new())),
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
            let was = self.shared.positions();
            self.timer.update(&mut self.engine);
            for (c, (a, b)) in self.carriage.iter_mut().zip(self.shared.positions().iter().zip(was)) {
                *c += (a.wrapping_sub(b)) as i64;
            }
            if let Some(w) = self.ctl.homing_watch() {
                if self.limit_mask() & w != 0 {
                    self.shared.stop_now();
                }
            }
            let hz = self.shared.rate_hz();
            self.peak_hz = self.peak_hz.max(hz);
            if let Some(t) = self.trace.as_mut() {
                let done = self.shared.moves_done();
                if t.last().is_none_or(|l| (l.1, l.2) != (hz, done)) {
                    t.push((self.timer.now(), hz, done));
                }
            }
            let active = self.probe_contact();
            if active != self.probe_was {
                self.probe_was = active;
                self.probe_edges.push(self.shared.positions());
            }
            self.shared.probe_input(active);
        }
        if self.shared.positions() != before && !self.enabled {
            self.stepped_while_disabled = true;
        }
        if let Some(e) = &mut self.encoder {
            // SysTick's sample, once a millisecond.
            e.history.push_back(self.shared.positions()[e.axis]);
            while e.history.len() > e.lag_ms + 1 {
                e.history.pop_front();
            }
            let counts = (e.history[0] as f64 * e.counts_per_step - e.slipped).floor() as i64;
            e.last = e.sampler.sample(counts as u16);
        }
        self.idle_step();
    }

    /// Limit switches pressed now (bit i = axis i).
    pub fn limit_mask(&self) -> u8 {
        let p = self.carriage;
        self.switches.iter().fold(0, |m, &(i, at, max)| {
            let (p, at) = (p[i], at as i64);
            if (max && p >= at) || (!max && p <= at) {
                m | 1 << i
            } else {
                m
            }
        })
    }

    /// One pass of the firmware's idle loop (the library's `take_inputs`, the encoder check,
    /// then the library's `idle_step`).
    fn idle_step(&mut self) {
        let inputs = Inputs {
            // GPIOA as the shell reads it: pulled up, a pressed (NO) switch pulls its pin low.
            gpioa_idr: !(self.limit_mask() as u32) & 0xFFFF,
            // The probe in contact pulls its pin low.
            probe_low: self.probe_contact(),
            door_open: self.door_open,
        };
        take_inputs(&mut self.ctl, self.shared, inputs);
        if let Some(e) = &self.encoder {
            self.ctl.encoder(e.last.0, e.last.1, &mut self.tx);
        }
        let a = idle_step(&mut self.ctl, &mut self.rx_out, &mut self.tx, self.now_ms, self.req);
        if a.reinit {
            // As the firmware's `output::rebuild` (at rest): the engine takes the new pin map
            // (the rig models no pin levels).
            self.engine.rebuild(self.ctl.settings().pins(), 0);
        }
        self.enabled = a.enable;
        self.actions.push(a);
        self.drain();
    }

    /// The probe switch is in contact now.
    pub fn probe_contact(&self) -> bool {
        self.probe.is_some_and(|(axis, at)| self.shared.positions()[axis] <= at)
    }

    pub fn run_ms(&mut self, ms: u32) {
        for _ in 0..ms {
            self.tick_ms();
        }
    }

    /// One received byte through the library's RX dispatch (realtime bytes act at once, line
    /// bytes go to the RX ring), then a pass of the idle loop; waits (in 1 ms steps) while the
    /// ring is full.
    pub fn byte(&mut self, b: u8) {
        if let Some(b) = dispatch(b, self.shared, self.req) {
            let mut waited = 0;
            while self.rx_in.enqueue(b).is_err() {
                self.tick_ms();
                waited += 1;
                assert!(waited < 600_000, "RX ring full for 10 min");
            }
        }
        self.idle_step();
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

    /// Line bytes in the RX ring that the controller has not taken yet.
    pub fn rx_waiting(&self) -> usize {
        self.rx_out.len()
    }

    /// Runs until the held line, if any, is accepted.
    pub fn finish(&mut self) {
        let mut waited = 0;
        while self.ctl.busy() || self.rx_out.len() > 0 {
            self.tick_ms();
            waited += 1;
            assert!(waited < 600_000, "line held for 10 min");
        }
    }

    /// Runs until the queue is empty, no line is held and the engine is idle.
    pub fn run_to_idle(&mut self, max_ms: u32) {
        for _ in 0..max_ms {
            self.tick_ms();
            if !self.ctl.busy() && self.rx_out.len() == 0 && self.shared.state() == State::Idle && self.queue_empty() {
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

/// Moves the controller buffers (look-ahead plus prepared ring): `[OPT:]`'s block count and
/// `Bf:`'s free blocks at rest.
#[allow(dead_code, reason = "not every test file uses it")]
pub const BLOCKS: usize = ddastep::planning::lookahead::LOOKAHEAD + ddastep::motion::ring::RING;

/// Counts `ok` and `error:` replies.
pub fn replies(text: &str) -> (usize, usize) {
    let oks = text.lines().filter(|l| l.trim_end() == "ok").count();
    let errs = text.lines().filter(|l| l.starts_with("error:")).count();
    (oks, errs)
}
