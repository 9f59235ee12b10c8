//! The move queue between the planner (producer) and the step engine (consumer), and the
//! state they share: all lock-free (a `heapless::spsc` queue and atomics).
//!
//! Who uses it: the planner pushes [`Move`]s through a [`Feeder`]; the engine consumes them;
//! status reports read [`Shared`].
//!
//! Invariant: an immediate stop ([`Feeder::abort`]) bumps an epoch; the engine drops the running
//! move at its next tick and every queued move stamped with an older epoch when it reaches it
//! (one per tick, so the interrupt never loops over the queue).

use core::sync::atomic::{fence, AtomicI32, AtomicU32, AtomicU8, Ordering::{Acquire, Relaxed, Release}};

use heapless::spsc::Producer;

use crate::interp::master_axis;
use crate::ramp::{period_of_millihz, Period, MAX_RATE_HZ, MIN_RATE_HZ};

/// What the engine is doing, as published in [`Shared::state`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum State {
    /// No move.
    Idle = 0,
    /// Running a move.
    Run = 1,
    /// Feed hold requested, decelerating.
    Holding = 2,
    /// Feed hold complete: stopped mid-move (or between moves).
    Held = 3,
}

/// Grbl's override percentages (feed, rapid, spindle; 100 = as programmed), as `Ov:` reports
/// them: feed 10–200, rapid 25/50/100, spindle 10–200.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Overrides {
    pub feed: u8,
    pub rapid: u8,
    pub spindle: u8,
}

impl Overrides {
    /// Everything as programmed (power-up and reset).
    pub const NONE: Overrides = Overrides { feed: 100, rapid: 100, spindle: 100 };

    const fn pack(self) -> u32 {
        self.feed as u32 | (self.rapid as u32) << 8 | (self.spindle as u32) << 16
    }

    /// After one Grbl 1.1 override byte (0x90–0x9D; others change nothing): feed and spindle
    /// 100 % / ±10 / ±1 within 10–200 %, rapid 100, 50 or 25 %.
    pub fn apply(self, b: u8) -> Overrides {
        let step = |v: u8, d: i16| (v as i16 + d).clamp(10, 200) as u8;
        let mut o = self;
        match b {
            0x90 => o.feed = 100,
            0x91 => o.feed = step(o.feed, 10),
            0x92 => o.feed = step(o.feed, -10),
            0x93 => o.feed = step(o.feed, 1),
            0x94 => o.feed = step(o.feed, -1),
            0x95 => o.rapid = 100,
            0x96 => o.rapid = 50,
            0x97 => o.rapid = 25,
            0x99 => o.spindle = 100,
            0x9A => o.spindle = step(o.spindle, 10),
            0x9B => o.spindle = step(o.spindle, -10),
            0x9C => o.spindle = step(o.spindle, 1),
            0x9D => o.spindle = step(o.spindle, -1),
            _ => {}
        }
        o
    }
}

/// Why a move cannot be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MoveError {
    /// No axis moves.
    ZeroLength,
    /// A step count beyond ±(2^31 - 1).
    TooManySteps,
    /// Cruise rate outside 1 step/s ..= 1 MHz.
    RateOutOfRange,
}

/// One straight move, ready for the queue: signed steps per axis and the master cruise rate.
/// Built outside the interrupt (this is where the division happens).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Move<const N: usize> {
    pub(crate) steps: [i32; N],
    pub(crate) master: u8,
    pub(crate) cruise: Period,
    pub(crate) epoch: u32,
}

impl<const N: usize> Move<N> {
    /// A move of `steps` (signed, per axis) whose master axis cruises at `cruise_hz` steps/s.
    pub fn new(steps: [i64; N], cruise_hz: u32) -> Result<Self, MoveError> {
        Self::new_millihz(steps, cruise_hz as u64 * 1000)
    }

