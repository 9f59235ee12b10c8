//! The step half of the engine: what the TIM2 interrupt does, one tick at a time (see the
//! parent module for the contract and the split).
//!
//! Who uses it: the firmware's TIM2 handler, and the host's `Engine`, which runs both halves.

use core::sync::atomic::Ordering::Relaxed;

use super::link::Link;
use super::ticks::{IDLE_TICKS, MAX_TICK, PRIME_TICKS};
use crate::board::PinMap;
use crate::motion::control::Ctl;
use crate::motion::prepared::{Prepared, Slave};
use crate::motion::shared::{Shared, State};
use crate::motion::ramp::{RampSlot, RAMP_LEN};
use crate::motion::ring::RingConsumer;
use crate::TICKS_PER_MS;

/// [`Link::succ`] as the step half leaves it when it enters a move or goes idle: no successor
/// primed, and never a value the ramp half last stored (so its compare-and-swap over a stale
/// view fails).
const CLEARED: usize = 1;

pub(crate) mod plain;

/// A tick whose own period (the gap from its update event to the next) is at least this (2048
/// ticks: below 35 kHz) leaves room before a direction change for the change itself: the
/// finishing step's gap is shortened by the setup.
const SHORT_GAP: u32 = 2048;

/// What the step half is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// No move loaded.
    Idle,
    /// The move after the running one starts at the next edge with its first step.
    Enter,
    /// The move after the running one starts at the next edge with its direction change,
    /// then its first step.
    Dir,
    /// Stepping.
    Run,
    /// Stopped by feed hold, move not finished.
    Held,
}

/// The step half for `N` axes.
pub struct Stepper<'a, const N: usize, const L: usize = RAMP_LEN> {
    shared: &'a Shared<N>,
    ring: RingConsumer<'a, N>,
    ramp: &'a RampSlot<L>,
    step_off: u32,
    /// Dual-edge mode: each step toggles its pin; `level` shadows the step pins' level (the
    /// pins are low when the engine is built: boot drives them low, a mode change restarts).
    dual: bool,
    level: u32,
    // The edge about to happen.
    word: u32,
    extend: u32,
    frac: u32,
    ms_left: i32,
    // The running move (a slot of the ring; valid while `phase != Idle`).
    phase: Phase,
    cur: *mut Prepared<N>,
    left: u32,
    /// This tick's own period: from its update event to the next (the previous tick's ARR); for
    /// the last piece of a split period, the whole period (so the decisions that depend on it
    /// do not depend on how a period is split).
    gap_in: u32,
    /// The whole of the period being split.
    whole: u32,
    hold: bool,
    ctl_seen: Ctl,
    /// How to ask for the ramp half's interrupt (a counter in [`Link`] moved): write `.1` to
    /// the register at `.0` (the NVIC's set-pending word for its vector); null on the host,
    /// where the host's `Engine` runs the ramp half after every tick anyway.
    pend: (*mut u32, u32),
    /// Set when a tick asked for the ramp half and no register is set to pend ([`Self::set_pend`]):
    /// the DMA burst fill runs the ramp half itself ([`crate::motion::burst`]).
    pended: bool,
    /// Longest period one event may have: [`MAX_TICK`] (the timer's 16 bits), less in DMA burst
    /// mode, where it bounds the time the buffers hold (longer periods are split into fillers).
    max_tick: u32,
    /// The next tick may be a plain step ([`Self::tick_quick`]): stepping (`phase` is `Run`)
    /// and no period being split. Set by every whole tick; only ever conservative.
    quick: bool,
    /// The DMA fill's last run of plain entries took the slave-major lane (its words are whole
    /// only at its end; [`crate::motion::burst::Burst::fill_watched`] checks DMA against its start).
    pub(crate) slave_major: bool,
}

// SAFETY: `cur` points into the ring the engine consumes; the step half is moved into the
// interrupt once and used only there.
unsafe impl<const N: usize, const L: usize> Send for Stepper<'_, N, L> {}

