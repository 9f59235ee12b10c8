//! The feeder: the producer side of the move ring. It keeps the look-ahead buffer, replans it
//! as moves arrive, and prepares moves for the step interrupt just in time.
//!
//! Who uses it: the controller (one [`Feeder::push`] per planned move, [`Feeder::service`] at
//! every poll) and host rigs.
//!
//! Just in time: a move leaves the look-ahead (where later moves can still raise its speeds)
//! only when the engine needs it: when the engine has less than [`HORIZON_US`] of motion
//! prepared before the stop it plans at the end of what it has (the last move's stopping
//! distance from the highest index it can reach does not count: inside it the engine would
//! already hold or lose speed, a dip at the junction), or fewer than two moves, or the buffer
//! is full. When it hands a move over, it first raises the exit of the last prepared move to
//! the new move's entry, then publishes the new move; until then the engine plans that last
//! move's exit as a stop. So the engine never runs out of moves at speed: at worst it slows to
//! rest at the end of what it has.
//!
//! Overrides (Grbl's feed and rapid): when one changes, every queued move gets its new cruise
//! (as Grbl recomputes its plan). A prepared move gets its new cruise index and floor in its
//! slot, which the engine reads at its next ramp millisecond and walks to at the move's own
//! acceleration; the buffered moves are priced again and replanned. Exits already handed over
//! stay: they are junction and stopping limits, which no override changes (a move whose new
//! cruise is below its exit leaves at its cruise).

use crate::board::PinMap;
use crate::planning::lookahead::{cruise_for, reach, replan, Block, Buffer, Tail, LOOKAHEAD};
use crate::motion::prepared::{DirState, Prepared};
use crate::motion::moves::{Move, Overrides};
use crate::motion::shared::{Shared, State};
use crate::motion::ramp::RampSlot;
use crate::motion::ring::{RingProducer, RING};
use core::sync::atomic::Ordering::{Relaxed, Release};

/// Motion the feeder keeps prepared ahead of the engine, µs (several poll intervals).
pub const HORIZON_US: u32 = 8_000;

/// Producer side of the move queue.
pub struct Feeder<'a, const N: usize> {
    ring: RingProducer<'a, N>,
    shared: &'a Shared<N>,
    slot: &'a RampSlot,
    pins: PinMap<N>,
    /// The look-ahead buffer, oldest first.
    blocks: &'a mut Buffer<N>,
    /// The last move handed to the engine (for the forward pass).
    tail: Option<Tail>,
    dir: DirState,
    /// Absolute position after the last move handed over.
    pos: [i32; N],
    resync: bool,
    accepted: u32,
    /// The overrides the queued moves are priced for.
    ovr: Overrides,
}

impl<'a, const N: usize> Feeder<'a, N> {
    /// A feeder at the engine's current position.
    pub fn new(
        ring: RingProducer<'a, N>,
        blocks: &'a mut Buffer<N>,
        shared: &'a Shared<N>,
        slot: &'a RampSlot,
        pins: PinMap<N>,
    ) -> Self {
        blocks.clear();
        Feeder {
            ring,
            shared,
            slot,
            pins,
            blocks,
            tail: None,
            dir: DirState::UNKNOWN,
            pos: shared.positions(),
            resync: false,
            accepted: shared.moves_done(),
            ovr: Overrides::NONE,
        }
    }

    /// Takes a move into the look-ahead; gives it back when the buffer is full (or the engine
    /// is still stopping after an abort).
    /// The look-ahead buffer is full: [`Self::push`] would fail until the engine takes a move.
    pub fn full(&self) -> bool {
        self.blocks.is_full()
    }

    pub fn push(&mut self, mv: Move<N>) -> Result<(), Move<N>> {
        if !self.synced() {
            return Err(mv);
        }
        self.sync_overrides();
        if self.blocks.is_full() {
            self.service();
            if self.blocks.is_full() {
                return Err(mv);
            }
        }
        let profile = self.slot.producer_view();
        let joins = !(self.blocks.is_empty() && self.ring.is_empty());
        let block = Block::new(mv, profile, joins, self.ovr);
        if self.blocks.push_back(block).is_err() {
            return Err(mv); // unreachable: checked above
        }
        self.accepted = self.accepted.wrapping_add(1);
        self.replan();
        self.service();
        Ok(())
    }

    /// Hands moves to the engine as it needs them (call at every poll).
    pub fn service(&mut self) {
        if !self.synced() {
            return;
        }
        self.sync_overrides();
        while !self.blocks.is_empty() && self.ring.len() < RING {
            let must = self.blocks.is_full() || self.ring.len() < 2 || self.horizon_us() < HORIZON_US;
            if !must {
                break;
            }
            self.commit();
        }
    }

    /// Moves queued (in the look-ahead or the ring) or running.
    pub fn pending(&self) -> u32 {
        self.accepted.wrapping_sub(self.shared.moves_done())
    }

    /// Moves the look-ahead and the ring hold at most.
    pub fn capacity(&self) -> usize {
        LOOKAHEAD + RING
    }

