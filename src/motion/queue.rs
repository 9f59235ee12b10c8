//! Moves as the planner hands them over, and the state shared lock-free between the step
//! interrupt and everything else (atomics only).
//!
//! Who uses it: the planner builds [`Move`]s; the [`Feeder`] plans and prepares them for the
//! engine; status reports read [`Shared`].
//!
//! Invariant: an immediate stop ([`Feeder::abort`]) bumps an epoch in the control word; the
//! engine drops the running move at its next tick and every queued move stamped with an older
//! epoch when it reaches it (one per tick, so the interrupt never loops over the queue).

use core::sync::atomic::{fence, AtomicI32, AtomicU32, AtomicU8, AtomicUsize, Ordering::{Acquire, Relaxed, Release}};

use crate::motion::control::Control;
pub use crate::planning::feeder::Feeder;
use crate::motion::interp::master_axis;
use crate::motion::prepared::Prepared;
use crate::motion::ramp::{period_of_millihz, Period, MAX_RATE_HZ, MIN_RATE_HZ};

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

/// One straight move: signed steps per axis and the master cruise rate; with a [`Path`], also
/// what the look-ahead needs to run it through its junctions. Built outside the interrupt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move<const N: usize> {
    pub(crate) steps: [i32; N],
    pub(crate) master: u8,
    pub(crate) ovr: Ovr,
    pub(crate) cruise: Period,
    pub(crate) path: Option<Path>,
}

/// Which override scales a move: feed for G1/G2/G3 (and G93), rapid for G0, none for jogs
/// (Grbl 1.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Ovr {
    None,
    Feed,
    Rapid,
}

/// A move's master cruise rate and what an override makes of it: Grbl scales the programmed
/// rate (F, or the axes' limit for G0), then the axes' max rates still bind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates {
    pub ovr: Ovr,
    /// Master steps/s asked at 100 % and allowed (see [`Path`]).
    pub asked_hz: f32,
    pub cap_hz: f32,
    /// Master period at 100 % (every clamp applied).
    pub cruise: Period,
}

impl Rates {
    /// The master cruise under the overrides `o`.
    pub fn cruise_at(&self, o: Overrides) -> Period {
        let pct = match self.ovr {
            Ovr::Feed => o.feed,
            Ovr::Rapid => o.rapid,
            Ovr::None => 100,
        };
        if pct == 100 {
            return self.cruise;
        }
        // max/min, not clamp (no panic path); f32 like the planner.
        let hz = (self.asked_hz * pct as f32 * 0.01).min(self.cap_hz).max(MIN_RATE_HZ as f32);
        period_of_millihz(crate::num::u64_of(hz * 1000.0))
    }
}

/// A move's length and limits in path units (mm, s), for the look-ahead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Path {
    /// Master steps per mm of path.
    pub share: f32,
    /// Path acceleration the moving axes allow, mm/s².
    pub accel: f32,
    /// Master steps/s asked at 100 % (F, or the axes' limit for G0), before any clamp, and
    /// the most the axes' max rates, the step timing and the table's top allow: an override
    /// scales the first, the second still binds.
    pub asked_hz: f32,
    pub cap_hz: f32,
    /// Highest speed at the junction with the previous move from junction deviation `$11`
    /// (0 from rest, +∞ straight on), mm/s; the look-ahead also caps it by both moves' speeds.
    pub junction: f32,
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
        if counts.get(master).is_none_or(|&c| c == 0) {
            return Err(MoveError::ZeroLength);
        }
        Ok(Move { steps: s, master: master as u8, ovr: Ovr::None, cruise: period_of_millihz(cruise_millihz), path: None })
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

    /// Its cruise and how the overrides scale it (a move without a path: not at all).
    pub fn rates(&self) -> Rates {
        let (ovr, asked_hz, cap_hz) = match self.path {
            Some(p) => (self.ovr, p.asked_hz, p.cap_hz),
            None => (Ovr::None, 0.0, 0.0),
        };
        Rates { ovr, asked_hz, cap_hz, cruise: self.cruise }
    }

    /// The same move, never overridden (a jog).
    pub fn fixed(mut self) -> Self {
        self.ovr = Ovr::None;
        self
    }

    /// The same move with its geometry, so the look-ahead can join it to its neighbours.
    pub fn with_path(mut self, path: Path) -> Self {
        self.path = Some(path);
        self
    }

    /// Its geometry, if it has one (a move without one starts and ends at rest).
    pub fn path(&self) -> Option<&Path> {
        self.path.as_ref()
    }
}

/// Override percentages (Grbl 1.1 realtime bytes 0x90–0x9D).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Overrides {
    pub feed: u8,
    pub rapid: u8,
    pub spindle: u8,
}