impl<'a, const N: usize, const L: usize> Stepper<'a, N, L> {
    pub(super) fn new(shared: &'a Shared<N>, ring: RingConsumer<'a, N>, ramp: &'a RampSlot<L>, pins: PinMap<N>) -> Self {
        Stepper {
            shared,
            ring,
            ramp,
            step_off: pins.step_off,
            dual: pins.dual,
            level: 0,
            word: 0,
            extend: 0,
            frac: 0,
            ms_left: TICKS_PER_MS as i32,
            phase: Phase::Idle,
            cur: core::ptr::null_mut(),
            left: 0,
            gap_in: 0,
            whole: 0,
            hold: false,
            ctl_seen: shared.ctl.load(),
            pend: (core::ptr::null_mut(), 0),
            pended: false,
            max_tick: MAX_TICK,
            quick: false,
            slave_major: false,
        }
    }

    /// Whether the next tick is a filler piece of an extended period (it reads nothing shared).
    pub(crate) fn filler_next(&self) -> bool {
        self.extend != 0
    }

    /// Master steps left in the running move.
    pub(super) fn left(&self) -> u32 {
        self.left
    }

    /// The BSRR word to store at this update event (precomputed by the previous tick).
    #[inline(always)]
    pub fn word(&self) -> u32 {
        self.word
    }

    /// The BSRR word for the compare event (falling step edges).
    #[inline(always)]
    pub fn step_off(&self) -> u32 {
        self.step_off
    }

    /// How to ask for the ramp half's interrupt: write `bit` to the register at `reg`.
    ///
    /// # Safety
    /// `reg` must be valid for volatile writes of `bit` whenever the step half runs, with no
    /// effect but pending the ramp half's interrupt (the NVIC's ISPR word of its vector).
    pub unsafe fn set_pend(&mut self, reg: *mut u32, bit: u32) {
        self.pend = (reg, bit);
    }

    /// Pends the ramp half's interrupt (or notes the request, with no register set).
    #[inline(always)]
    fn pend(&mut self) {
        if !self.pend.0.is_null() {
            // SAFETY: `set_pend`'s contract.
            unsafe { core::ptr::write_volatile(self.pend.0, self.pend.1) };
        } else {
            self.pended = true;
        }
    }

    /// Whether a tick asked for the ramp half since the last call (no register set).
    #[inline(always)]
    pub(crate) fn take_pended(&mut self) -> bool {
        core::mem::replace(&mut self.pended, false)
    }

    /// Longest period of one event, timer ticks (at most [`MAX_TICK`], at least 2).
    pub(crate) fn set_max_tick(&mut self, ticks: u32) {
        self.max_tick = ticks.clamp(2, MAX_TICK);
    }

    /// Computes the next edge's word; returns the ARR value to preload now.
    /// Not inlined, so the handler's own prologue stays small and the BSRR store comes first.
    /// Period extension stays off this path: only a period over 65 536 ticks (< 1.1 kHz) or
    /// its filler events take the out-of-line branch.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".data.ramfunc.tick")]
    pub fn tick(&mut self) -> u16 {
        let arr = self.whole_tick();
        self.quick = self.phase == Phase::Run && self.extend == 0;
        arr
    }

    #[inline(always)]
    fn whole_tick(&mut self) -> u16 {
        if self.extend != 0 {
            return self.filler();
        }
        let (word, ticks) = self.next_event();
        self.word = word;
        if ticks > self.max_tick {
            return self.extended(ticks);
        }
        self.elapse(ticks)
    }

    /// [`Self::tick`] with a fast path for the step interrupt: a plain step (running, no control
    /// change, neither the deceleration trigger nor the move's last step, no ramp millisecond
    /// ending, one event) takes only those checks, inline in the handler, and a call that
    /// computes it; every other tick is a whole one (no second prologue on its way). The same
    /// words and periods as `tick` (the property tests compare them).
    #[inline(always)]
    pub fn tick_quick(&mut self) -> u16 {
        if !self.quick || self.shared.ctl.load() != self.ctl_seen {
            return self.tick();
        }
        let p = self.cur;
        // SAFETY: `quick` is only set while a move runs (`cur` is its slot, see `step`).
        let (period, at) = unsafe { ((*p).period.load(Relaxed), (*p).decel_at.load(Relaxed)) };
        let left = self.left.wrapping_sub(1);
        // Past the trigger or at the last step (left ≤ at, at ≥ 0), or held to rest: a whole tick.
        if period == 0 || left <= at {
            return self.tick();
        }
        let acc = self.frac + period;
        let ms_left = self.ms_left - (acc >> 4) as i32;
        if ms_left <= 0 || acc >> 4 > self.max_tick {
            return self.tick();
        }
        self.plain_step(left, acc, ms_left)
    }

