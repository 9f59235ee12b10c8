//! A prepared move: everything the step interrupt needs, computed by the feeder outside it.
//!
//! Who uses it: the feeder builds one per move ([`Prepared::new`]) and publishes it in the
//! ring; the engine runs it in place. The interrupt never searches, divides or loops over
//! axes to start a move: the slaves' DDA start, the direction word (and so whether a
//! direction-setup gap is due), the ramp positions and the step timing are all here.
//!
//! Ramp positions are Q20 indices into the one ramp table, which is in *path* units: the
//! table's rate `T` is the path speed times `per_mm` (the profile's steps per mm), the same
//! for every move, so the index at a junction means the same speed on both sides and carries
//! over from move to move. The move's master runs at `T / scale` (Q16: the share of the
//! path speed its master sees; ≥ 1 unless the table's units are coarser than the finest
//! axis, `Settings::per_mm`) and walks `walk_q / 2^20` entries per ms (its
//! own acceleration as a fraction of the table's).

use core::sync::atomic::AtomicU32;

use crate::board::PinMap;
use crate::motion::interp::Dda;
use crate::motion::moves::Rates;
use crate::motion::ramp::Period;
use crate::motion::timing::{Timing, STORE_JITTER_TICKS};

/// One slave axis of a move.
#[derive(Clone, Copy, Debug)]
pub struct Slave {
    pub(crate) dda: Dda,
    pub(crate) on: u32,
    pub(crate) axis: u8,
}

/// Where a move runs on the ramp table (all indices Q20).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RampPlan {
    /// Highest index the move accelerates to (its cruise).
    pub cruise_q: u32,
    /// Index to end at when a successor is queued (otherwise 0: a stop).
    pub exit_q: u32,
    /// Entries per ms, Q20 (≤ 1 entry).
    pub walk_q: u32,
    /// Master period = table period × `scale` / 2^16.
    pub scale: u32,
    /// Master steps per table distance unit (1/256 step) at this walk rate, Q24:
    /// `scale⁻¹ / walk`, so a deceleration from `a` to `b` takes
    /// `(sum(a) − sum(b)) · dist_q / 2^24` master steps.
    pub dist_q: u32,
    /// Master period at cruise (the move's own rate, which the table may not hold exactly).
    pub cruise: Period,
}

impl RampPlan {
    /// A move whose master is the table (scale 1, full walk rate) cruising at `cruise`, from
    /// and to a stop: the seed paper's single move.
    pub const fn lone(cruise_q: u32, cruise: Period) -> Self {
        RampPlan { cruise_q, exit_q: 0, walk_q: crate::motion::ramp::IDX_ONE, scale: 1 << 16, dist_q: 1 << 16, cruise }
    }
}

/// A move ready for the step interrupt.
#[derive(Debug)]
pub struct Prepared<const N: usize> {
    // The step path.
    pub(crate) total: u32,
    pub(crate) master_on: u32,
    pub(crate) n_slaves: u8,
    pub(crate) master: u8,
    pub(crate) slaves: [Slave; N],
    // The ramp.
    pub(crate) ramp: RampPlan,
    /// The feeder raises this (from `ramp.exit_q`) while the move is the last one queued.
    pub(crate) exit_q: AtomicU32,
    /// The cruise under the overrides in force (index Q20, floor period bits): the feeder
    /// stores the index, then the floor (release), when an override changes; the engine reads
    /// both once per ramp millisecond in its interrupt, where the feeder cannot run between the
    /// two loads, so at worst it pairs a new index with the old floor (harmless: the floor only
    /// holds at or below the index), never a new floor with an old index.
    pub(crate) cruise_q: AtomicU32,
    pub(crate) cruise_bits: AtomicU32,
    pub(crate) min_period: Period,
    /// The engine's ramp half: the master period at the walk's index (bits; 0 until primed,
    /// and while a hold rests), and the deceleration trigger (master steps left; 0: cannot
    /// fire, not computed yet or fired).
    pub(crate) period: AtomicU32,
    pub(crate) decel_at: AtomicU32,
    /// The period one walk down from the index the trigger was computed at (bits): the
    /// trigger's own step runs at it.
    pub(crate) down_period: AtomicU32,
    /// The feeder's: how overrides scale the cruise.
    pub(crate) rates: Rates,
    // Edges.
    /// Direction pins to change before the first step (0: none, no setup gap).
    pub(crate) dir_word: u32,
    pub(crate) dir_setup: u32,
    /// Shortest gap between two edges (the pulse and its low time, a step tick's cost).
    pub(crate) min_gap: u32,
    // The position record.
    pub(crate) start: [i32; N],
    pub(crate) steps: [i32; N],
    pub(crate) epoch: u32,
}

