//! What the engine's step half tells its ramp half: counters only the step half writes.
//!
//! Who uses it: both halves of the engine, through the shared state that holds it
//! (`motion::shared`).

use core::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize};

/// What the step half tells the ramp half: counters only the step half writes (one word each,
/// read by the ramp half against its own copies), so neither side read-modify-writes a word
/// the other writes. A move entered or ended shows in the position record's sequence
/// (`Shared::record_seq`), the running move itself in the record (`Shared::running`).
pub struct Link {
    /// Ramp milliseconds of timer time passed while stepping.
    pub(crate) ms: AtomicU32,
    /// Deceleration triggers fired, and the move the last one fired in.
    pub(crate) decel: AtomicU32,
    pub(crate) decel_in: AtomicUsize,
    /// The move a move change enters (from the last step of the one before until it is the
    /// running move; 0 otherwise): the walk is on it from then on.
    pub(crate) next: AtomicUsize,
    /// The running move's successor once the ramp half has primed it (0 or 1: none; the step
    /// half stores 1 when it enters the successor or goes idle). A ramp pass preempted across
    /// a move change can leave a stale slot here: the step half takes it only when it is the
    /// ring's slot after the running move.
    pub(crate) succ: AtomicUsize,
    /// Requests to prime the front move for a start from rest.
    pub(crate) primes: AtomicU32,
    /// The step half's feed hold.
    pub(crate) hold: AtomicBool,
    /// The ramp half's table index (Q20), for the step half's starvation count.
    pub(crate) idx: AtomicU32,
}

impl Link {
    pub(crate) const fn new() -> Self {
        Link {
            ms: AtomicU32::new(0),
            decel: AtomicU32::new(0),
            decel_in: AtomicUsize::new(0),
            next: AtomicUsize::new(0),
            succ: AtomicUsize::new(0),
            primes: AtomicU32::new(0),
            hold: AtomicBool::new(false),
            idx: AtomicU32::new(0),
        }
    }
}