    /// The plain step [`Self::tick_quick`] found: `left` steps after it, `acc` the period's
    /// sum with the fraction, `ms_left` the millisecond's ticks after its gap.
    #[inline(never)]
    #[cfg_attr(target_os = "none", link_section = ".data.ramfunc.plain_step")]
    fn plain_step(&mut self, left: u32, acc: u32, ms_left: i32) -> u16 {
        let p = self.cur;
        let gap = acc >> 4;
        // SAFETY: as in `tick_quick`; plain fields, and the slaves only the step half touches.
        let (mut word, total, n) = unsafe { ((*p).master_on, (*p).total, (*p).n_slaves as usize) };
        // SAFETY: as above.
        word |= slave_bits(unsafe { &mut (*p).slaves }, n, total);
        if self.dual {
            word = toggle(word, &mut self.level);
        }
        self.word = word;
        self.left = left;
        self.shared.mv_done.store(total - left, Relaxed);
        self.frac = acc & 15;
        self.ms_left = ms_left;
        self.gap_in = gap;
        (gap - 1) as u16
    }

    /// A period longer than the timer holds: its first piece now, fillers for the rest.
    #[inline(never)]
    fn extended(&mut self, ticks: u32) -> u16 {
        self.extend = ticks;
        self.whole = ticks;
        self.filler_piece()
    }

    /// A filler event of an extended period: an empty word and the next piece.
    #[inline(never)]
    fn filler(&mut self) -> u16 {
        self.word = 0;
        self.filler_piece()
    }

    /// The next piece of an extended period, at most the longest period (65 536 ticks, less in
    /// DMA burst mode) and at least half of it: with the timer's 16 bits a filler never gets
    /// shorter than a real period, and a step's own first piece always holds its pulse.
    fn filler_piece(&mut self) -> u16 {
        let rem = self.extend;
        let chunk = piece(rem, self.max_tick);
        self.extend = rem - chunk;
        let arr = self.elapse(chunk);
        if self.extend == 0 {
            self.gap_in = self.whole;
        }
        arr
    }

    /// `chunk` ticks until the next update event: keeps time for the ramp; returns the ARR
    /// value.
    #[inline(always)]
    fn elapse(&mut self, chunk: u32) -> u16 {
        self.ms_left -= chunk as i32;
        if self.ms_left <= 0 {
            self.ms_left += TICKS_PER_MS as i32;
            if self.phase != Phase::Idle && self.phase != Phase::Held {
                bump(&self.link().ms);
                self.pend();
            }
        }
        self.gap_in = chunk;
        (chunk - 1) as u16
    }

