//! The state shared lock-free between the step interrupt and everything else (atomics only):
//! the position record (a sequence lock), the engine's state, the control word, the override
//! percentages, the probe cycle, and the engine's own step-to-ramp link.
//!
//! Who uses it: the engine writes it; the feeder, the controller, status reports and the
//! shell's interrupts read it or post requests (hold, stop, overrides, probe).
//!
//! Invariant: an immediate stop (the feeder's `abort`, [`Shared::stop_now`]) bumps an epoch in
//! the control word; the engine drops the running move at its next tick and every queued move
//! stamped with an older epoch when it reaches it (one per tick, so the interrupt never loops
//! over the queue).

use core::sync::atomic::{fence, AtomicI32, AtomicU32, AtomicU8, AtomicUsize, Ordering::{Acquire, Relaxed, Release}};

use crate::motion::control::Control;
use crate::motion::engine::link::Link;
use crate::motion::moves::Overrides;
use crate::motion::prepared::Prepared;
use crate::num::mul_div;

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
    pub(crate) link: Link,
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
            link: Link::new(),
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

    /// Current master step rate in steps/s: 0 whenever no step is coming (idle, or a feed
    /// hold at rest, where the engine keeps the period it stopped at for the resume), as
    /// Grbl's `st_get_realtime_rate`. (Inlined into the status report and laser power, as it
    /// was before the state check: the flash code after them keeps its address mod 8.)
    #[inline(always)]
    pub fn rate_hz(&self) -> u32 {
        match self.period_bits.load(Relaxed) {
            b if b != 0 && matches!(self.state(), State::Run | State::Holding) => ((crate::TIMER_HZ as u64 * 16) / b as u64) as u32,
            _ => 0,
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