    /// True when another move fits.
    pub fn ready(&self) -> bool {
        !self.blocks.is_full()
    }

    /// Immediate stop: the running move ends at the next tick and every queued one is dropped.
    /// Positions stay equal to the pulses emitted.
    pub fn abort(&mut self) {
        self.shared.ctl.stop();
        self.blocks.clear();
        self.tail = None;
        self.dir = DirState::UNKNOWN;
        self.resync = true;
        // Dropped moves never count as done; forget them here.
        self.accepted = self.shared.moves_done();
    }

    /// A new pin map (at rest: `$2`, `$3`, `$580`): the next move writes every direction pin.
    pub fn set_pins(&mut self, pins: PinMap<N>) {
        self.pins = pins;
        self.dir = DirState::UNKNOWN;
    }

    /// Sets positions while idle (G92): the engine's record and the next move's start.
    pub fn set_positions(&mut self, p: [i32; N]) {
        self.shared.set_positions(p);
        self.pos = p;
    }

    /// After an abort: true once the engine has stopped (positions are final).
    fn synced(&mut self) -> bool {
        if self.resync && self.shared.state() == State::Idle {
            self.pos = self.shared.positions();
            self.accepted = self.shared.moves_done();
            self.resync = false;
        }
        !self.resync
    }

    fn replan(&mut self) {
        let tail = if self.ring.is_empty() { None } else { self.tail };
        let (front, back) = self.blocks.as_mut_slices();
        replan(front, back, tail.as_ref(), &self.slot.producer_view().ramp);
    }

    /// Prepares the oldest buffered move and publishes it.
    /// (No replan here: handing over the front block leaves the plan of the rest as it was.)
    fn commit(&mut self) {
        // (Read in place and dropped at the end: no copy of the block.)
        let Some(b) = self.blocks.front() else { return };
        let profile = self.slot.producer_view();
        let mut ramp = b.ramp;
        ramp.exit_q = b.exit_q;
        let start = self.pos;
        let steps = b.mv.steps;
        let p = Prepared::new(steps, b.mv.master as usize, start, ramp, b.mv.rates(), &profile.timing, &self.pins, &mut self.dir, self.shared.epoch());
        // The last prepared move may now run through into this one.
        self.ring.set_last_exit(b.entry_q);
        let tail = b.tail();
        self.blocks.pop_front();
        if self.ring.push(p).is_err() {
            return; // unreachable: the caller checked for room
        }
        for (q, s) in self.pos.iter_mut().zip(steps) {
            *q = q.wrapping_add(s);
        }
        self.tail = Some(tail);
    }

    /// An override changed: prices every queued move again (see the module docs).
    fn sync_overrides(&mut self) {
        let o = self.shared.overrides();
        if o == self.ovr {
            return;
        }
        self.ovr = o;
        let profile = self.slot.producer_view();
        for p in self.ring.slots() {
            // SAFETY: a published slot (or one just freed, not yet rewritten): plain fields the
            // engine never writes, and its atomics.
            let q = unsafe {
                let (cruise, q) = cruise_for(&(*p).rates, o, (*p).ramp.scale, (*p).min_period.to_bits(), &profile.ramp);
                (*p).cruise_q.store(q, Relaxed);
                (*p).cruise_bits.store(cruise.to_bits(), Release);
                q
            };
            if let Some(t) = self.tail.as_mut() {
                t.cruise_q = q; // the last one's stays
            }
        }
        for b in self.blocks.iter_mut() {
            b.price(profile, o);
        }
        self.replan();
    }

    /// Estimated motion the engine has left at cruise before it must start to stop at the end
    /// of what it has, µs (counted only up to [`HORIZON_US`]): the last move's stopping
    /// distance from the highest index it can reach does not count (the engine plans its exit
    /// as a stop, and inside that distance neither accelerates nor holds its speed; the moves
    /// before it have their exits).
    fn horizon_us(&self) -> u32 {
        let made = self.shared.mv_done.load(Relaxed);
        let last = self.ring.len().wrapping_sub(1);
        let mut us = 0u32;
        for (k, p) in self.ring.slots().enumerate() {
            // SAFETY: as in `sync_overrides`.
            let (total, bits, dist_q) = unsafe { ((*p).total, (*p).cruise_bits.load(Relaxed).max((*p).min_period.to_bits()), (*p).ramp.dist_q) };
            // The running move (the oldest) counts what it has left.
            let mut left = if k == 0 { total.saturating_sub(made) } else { total };
            if let (true, Some(t)) = (k == last, self.tail) {
                let table = &self.slot.producer_view().ramp;
                let top = reach(table, t.entry_q, t.budget).min(t.cruise_q);
                left = left.saturating_sub(((table.sum_at(top) as u64 * dist_q as u64) >> 24) as u32);
            }
            us = us.saturating_add(crate::num::u32_of(left as f32 * bits as f32 * (1e6 / 16.0 / crate::TIMER_HZ as f32)));
            if us >= HORIZON_US {
                break;
            }
        }
        us
    }
}