    #[inline(always)]
    fn link(&self) -> &'a Link {
        &self.shared.link
    }

    /// The next edge: a step, a direction change or an idle gap, with the gap after it.
    #[inline(always)]
    fn next_event(&mut self) -> (u32, u32) {
        let ctl = self.shared.ctl.load();
        if ctl != self.ctl_seen {
            self.control(ctl);
        }
        if self.phase != Phase::Run {
            if self.phase == Phase::Enter {
                self.enter_next();
            } else if let Some(event) = self.other_event() {
                return event;
            }
        }
        self.step()
    }

    /// The next edge when not simply stepping: a move change's second half, a direction
    /// change, a hold, idle; `None` when it is a step after all (the phase is `Run` now).
    #[inline(never)]
    fn other_event(&mut self) -> Option<(u32, u32)> {
        match self.phase {
            Phase::Run => None,
            Phase::Enter => {
                self.enter_next();
                None
            }
            Phase::Dir => Some(self.dir_change()),
            Phase::Held => self.held(),
            Phase::Idle => self.refill(),
        }
    }

    /// One master step (and the slaves' share): the hot path.
    #[inline(always)]
    fn step(&mut self) -> (u32, u32) {
        let p = self.cur;
        // SAFETY: `cur` is the front slot of the ring, owned by the engine until it pops it;
        // its fields are reached through the pointer, never a reference to the whole move:
        // only its slaves are borrowed mutably (the feeder and the ramp half store its atomics).
        let mut period = unsafe { (*p).period.load(Relaxed) };
        if period == 0 {
            // The ramp half brought a hold to rest.
            return self.halt();
        }
        // SAFETY: as above; plain fields nobody writes while the move is published.
        let (mut word, total, n) = unsafe { ((*p).master_on, (*p).total, (*p).n_slaves as usize) };
        // SAFETY: as above; only the step half touches the slaves of the running move.
        word |= slave_bits(unsafe { &mut (*p).slaves }, n, total);
        if self.dual {
            word = toggle(word, &mut self.level);
        }
        self.left -= 1;
        self.shared.mv_done.store(total - self.left, Relaxed);
        // The trigger is 0 (cannot fire) until the ramp half has computed it for this move and
        // once it fired. (Not at the last step: a successor takes over the walk there, and with
        // none the move has reached its exit.)
        // SAFETY: as above; an atomic field.
        if self.left <= unsafe { (*p).decel_at.load(Relaxed) } && self.left != 0 {
            period = self.trigger();
        }
        let acc = self.frac + period;
        self.frac = acc & 15;
        let mut gap = acc >> 4;
        if self.left == 0 {
            gap = self.finish(gap, period);
        }
        (word, gap)
    }

    /// The deceleration trigger fired: the walk steps down at once, on a fresh millisecond
    /// (this step's gap already at the period one walk down, which the ramp half published with
    /// the trigger; it takes the walk from there). Returns that period.
    #[inline(never)]
    fn trigger(&mut self) -> u32 {
        // SAFETY: as in `step`; atomic fields.
        let p = self.cur;
        let period = unsafe {
            (*p).decel_at.store(0, Relaxed);
            let period = (*p).down_period.load(Relaxed);
            (*p).period.store(period, Relaxed);
            period
        };
        self.ms_left = TICKS_PER_MS as i32;
        self.link().decel_in.store(self.cur as usize, Relaxed);
        bump(&self.link().decel);
        self.pend();
        period
    }

    /// A hold came to rest: no more steps until it is released.
    #[inline(never)]
    fn halt(&mut self) -> (u32, u32) {
        self.phase = Phase::Held;
        self.publish(State::Held);
        (0, IDLE_TICKS)
    }

    /// Held: waits for the release and the ramp half's resume period; `None` once it resumes
    /// (the next edge is a step).
    fn held(&mut self) -> Option<(u32, u32)> {
        // SAFETY: as in `step`; an atomic field.
        if self.hold || unsafe { (*self.cur).period.load(Relaxed) } == 0 {
            return Some((0, if self.hold { IDLE_TICKS } else { PRIME_TICKS }));
        }
        // Resume: the ramp half restarted the walk from the bottom of the table.
        self.ms_left = TICKS_PER_MS as i32;
        self.publish(State::Run);
        self.phase = Phase::Run;
        None
    }

    /// The next move starts with its direction change, then the setup gap.
    #[inline(never)]
    fn dir_change(&mut self) -> (u32, u32) {
        self.enter_next();
        // SAFETY: as in `step`; plain fields the feeder never writes after publishing.
        unsafe { ((*self.cur).dir_word, (*self.cur).dir_setup) }
    }

    /// The move after the running one becomes the running one (the second half of a move
    /// change, on the tick after the last step: the first half found it).
    #[inline(always)]
    fn enter_next(&mut self) {
        self.ring.pop();
        let link = self.link();
        self.enter(link.next.load(Relaxed) as *mut Prepared<N>);
        link.next.store(0, Relaxed);
        // Primed for the move before: the ramp half primes this one's successor next.
        link.succ.store(CLEARED, Relaxed);
        self.phase = Phase::Run;
    }

    /// The control word changed: an immediate stop, or a feed hold on or off.
    #[inline(never)]
    fn control(&mut self, ctl: Ctl) {
        let old = core::mem::replace(&mut self.ctl_seen, ctl);
        if ctl.stopped_since(old) && self.phase != Phase::Idle {
            self.stop_move();
        }
        let hold = ctl.hold();
        if hold == self.hold {
            return;
        }
        self.hold = hold;
        self.link().hold.store(hold, Relaxed);
        self.pend();
        match self.phase {
            Phase::Run | Phase::Enter | Phase::Dir if hold => {
                // The ramp half walks down from here, on a fresh millisecond.
                self.ms_left = TICKS_PER_MS as i32;
                self.publish(State::Holding);
            }
            Phase::Run | Phase::Enter | Phase::Dir => self.publish(State::Run),
            // A resume from rest waits in `held` for the ramp half's period.
            Phase::Held | Phase::Idle => {}
        }
    }

    /// Makes `p` the running move (its steps and position record; the step path reads the
    /// rest from its slot, where the ramp half primed its period).
    #[inline(always)]
    fn enter(&mut self, p: *mut Prepared<N>) {
        self.cur = p;
        // SAFETY: a published slot, now owned by the engine; a plain field.
        self.left = unsafe { (*p).total };
        // (The position record's sequence tells the ramp half, at its next run: until then the
        // move runs on the period and trigger it primed.)
        self.shared.start_move(p as *const Prepared<N>);
    }

    /// The running move made its last step (at `period`): the next one starts at the next
    /// edge (that tick frees this move's slot and enters it), or go idle now. Returns the gap
    /// after the last step: shortened when a direction change comes first and steps are slow;
    /// at speed the change comes one whole period after the last step, since this tick's late
    /// ARR store would otherwise shorten the setup gap instead.
    #[inline(never)]
    fn finish(&mut self, gap: u32, period: u32) -> u32 {
        bump(&self.shared.moves_done);
        // The successor the ramp half primed (its period and trigger), else one queued since
        // it last ran.
        let mut p = self.link().succ.load(Relaxed) as *mut Prepared<N>;
        if (p as usize) <= CLEARED {
            p = self.unprimed(period);
            if p.is_null() {
                return self.end_of_queue(gap);
            }
        }
        // SAFETY: a published slot; plain fields and its atomics (read where needed, so the
        // common path keeps few registers).
        unsafe {
            // The rate in force from the next step on (reports, and the ramp half's own once
            // it sees the change, right after this tick).
            self.shared.period_bits.store((*p).period.load(Relaxed), Relaxed);
            self.link().next.store(p as usize, Relaxed);
            if (*p).dir_word == 0 {
                self.phase = Phase::Enter;
                return gap;
            }
        }
        self.phase = Phase::Dir;
        if self.gap_in >= SHORT_GAP {
            return self.room_for_dir(p, gap);
        }
        gap
    }

    /// Slow steps before a direction change: the change comes `dir_setup` before the next
    /// step would have (never sooner than the move's shortest gap after the last step).
    #[inline(never)]
    fn room_for_dir(&self, p: *mut Prepared<N>, gap: u32) -> u32 {
        // SAFETY: a published slot; plain fields.
        let (setup, min_gap) = unsafe { ((*p).dir_setup, (*p).min_gap) };
        gap.saturating_sub(setup).max(min_gap)
    }

    /// The running move ended with nothing queued after it: idle (at rest unless the feeder
    /// was late at speed, counted).
    #[inline(never)]
    fn end_of_queue(&mut self, gap: u32) -> u32 {
        self.ring.pop();
        if self.link().idx.load(Relaxed) != 0 && !self.hold {
            self.shared.starved.fetch_add(1, Relaxed);
        }
        self.go_idle(|p, i| p.steps[i]);
        gap
    }

    /// No successor primed: the move after the running one in the ring, if any, of this
    /// epoch, queued too late for the ramp half to prime it: the last period, never faster than
    /// that move allows, until the ramp half has seen the change (now: it computes the trigger
    /// too). Null when none.
    #[cold]
    #[inline(never)]
    fn unprimed(&mut self, period: u32) -> *mut Prepared<N> {
        let Some(p) = self.ring.second() else { return core::ptr::null_mut() };
        // SAFETY: a published slot; plain fields and an atomic.
        unsafe {
            if (*p).epoch != self.ctl_seen.epoch() {
                return core::ptr::null_mut();
            }
            if (*p).period.load(Relaxed) == 0 {
                (*p).period.store(period.max((*p).min_period.to_bits()), Relaxed);
            }
        }
        self.pend();
        p
    }

    /// An immediate stop: the running move ends where it is, each axis at the steps it made.
    #[inline(never)]
    fn stop_move(&mut self) {
        // SAFETY: the running slot; a plain field.
        let total = unsafe { (*self.cur).total };
        let done = total - self.left;
        self.ring.pop();
        self.go_idle(|p, i| {
            let made = if i == p.master as usize {
                done
            } else {
                p.slaves[..p.n_slaves as usize].iter().find(|s| s.axis as usize == i).map_or(0, |s| s.dda.made(done, total))
            };
            if p.steps[i] < 0 {
                -(made as i32)
            } else {
                made as i32
            }
        });
    }

    /// Publishes the positions after the running move (`made(move, axis)`) and goes idle.
    fn go_idle(&mut self, made: impl Fn(&Prepared<N>, usize) -> i32) {
        // SAFETY: the slot was just popped but is not reused before the producer sees the pop
        // and pushes again, which cannot happen inside this interrupt.
        let p = unsafe { &*self.cur };
        self.shared.idle_at(|i| p.start[i].wrapping_add(made(p, i)));
        self.cur = core::ptr::null_mut();
        self.left = 0;
        self.phase = Phase::Idle;
        self.shared.period_bits.store(0, Relaxed);
        self.link().next.store(0, Relaxed);
        self.link().succ.store(CLEARED, Relaxed);
        self.publish(State::Idle);
    }

    /// Loads the next move from rest, if any, once the ramp half has primed it (queue refill;
    /// never in the step path); `None` when the next edge is its first step.
    fn refill(&mut self) -> Option<(u32, u32)> {
        const WAIT: Option<(u32, u32)> = Some((0, IDLE_TICKS));
        if self.hold {
            self.publish(State::Held);
            return WAIT;
        }
        if !self.ramp.enter() {
            return WAIT;
        }
        let Some(p) = self.ring.front() else {
            self.publish(State::Idle);
            return WAIT;
        };
        // SAFETY: a published slot; plain fields and an atomic.
        let (epoch, dir, setup, primed) = unsafe { ((*p).epoch, (*p).dir_word, (*p).dir_setup, (*p).period.load(Relaxed)) };
        if epoch != self.ctl_seen.epoch() {
            self.ring.pop(); // dropped by an immediate stop
            return WAIT;
        }
        if primed == 0 {
            bump(&self.link().primes);
            self.pend();
            return Some((0, PRIME_TICKS));
        }
        self.enter(p);
        self.phase = Phase::Run;
        self.publish(State::Run);
        // The ramp's milliseconds start at the move's first step.
        self.ms_left = TICKS_PER_MS as i32;
        if dir != 0 {
            self.ms_left += setup as i32;
            Some((dir, setup))
        } else {
            None
        }
    }

    #[inline(always)]
    fn publish(&self, s: State) {
        self.shared.state.store(s as u8, Relaxed);
    }
}

