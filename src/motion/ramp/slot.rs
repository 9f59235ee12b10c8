//! The profile (ramp table and step timing) shared lock-free between the settings code,
//! which rebuilds it, and the engine, which reads it while moves run.
//!
//! Who uses it: the settings ([`RampSlot::try_write`]), the feeder ([`RampSlot::producer_view`])
//! and the engine ([`RampSlot::enter`], [`RampSlot::profile`]).

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, Ordering};

use super::scurve::SCurve;
use super::table::{RampTable, RAMP_LEN};
use crate::motion::timing::Timing;

/// What the engine reads from settings: the ramp table and the step timing.
pub struct Profile<const L: usize = RAMP_LEN> {
    pub ramp: RampTable<L>,
    pub timing: Timing,
    /// Table rate per mm/s of path speed (`Settings::per_mm`: steps/mm of the finest axis, or
    /// fewer where the table's top needs it): a move whose master
    /// makes `share` steps per mm of path runs at `share / per_mm` of the table's rate. Zero
    /// (not set) means table rates are master rates.
    pub per_mm: f32,
    /// The S-curve each ramp leg follows (`$41=1`; off: the trapezoid).
    pub scurve: SCurve,
}

/// The profile shared between the step interrupt (reader) and the settings code (writer)
/// without locks: the writer asks, the engine parks between moves, the writer rebuilds.
///
/// Protocol: [`RampSlot::try_write`] raises `writer`; the engine, which reads the table only
/// while a move runs, sees the flag when it would load the next move, clears `reading` and
/// loads nothing; once it is not reading the writer gets the table, and dropping the guard
/// lowers `writer`. (Both flags start false, so the slot lives in .bss, not 4 KiB of .data.)
pub struct RampSlot<const L: usize = RAMP_LEN> {
    table: UnsafeCell<Profile<L>>,
    writer: AtomicBool,
    reading: AtomicBool,
}

// SAFETY: the table is read only by the engine while `writer` is low (checked before each
// move starts) and written only through a guard that exists only while the engine is parked.
unsafe impl<const L: usize> Sync for RampSlot<L> {}

impl<const L: usize> Default for RampSlot<L> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const L: usize> RampSlot<L> {
    /// An empty slot; the engine starts parked, so the first write needs no handshake.
    pub const fn new() -> Self {
        RampSlot {
            // Zero timing keeps the slot in .bss; the engine reads it as `Timing::DEFAULT`.
            table: UnsafeCell::new(Profile { ramp: RampTable::new(), timing: Timing::UNSET, per_mm: 0.0, scurve: SCurve::OFF }),
            writer: AtomicBool::new(false),
            reading: AtomicBool::new(false),
        }
    }

    /// Writer side: the table, if the engine is parked; otherwise asks it to park and returns
    /// `None` (try again after the running move ends).
    pub fn try_write(&self) -> Option<RampWriteGuard<'_, L>> {
        self.writer.store(true, Ordering::SeqCst);
        if !self.reading.load(Ordering::SeqCst) {
            Some(RampWriteGuard { slot: self })
        } else {
            None
        }
    }

    /// Engine side: may a move start now? Parks (and says no) while a writer waits.
    #[inline]
    pub(crate) fn enter(&self) -> bool {
        if self.writer.load(Ordering::SeqCst) {
            self.reading.store(false, Ordering::SeqCst);
            false
        } else {
            self.reading.store(true, Ordering::SeqCst);
            true
        }
    }

    /// Producer side (the feeder that prepares moves): the table, read in the same context
    /// that holds the writer, so never while a write guard lives.
    pub(crate) fn producer_view(&self) -> &Profile<L> {
        // SAFETY: the feeder and the settings writer run in one context (the controller), so
        // no guard exists while this reference is used; the engine only reads.
        unsafe { &*self.table.get() }
    }

    /// Engine side: the table, valid from a successful [`Self::enter`] to the move's end.
    #[inline(always)]
    pub(crate) fn profile(&self) -> &Profile<L> {
        // SAFETY: called only by the engine between `enter() == true` and the next `enter`,
        // during which no write guard can exist (see the type's protocol).
        unsafe { &*self.table.get() }
    }
}

/// Exclusive access to the table while the engine is parked.
pub struct RampWriteGuard<'a, const L: usize> {
    slot: &'a RampSlot<L>,
}

impl<const L: usize> core::ops::Deref for RampWriteGuard<'_, L> {
    type Target = Profile<L>;
    fn deref(&self) -> &Profile<L> {
        // SAFETY: the guard exists only while the engine is parked (no reader).
        unsafe { &*self.slot.table.get() }
    }
}

impl<const L: usize> core::ops::DerefMut for RampWriteGuard<'_, L> {
    fn deref_mut(&mut self) -> &mut Profile<L> {
        // SAFETY: as above, and `&mut self` makes this the only writer.
        unsafe { &mut *self.slot.table.get() }
    }
}

impl<const L: usize> Drop for RampWriteGuard<'_, L> {
    fn drop(&mut self) {
        self.slot.writer.store(false, Ordering::SeqCst);
    }
}