    /// The same with the cruise rate in milli-steps per second (G93 times need more than whole
    /// steps/s at low rates).
    pub fn new_millihz(steps: [i64; N], cruise_millihz: u64) -> Result<Self, MoveError> {
        if !(MIN_RATE_HZ as u64 * 1000..=MAX_RATE_HZ as u64 * 1000).contains(&cruise_millihz) {
            return Err(MoveError::RateOutOfRange);
        }
        let mut s = [0i32; N];
        let mut counts = [0u32; N];
        for i in 0..N {
            if steps[i] > i32::MAX as i64 || steps[i] < -(i32::MAX as i64) {
                return Err(MoveError::TooManySteps);
            }
            s[i] = steps[i] as i32;
            counts[i] = s[i].unsigned_abs();
        }
        let master = master_axis(&counts);
        if counts[master] == 0 {
            return Err(MoveError::ZeroLength);
        }
        Ok(Move { steps: s, master: master as u8, cruise: period_of_millihz(cruise_millihz), epoch: 0 })
    }

    /// Signed steps per axis.
    pub fn steps(&self) -> &[i32; N] {
        &self.steps
    }

    /// The master axis (most steps, ties to the lowest index).
    pub fn master(&self) -> usize {
        self.master as usize
    }

    /// Master cruise period.
    pub fn cruise(&self) -> Period {
        self.cruise
    }
}

/// State shared lock-free between the engine (interrupt) and the rest of the firmware.
///
/// Positions are published as a record the engine rewrites only when a move starts or ends:
/// the axes' positions at the start of the running move (`base`), that move's signed steps, its
/// master count and the master steps handed out so far (`done`, one store per step). A reader
/// derives every axis's position exactly as the DDA made it, `base + sign·⌊(done·|c| + ⌊M/2⌋)/M⌋`
/// (the division happens in the reader, never in the interrupt). `seq` is a sequence lock: odd
/// while the engine rewrites the record, so a reader that overlapped a rewrite reads again.
pub struct Shared<const N: usize> {
    base: [AtomicI32; N],
    mv_steps: [AtomicI32; N],
    mv_total: AtomicU32,
    pub(crate) mv_done: AtomicU32,
    seq: AtomicU32,
    /// Control word the engine polls with one load per tick: bit 0 feed hold, bits 1.. the
    /// immediate-stop epoch.
    pub(crate) ctl: AtomicU32,
    pub(crate) state: AtomicU8,
    pub(crate) moves_done: AtomicU32,
    pub(crate) period_bits: AtomicU32,
    /// [`Overrides`] packed feed | rapid << 8 | spindle << 16.
    ovr: AtomicU32,
}

impl<const N: usize> Default for Shared<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Shared<N> {
    pub const fn new() -> Self {
        Shared {
            base: [const { AtomicI32::new(0) }; N],
            mv_steps: [const { AtomicI32::new(0) }; N],
            mv_total: AtomicU32::new(0),
            mv_done: AtomicU32::new(0),
            seq: AtomicU32::new(0),
            ctl: AtomicU32::new(0),
            state: AtomicU8::new(State::Idle as u8),
            moves_done: AtomicU32::new(0),
            period_bits: AtomicU32::new(0),
            ovr: AtomicU32::new(Overrides::NONE.pack()),
        }
    }

    /// Feed hold on (decelerate and pause) or off (resume).
    pub fn set_hold(&self, on: bool) {
        if on {
            self.ctl.fetch_or(1, Relaxed);
        } else {
            self.ctl.fetch_and(!1, Relaxed);
        }
    }

    /// The override percentages in force.
    pub fn overrides(&self) -> Overrides {
        let v = self.ovr.load(Relaxed);
        Overrides { feed: v as u8, rapid: (v >> 8) as u8, spindle: (v >> 16) as u8 }
    }

    /// Sets the override percentages (the realtime override bytes).
    pub fn set_overrides(&self, o: Overrides) {
        self.ovr.store(o.pack(), Relaxed);
    }

    /// True while a feed hold is requested.
    pub fn hold_requested(&self) -> bool {
        self.ctl.load(Relaxed) & 1 != 0
    }

    /// The immediate-stop epoch moves are stamped with.
    pub(crate) fn epoch(&self) -> u32 {
        self.ctl.load(Relaxed) >> 1
    }

    /// What the engine is doing.
    pub fn state(&self) -> State {
        match self.state.load(Relaxed) {
            1 => State::Run,
            2 => State::Holding,
            3 => State::Held,
            _ => State::Idle,
        }
    }