/// The step bits of the slaves of a move with `n` slaves and `total` master steps, for one
/// master step: unrolled over the slots (N is a constant), stopping after the move's last
/// slave: no loop counter, no bounds checks, no branch inside a slot.
#[inline(always)]
fn slave_bits<const N: usize>(slaves: &mut [Slave; N], n: usize, total: u32) -> u32 {
    let mut bits = 0;
    macro_rules! slaves {
        ($out:lifetime; $($i:literal)*) => {$(
            if $i + 1 >= N || $i >= n {
                break $out;
            }
            let s = &mut slaves[$i];
            bits |= s.on & s.dda.step_mask(total);
        )*};
    }
    'slaves: {
        slaves!('slaves; 0 1 2 3 4 5);
    }
    bits
}

/// Dual-edge mode: the BSRR word that toggles the pins of `word`, given their `level` (set
/// those that are low, reset those that are high); `level` follows.
#[inline(always)]
fn toggle(word: u32, level: &mut u32) -> u32 {
    let old = *level;
    *level = old ^ word;
    (word & !old) | (word & old) << 16
}

/// The piece of a `rem`-tick period an event takes when events are at most `max` ticks: all
/// of it, else `max`, else half of `max` (so the last piece is at least half of `max`).
#[inline(always)]
fn piece(rem: u32, max: u32) -> u32 {
    if rem <= max {
        rem
    } else if rem >= max + max / 2 {
        max
    } else {
        max / 2
    }
}

/// One more on a counter only the step half writes (no read-modify-write race: every other
/// context only reads it).
#[inline(always)]
fn bump(c: &core::sync::atomic::AtomicU32) {
    c.store(c.load(Relaxed).wrapping_add(1), Relaxed);
}