/// Direction pins as the feeder last left them (per axis: known, negative).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DirState {
    known: u32,
    neg: u32,
}

impl DirState {
    /// Nothing known (after boot or an immediate stop): the next move sets every pin it uses.
    pub const UNKNOWN: DirState = DirState { known: 0, neg: 0 };
}

impl<const N: usize> Prepared<N> {
    /// Prepares `steps` (signed, master `master`) starting at absolute `start`, for the pins,
    /// timing and ramp plan given (priced for the overrides in force from `rates`); `dir` is
    /// updated to the pins after this move.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        steps: [i32; N],
        master: usize,
        start: [i32; N],
        ramp: RampPlan,
        rates: Rates,
        timing: &Timing,
        pins: &PinMap<N>,
        dir: &mut DirState,
        epoch: u32,
    ) -> Self {
        // (`get`, not indexing, here and below: `master` and the slave count stay below `N`,
        // and the feeder's code then has no bounds-check panic path.)
        let total = steps.get(master).map_or(0, |s| s.unsigned_abs());
        // Slots from `n_slaves` on stay as here (count 0, no pins): the DMA fill walks slot
        // `n_slaves` alongside the last slave when that saves a pass (it never steps).
        let mut slaves = [Slave { dda: Dda::new(0, 0), on: 0, axis: 0 }; N];
        let mut n = 0;
        let mut dir_word = 0;
        // (Each axis's pin words zipped in, not indexed: no bounds-check paths.)
        let words = pins.step_on.iter().zip(pins.dir_neg.iter().zip(&pins.dir_pos));
        for (i, (&s, (&on, (&dir_neg, &dir_pos)))) in steps.iter().zip(words).enumerate() {
            if s == 0 {
                continue;
            }
            let neg = (s < 0) as u32;
            if dir.known >> i & 1 == 0 || dir.neg >> i & 1 != neg {
                dir_word |= if neg == 1 { dir_neg } else { dir_pos };
                dir.neg = (dir.neg & !(1 << i)) | neg << i;
                dir.known |= 1 << i;
            }
            if i != master {
                if let Some(slave) = slaves.get_mut(n) {
                    *slave = Slave { dda: Dda::new(s.unsigned_abs(), total), on, axis: i as u8 };
                }
                n += 1;
            }
        }
        let t = match *timing {
            Timing::UNSET => Timing::DEFAULT,
            t => t,
        };
        Prepared {
            total,
            master_on: pins.step_on.get(master).copied().unwrap_or(0),
            n_slaves: n as u8,
            master: master as u8,
            slaves,
            ramp,
            exit_q: AtomicU32::new(ramp.exit_q),
            cruise_q: AtomicU32::new(ramp.cruise_q),
            cruise_bits: AtomicU32::new(ramp.cruise.to_bits()),
            min_period: Period::from_bits(t.min_period_for(n as u32).saturating_mul(16)),
            period: AtomicU32::new(0),
            decel_at: AtomicU32::new(0),
            down_period: AtomicU32::new(0),
            rates,
            dir_word,
            // Both gaps hold a step tick of this move (its handler cost, as its periods do).
            dir_setup: (t.dir_setup_ticks + STORE_JITTER_TICKS).max(t.min_period_for(n as u32)),
            min_gap: t.min_period_for(n as u32),
            start,
            steps,
            epoch,
        }
    }

    /// Signed steps per axis.
    pub fn steps(&self) -> &[i32; N] {
        &self.steps
    }

    /// The ramp plan.
    pub fn ramp(&self) -> &RampPlan {
        &self.ramp
    }
}