impl Overrides {
    /// 100 % everywhere.
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


/// State shared lock-free between the engine (interrupt) and the rest of the firmware.
///
/// Positions are published as a record the engine rewrites only when a move starts or ends:
/// the running move (a pointer to its prepared slot: absolute start, signed steps, master
/// count) and the master steps handed out so far (`done`, one store per step); while idle, the
/// positions themselves (`base`). A reader derives every axis's position exactly as the DDA
/// made it, `start + sign·⌊(done·|c| + ⌊M/2⌋)/M⌋` (the division happens in the reader, never
/// in the interrupt). `seq` is a sequence lock: odd while the engine rewrites the record, so a
/// reader that overlapped a rewrite reads again.
pub struct Shared<const N: usize> {
    base: [AtomicI32; N],
    cur: AtomicUsize,
    pub(crate) mv_done: AtomicU32,
    seq: AtomicU32,
    /// Feed hold and immediate-stop epoch, polled by the engine with one load per tick.
    pub(crate) ctl: Control,
    pub(crate) state: AtomicU8,
    pub(crate) moves_done: AtomicU32,
    pub(crate) period_bits: AtomicU32,
    /// Moves that ended above the table's first entry with nothing queued (a deceleration to
    /// rest that landed a little high, or a feeder late at speed): a diagnostic.
    pub(crate) starved: AtomicU32,
    /// Override percentages: feed | rapid << 8 | spindle << 16.
    ovr: AtomicU32,
    /// The engine's step half to its ramp half.
    pub(crate) link: crate::motion::engine::Link,
    /// Probe cycle: [`PROBE_ARMED`], [`PROBE_AWAY`], [`PROBE_TRIPPED`] bits.
    probe: AtomicU8,
}

/// A probe cycle is running: the probe input's edge stops the engine.
pub const PROBE_ARMED: u8 = 1;
/// The cycle waits for the probe to *lose* contact (G38.4/G38.5).
pub const PROBE_AWAY: u8 = 2;
/// The probe edge stopped the engine.
pub const PROBE_TRIPPED: u8 = 4;

impl<const N: usize> Default for Shared<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Shared<N> {
    pub const fn new() -> Self {
        Shared {
            base: [const { AtomicI32::new(0) }; N],
            cur: AtomicUsize::new(0),
            mv_done: AtomicU32::new(0),
            seq: AtomicU32::new(0),
            ctl: Control::new(),
            state: AtomicU8::new(State::Idle as u8),
            moves_done: AtomicU32::new(0),
            period_bits: AtomicU32::new(0),
            starved: AtomicU32::new(0),
            ovr: AtomicU32::new(100 | 100 << 8 | 100 << 16),
            probe: AtomicU8::new(0),
            link: crate::motion::engine::Link::new(),
        }
    }

    /// Feed hold on (decelerate and pause) or off (resume). (Out of line: a dozen callers in
    /// the controller and the shell, none on the step path.)
    #[inline(never)]
    pub fn set_hold(&self, on: bool) {
        self.ctl.set_hold(on);
    }

    /// Controller: a probe cycle starts (`away`: G38.4/G38.5).
    pub fn probe_arm(&self, away: bool) {
        self.probe.store(PROBE_ARMED | if away { PROBE_AWAY } else { 0 }, Relaxed);
    }

    /// The probe cycle's bits now.
    pub fn probe_bits(&self) -> u8 {
        self.probe.load(Relaxed)
    }

    /// Controller: the probe cycle ends; true when the probe edge had stopped the engine.
    pub fn probe_disarm(&self) -> bool {
        self.probe.swap(0, Relaxed) & PROBE_TRIPPED != 0
    }

