//! Look-ahead: junction speeds for a chain of moves, mapped onto the ramp table (Grbl's idea).
//!
//! Who uses it: the feeder, which keeps the moves not yet handed to the engine here and
//! replans them whenever one arrives.
//!
//! Every speed is a Q20 index into the one ramp table (the table is in path units: see
//! [`crate::prepared`]), and every distance is in the table's own distance sums, so planning
//! is table lookups and one binary search per bound, whatever the table's shape. Per move:
//! - its walk rate is its path acceleration (the smallest `$120+i / |unitᵢ|` over the axes it
//!   moves) as a fraction of the table's;
//! - its budget is the table distance it can cover walking at that rate in its own length;
//! - its entry is capped by the junction speed from junction deviation `$11`
//!   (`v² = a·δ·sin(θ/2)/(1 − sin(θ/2))`, `a` the largest acceleration the axes allow along
//!   the change of direction) and by both moves' nominal speeds.
//!
//! The reverse pass starts from rest after the last buffered move and lowers each entry to
//! what its move can still stop from; the forward pass starts from the last move already
//! handed to the engine and lowers each exit to what its move can reach. So the buffer always
//! ends at rest, and a starved buffer never means an abrupt stop from speed.

use crate::num::u32_of;
use crate::prepared::RampPlan;
use crate::queue::Move;
use crate::ramp::{Profile, RampTable, IDX_ONE};
use crate::timing::Timing;
use crate::walk::DECEL_MARGIN;

/// Moves the look-ahead buffers (beyond the few already prepared in the engine's ring).
pub const LOOKAHEAD: usize = 16;

/// The look-ahead buffer's storage (a `static` in the firmware, so the feeder holds a
/// reference and no 2 KiB value moves over the stack at boot).
pub type Buffer<const N: usize> = heapless::Deque<Block<N>, LOOKAHEAD>;

/// One buffered move with its plan.
#[derive(Clone, Copy, Debug)]
pub struct Block<const N: usize> {
    pub mv: Move<N>,
    /// Ramp plan except the exit (set by the passes).
    pub ramp: RampPlan,
    /// Table distance the move covers at its walk rate (1/256 step of the table).
    pub budget: u32,
    /// Highest entry the junction and the nominal speeds allow.
    pub max_entry_q: u32,
    /// Highest entry the moves after it allow (reverse pass; kept to stop early).
    pub rev_entry_q: u32,
    /// Planned entry and exit.
    pub entry_q: u32,
    pub exit_q: u32,
    /// Estimated duration at cruise, µs (for the feeder's horizon).
    pub est_us: u32,
}

/// What the passes need of the last move handed to the engine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tail {
    pub entry_q: u32,
    pub budget: u32,
    pub cruise_q: u32,
}

