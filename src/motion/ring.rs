//! The ring of prepared moves between the feeder (producer, thread mode) and the step engine
//! (consumer, TIM2 interrupt): single producer, single consumer, lock-free.
//!
//! Unlike a plain queue, the consumer runs a move *in its slot* (its DDA accumulators live
//! there) and releases the slot only when the move ends, so a move change costs the interrupt
//! a pointer, not a copy. The producer may still raise the exit speed of the last move it
//! pushed (its atomic `exit_q`, through [`RingProducer::set_last_exit`]) before it publishes
//! the next one.
//!
//! Invariant: slots `head..tail` (mod [`RING`]) hold published moves; the producer writes only
//! slot `tail` and publishes it with a release store of `tail`; the consumer reads only
//! published slots and frees the oldest with a release store of `head`.

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicU32, Ordering::{Acquire, Relaxed, Release}};

use crate::motion::prepared::Prepared;

/// Prepared moves the ring holds (a power of two). The look-ahead keeps its own, longer
/// buffer of moves not yet prepared; this only needs to cover the feeder's poll interval.
pub const RING: usize = 8;
const _: () = assert!(RING.is_power_of_two());

/// The ring's storage (a `static` in the firmware).
pub struct MoveRing<const N: usize> {
    slots: [UnsafeCell<MaybeUninit<Prepared<N>>>; RING],
    head: AtomicU32,
    tail: AtomicU32,
}

// SAFETY: slots are shared under the protocol above (one writer per slot at a time, published
// with release/acquire); only the producer and consumer handles touch them.
unsafe impl<const N: usize> Sync for MoveRing<N> {}

impl<const N: usize> Default for MoveRing<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> MoveRing<N> {
    /// An empty ring (all zero: lives in .bss).
    pub const fn new() -> Self {
        MoveRing {
            slots: [const { UnsafeCell::new(MaybeUninit::uninit()) }; RING],
            head: AtomicU32::new(0),
            tail: AtomicU32::new(0),
        }
    }

    /// The two ends; the `&mut` makes sure there is one of each.
    pub fn split(&mut self) -> (RingProducer<'_, N>, RingConsumer<'_, N>) {
        let ring: &Self = self;
        (RingProducer { ring }, RingConsumer { ring })
    }

    fn slot(&self, i: u32) -> *mut Prepared<N> {
        self.slots[i as usize & (RING - 1)].get().cast()
    }
}

/// Producer end.
pub struct RingProducer<'a, const N: usize> {
    ring: &'a MoveRing<N>,
}

impl<const N: usize> RingProducer<'_, N> {
    /// Moves published and not yet finished (the running one included). (Out of line: the
    /// feeder asks in several places; the engine holds the consumer end.)
    #[inline(never)]
    pub fn len(&self) -> usize {
        self.ring.tail.load(Relaxed).wrapping_sub(self.ring.head.load(Acquire)) as usize
    }

    /// True when nothing is published.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Publishes a move; gives it back when the ring is full.
    pub fn push(&mut self, mv: Prepared<N>) -> Result<(), Prepared<N>> {
        if self.len() >= RING {
            return Err(mv);
        }
        let t = self.ring.tail.load(Relaxed);
        // SAFETY: slot `tail` is not published, so the consumer does not touch it.
        unsafe { self.ring.slot(t).write(mv) };
        self.ring.tail.store(t.wrapping_add(1), Release);
        Ok(())
    }

    /// The published moves, oldest first (the running one included), as raw slots: the
    /// producer may read the plain fields it wrote and store the atomic ones, never through a
    /// reference to a move (the engine runs the oldest in place). A slot the engine frees
    /// meanwhile keeps its contents until the producer pushes again.
    pub fn slots(&self) -> impl Iterator<Item = *const Prepared<N>> + '_ {
        let h = self.ring.head.load(Acquire);
        let n = self.ring.tail.load(Relaxed).wrapping_sub(h);
        (0..n).map(move |k| self.ring.slot(h.wrapping_add(k)) as *const Prepared<N>)
    }

    /// Raises (or sets) the exit index of the last published move, if it is still in the
    /// ring; call before publishing its successor.
    pub fn set_last_exit(&mut self, exit_q: u32) {
        if self.is_empty() {
            return;
        }
        let t = self.ring.tail.load(Relaxed).wrapping_sub(1);
        // SAFETY: the slot is published and not freed (or freed and unused: the store is then
        // harmless); only its atomic field is touched, never through a reference to the move.
        unsafe { (*core::ptr::addr_of!((*self.ring.slot(t)).exit_q)).store(exit_q, Relaxed) };
    }
}

/// Consumer end (the step engine).
pub struct RingConsumer<'a, const N: usize> {
    ring: &'a MoveRing<N>,
}

impl<'a, const N: usize> RingConsumer<'a, N> {
    /// A second, read-only view of the consumer's end (the engine's ramp half).
    pub fn peek(&self) -> RingPeek<'a, N> {
        RingPeek { ring: self.ring }
    }

    /// The oldest published move, if any; it stays in the ring until [`Self::pop`].
    #[inline(always)]
    pub fn front(&self) -> Option<*mut Prepared<N>> {
        let h = self.ring.head.load(Relaxed);
        if self.ring.tail.load(Acquire) == h {
            None
        } else {
            Some(self.ring.slot(h))
        }
    }

    /// The move published after the front one, if any.
    #[inline(always)]
    pub fn second(&self) -> Option<*mut Prepared<N>> {
        let h = self.ring.head.load(Relaxed);
        if self.ring.tail.load(Acquire).wrapping_sub(h) >= 2 {
            Some(self.ring.slot(h.wrapping_add(1)))
        } else {
            None
        }
    }

    /// Frees the front slot (its move is finished or dropped).
    #[inline(always)]
    pub fn pop(&mut self) {
        let h = self.ring.head.load(Relaxed);
        self.ring.head.store(h.wrapping_add(1), Release);
    }
}

/// A read-only view of the consumer's end for the engine's ramp half, which runs in a lower-priority
/// interrupt than the consumer: the slots it reads stay as they are until the producer, which
/// runs below both, pushes again.
pub struct RingPeek<'a, const N: usize> {
    ring: &'a MoveRing<N>,
}

impl<const N: usize> RingPeek<'_, N> {
    /// The oldest published move, if any.
    #[cfg_attr(target_os = "none", link_section = ".fill.front")]
    pub fn front(&self) -> Option<*const Prepared<N>> {
        self.nth(0)
    }

    /// The `k`-th published move after the oldest, if any.
    #[cfg_attr(target_os = "none", link_section = ".fill.nth")]
    pub fn nth(&self, k: u32) -> Option<*const Prepared<N>> {
        let h = self.ring.head.load(Acquire);
        (self.ring.tail.load(Acquire).wrapping_sub(h) > k).then(|| self.ring.slot(h.wrapping_add(k)) as *const Prepared<N>)
    }
}