    /// The probe input's interrupt (same priority as the step interrupt), or a bench after
    /// each tick: with a cycle armed and the probe in the state it looks for (`active`: in
    /// contact, `$6` applied), an immediate stop: the engine drops the move at its next tick,
    /// so the last step comes at most one step period after the edge, and the position stays
    /// the pulses made.
    pub fn probe_input(&self, active: bool) {
        let p = self.probe.load(Relaxed);
        if p & (PROBE_ARMED | PROBE_TRIPPED) == PROBE_ARMED
            && active != (p & PROBE_AWAY != 0)
            && self.probe.compare_exchange(p, p | PROBE_TRIPPED, Relaxed, Relaxed).is_ok()
        {
            self.ctl.stop();
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
        self.ctl.load().hold()
    }

    /// Immediate stop from an interrupt (homing: a limit switch closed): the running move ends
    /// at the engine's next tick, its position exact. The owner of the feeder must then call
    /// `Feeder::abort` (the controller's homing does) before queueing again.
    pub fn stop_now(&self) {
        self.ctl.stop();
    }

    /// The immediate-stop epoch moves are stamped with.
    pub(crate) fn epoch(&self) -> u32 {
        self.ctl.load().epoch()
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

    /// Moves that ended above the table's first entry with nothing queued after them.
    pub fn starved(&self) -> u32 {
        self.starved.load(Relaxed)
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
            let cur = self.cur.load(Relaxed) as *const Prepared<N>;
            let done = self.mv_done.load(Relaxed);
            let p = if cur.is_null() {
                core::array::from_fn(|i| self.base[i].load(Relaxed))
            } else {
                // SAFETY: a ring slot (static storage, always valid memory); if the engine left
                // it and the feeder rewrote it meanwhile, `seq` changed and this read is retried.
                let (start, steps, total) = unsafe {
                    (
                        core::ptr::read_volatile(core::ptr::addr_of!((*cur).start)),
                        core::ptr::read_volatile(core::ptr::addr_of!((*cur).steps)),
                        core::ptr::read_volatile(core::ptr::addr_of!((*cur).total)),
                    )
                };
                let total = total.max(1);
                core::array::from_fn(|i| {
                    let c = steps[i];
                    // |c| <= total (the master has the most steps), so the quotient fits.
                    let made = mul_div(done.min(total), c.unsigned_abs(), total / 2, total) as i32;
                    start[i].wrapping_add(if c < 0 { -made } else { made })
                })
            };
            fence(Acquire);
            if s1 & 1 == 0 && self.seq.load(Relaxed) == s1 {
                return p;
            }
        }
    }

    /// Sets positions (only while idle: G92 and homing).
    pub fn set_positions(&self, p: [i32; N]) {
        self.idle_at(|i| p[i]);
    }

    /// Engine: the move in slot `p` starts (its start and steps are in the slot).
    #[inline(always)]
    pub(crate) fn start_move(&self, p: *const Prepared<N>) {
        self.begin_write();
        self.cur.store(p as usize, Relaxed);
        self.mv_done.store(0, Relaxed);
        self.end_write();
    }

    /// The position record's sequence: it moves whenever a move is entered or ended (and on a
    /// G92 while idle); the engine's ramp half watches it.
    pub(crate) fn record_seq(&self) -> u32 {
        self.seq.load(Acquire)
    }

    /// The move the engine's step half runs (null: none).
    pub(crate) fn running(&self) -> *const Prepared<N> {
        self.cur.load(Relaxed) as *const Prepared<N>
    }

    /// Engine (or a G92 while idle): no move runs, axis `i` is at `pos(i)`.
    pub(crate) fn idle_at(&self, pos: impl Fn(usize) -> i32) {
        self.begin_write();
        for (i, a) in self.base.iter().enumerate() {
            a.store(pos(i), Relaxed);
        }
        self.cur.store(0, Relaxed);
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

/// `(a * b + add) / d` for a quotient that fits 32 bits (`a * b + add < d * 2^32`), without a
/// 64-bit division: shift-subtract on the 64-bit product. Saves the ~900 B `__aeabi_uldivmod`
/// the firmware otherwise links (only status reports and the feeder's horizon call this).
pub fn mul_div(a: u32, b: u32, add: u32, d: u32) -> u32 {
    let n = a as u64 * b as u64 + add as u64;
    let d64 = d as u64;
    let mut rem = n >> 32;
    let mut q = 0u32;
    for bit in (0..32).rev() {
        rem = (rem << 1) | ((n >> bit) & 1);
        q <<= 1;
        if rem >= d64 {
            rem -= d64;
            q |= 1;
        }
    }
    q
}

#[cfg(test)]
mod tests {
    use super::mul_div;
    use proptest::prelude::*;

    fn reference(a: u32, b: u32, add: u32, d: u32) -> u64 {
        (a as u64 * b as u64 + add as u64) / d as u64
    }

    #[test]
    fn mul_div_edges() {
        let m = u32::MAX;
        for (a, b, add, d) in [(0, 0, 0, 1), (m, m, m / 2, m), (m, 1, 0, 1), (m - 1, m, 0, m), (7, 3, 1, 2), (1, 1, 0, m)] {
            assert_eq!(mul_div(a, b, add, d) as u64, reference(a, b, add, d), "{a} {b} {add} {d}");
        }
    }

    proptest! {
        #[test]
        fn mul_div_matches_u64(total in 1u32.., done in any::<u32>(), c in any::<u32>()) {
            let (done, c) = (done % (total as u64 + 1) as u32, c % (total as u64 + 1) as u32);
            prop_assert_eq!(mul_div(done, c, total / 2, total) as u64, reference(done, c, total / 2, total));
            prop_assert_eq!(mul_div(c, done, 0, total) as u64, reference(c, done, 0, total));
        }
    }
}