    /// Moves finished since start (for synchronisation, e.g. G4 or `?`).
    pub fn moves_done(&self) -> u32 {
        self.moves_done.load(Relaxed)
    }

    /// Current master step rate in steps/s (0 when idle).
    pub fn rate_hz(&self) -> u32 {
        match self.period_bits.load(Relaxed) {
            0 => 0,
            b => ((crate::TIMER_HZ as u64 * 16) / b as u64) as u32,
        }
    }

    /// Position of every axis in steps: the step words handed out so far.
    pub fn positions(&self) -> [i32; N] {
        loop {
            let s1 = self.seq.load(Acquire);
            let total = self.mv_total.load(Relaxed).max(1) as u64;
            let done = self.mv_done.load(Relaxed) as u64;
            let p = core::array::from_fn(|i| {
                let c = self.mv_steps[i].load(Relaxed);
                let made = ((done * c.unsigned_abs() as u64 + total / 2) / total) as i32;
                let made = if c < 0 { -made } else { made };
                self.base[i].load(Relaxed).wrapping_add(made)
            });
            fence(Acquire);
            if s1 & 1 == 0 && self.seq.load(Relaxed) == s1 {
                return p;
            }
        }
    }

    /// Sets positions (only while idle: G92 and homing).
    pub fn set_positions(&self, p: [i32; N]) {
        self.begin_write();
        for (a, v) in self.base.iter().zip(p) {
            a.store(v, Relaxed);
        }
        self.end_write();
    }

    /// Engine: a move of `steps` (master count `total`) starts from the current base.
    pub(crate) fn start_move(&self, steps: &[i32; N], total: u32) {
        self.begin_write();
        for (a, &v) in self.mv_steps.iter().zip(steps) {
            a.store(v, Relaxed);
        }
        self.mv_total.store(total, Relaxed);
        self.mv_done.store(0, Relaxed);
        self.end_write();
    }

    /// Engine: the running move ends; `made(i)` is what axis `i` made of it (signed).
    pub(crate) fn end_move(&self, made: impl Fn(usize) -> i32) {
        self.begin_write();
        for (i, a) in self.base.iter().enumerate() {
            a.store(a.load(Relaxed).wrapping_add(made(i)), Relaxed);
        }
        for a in &self.mv_steps {
            a.store(0, Relaxed);
        }
        self.mv_done.store(0, Relaxed);
        self.end_write();
    }

    fn begin_write(&self) {
        self.seq.store(self.seq.load(Relaxed).wrapping_add(1), Relaxed);
        fence(Release);
    }

    fn end_write(&self) {
        fence(Release);
        self.seq.store(self.seq.load(Relaxed).wrapping_add(1), Release);
    }
}

/// Producer side of the move queue: stamps moves so an immediate stop can drop them.
pub struct Feeder<'a, const N: usize> {
    producer: Producer<'a, Move<N>>,
    shared: &'a Shared<N>,
    queued: u32,
}

impl<'a, const N: usize> Feeder<'a, N> {
    pub fn new(producer: Producer<'a, Move<N>>, shared: &'a Shared<N>) -> Self {
        Feeder { producer, shared, queued: shared.moves_done() }
    }

    /// Queues a move; gives it back when the queue is full.
    pub fn push(&mut self, mut mv: Move<N>) -> Result<(), Move<N>> {
        mv.epoch = self.shared.epoch();
        self.producer.enqueue(mv)?;
        self.queued = self.queued.wrapping_add(1);
        Ok(())
    }

    /// Moves the queue holds at most.
    pub fn capacity(&self) -> usize {
        self.producer.capacity()
    }

    /// True when another move fits.
    pub fn ready(&self) -> bool {
        self.producer.ready()
    }

    /// Moves queued or running.
    pub fn pending(&self) -> u32 {
        self.queued.wrapping_sub(self.shared.moves_done())
    }

    /// Immediate stop: the running move ends at the next tick and queued moves are dropped.
    /// Positions stay equal to the pulses emitted.
    pub fn abort(&mut self) {
        self.shared.ctl.fetch_add(2, Relaxed);
        // Dropped moves never count as done; forget them here.
        self.queued = self.shared.moves_done();
    }
}