impl<const N: usize> Block<N> {
    /// Plans `mv` on `table` (`per_mm`: table rate per mm/s of path; 0 if the table is in
    /// master steps); `joins` when a move runs before it (else it starts from rest).
    pub fn new<const L: usize>(mv: Move<N>, profile: &Profile<L>, joins: bool) -> Self {
        // f64 arithmetic (the inputs are stored as f32): the firmware links f64 soft float for the
        // planner anyway, and f32 arithmetic here would add a second set (~2 KB of flash).
        let (table, per_mm) = (&profile.ramp, profile.per_mm as f64);
        let total = mv.steps[mv.master as usize].unsigned_abs();
        // The cruise the engine will hold: the move's own, at most the step timing's ceiling.
        let timing = match profile.timing {
            Timing::UNSET => Timing::DEFAULT,
            t => t,
        };
        let slaves = mv.steps.iter().filter(|s| **s != 0).count().saturating_sub(1) as u32;
        let cruise_hz = (crate::ramp::hz_of_period(mv.cruise) as f64).min(timing.max_rate_for(slaves) as f64);
        let t_accel = table.config().accel.max(1) as f64;
        // `per_mm > 0.0` on the f32's bits (positive: 1 ..= +inf): LLVM would narrow an f64 compare of
        // a widened f32 back to an f32 one and link the f32 compare routines for it.
        let positive = (1..=0x7F80_0000).contains(&profile.per_mm.to_bits());
        let (ramp, budget, max_entry_q, est_us) = match (&mv.path, positive) {
            (Some(p), true) => {
                let s = (p.share as f64 / per_mm).clamp(1e-6, 1.0);
                let r = (p.accel as f64 * per_mm / t_accel).clamp(0.0, 1.0);
                let walk_q = u32_of(r * IDX_ONE as f64).max(1);
                let r = walk_q as f64 / IDX_ONE as f64;
                let cruise_q = table.index_of_hz(cruise_hz / s);
                let plan = RampPlan {
                    cruise_q,
                    exit_q: 0,
                    walk_q,
                    scale: u32_of((65536.0 / s).min(u32::MAX as f64)),
                    dist_q: u32_of(((s / r) * 65536.0).min(u32::MAX as f64)),
                    cruise: mv.cruise,
                };
                let budget = usable(total) * 256.0 * r / s;
                // min(junction, speed) · per_mm as the min of the products (per_mm > 0: same
                // value; the min of two widened f32s would be narrowed to fminf).
                let v_j = if joins { (p.junction as f64 * per_mm).min(p.speed as f64 * per_mm) } else { 0.0 };
                let est = p.len as f64 / (p.speed as f64).max(1e-3) * 1e6;
                (plan, budget, table.index_of_hz(v_j).min(cruise_q), est)
            }
            _ => {
                let plan = RampPlan::lone(table.index_of_hz(cruise_hz), mv.cruise);
                (plan, usable(total) * 256.0, 0, total as f64 / cruise_hz.max(1.0) * 1e6)
            }
        };
        let budget = u32_of(budget.clamp(0.0, u32::MAX as f64));
        Block { mv, ramp, budget, max_entry_q, rev_entry_q: u32::MAX, entry_q: 0, exit_q: 0, est_us: u32_of(est_us.min(4e9)) }
    }

    /// What the passes keep of it once it is handed over.
    pub fn tail(&self) -> Tail {
        Tail { entry_q: self.entry_q, budget: self.budget, cruise_q: self.ramp.cruise_q }
    }
}

/// Master steps a deceleration may plan on: the engine's trigger is conservative by
/// [`DECEL_MARGIN`] steps and by the step a millisecond boundary falls in.
fn usable(total: u32) -> f64 {
    total.saturating_sub(2 * DECEL_MARGIN + 1) as f64
}

/// Index reached from `from_q` walking `budget` of table distance up (or down) the table.
fn reach<const L: usize>(table: &RampTable<L>, from_q: u32, budget: u32) -> u32 {
    table.index_of_sum(table.sum_at(from_q).saturating_add(budget))
}

/// Replans the buffered moves `front` then `back` (oldest first, as a ring buffer's two
/// slices): the reverse pass from rest (stopping at the first move whose bound did not
/// change: the ones before it cannot change either), then the forward pass from `tail` (the
/// last move the engine has, if it is still running) or from rest.
pub fn replan<const N: usize, const L: usize>(
    front: &mut [Block<N>],
    back: &mut [Block<N>],
    tail: Option<&Tail>,
    table: &RampTable<L>,
) {
    let mut next_entry = 0;
    for b in back.iter_mut().rev().chain(front.iter_mut().rev()) {
        let e = b.max_entry_q.min(reach(table, next_entry, b.budget));
        if e == b.rev_entry_q {
            break;
        }
        b.rev_entry_q = e;
        next_entry = e;
    }
    let mut entry = match tail {
        Some(t) => reach(table, t.entry_q, t.budget).min(t.cruise_q),
        None => 0,
    };
    let mut it = front.iter_mut().chain(back.iter_mut()).peekable();
    while let Some(b) = it.next() {
        b.entry_q = b.rev_entry_q.min(entry);
        let next_rev = it.peek().map_or(0, |n| n.rev_entry_q);
        b.exit_q = next_rev.min(reach(table, b.entry_q, b.budget)).min(b.ramp.cruise_q);
        entry = b.exit_q;
    }
}
