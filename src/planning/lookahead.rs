//! Look-ahead: junction speeds for a chain of moves, mapped onto the ramp table (Grbl's idea).
//!
//! Who uses it: the feeder, which keeps the moves not yet handed to the engine here and
//! replans them whenever one arrives.
//!
//! Every speed is a Q20 index into the one ramp table (the table is in path units: see
//! [`crate::motion::prepared`]), and every distance is in the table's own distance sums, so planning
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
use crate::motion::prepared::RampPlan;
use crate::motion::moves::{Move, Overrides, Rates};
use crate::motion::ramp::{Period, Profile, RampTable, IDX_FRAC, IDX_ONE};
use crate::motion::timing::Timing;
use crate::motion::walk::DECEL_MARGIN;

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
    /// The junction deviation's limit on the entry (0 from rest).
    pub junction_q: u32,
    /// Highest entry the junction and the move's cruise allow (the previous move's cruise
    /// caps it in the forward pass).
    pub max_entry_q: u32,
    /// Highest entry the moves after it allow (reverse pass; kept to stop early).
    pub rev_entry_q: u32,
    /// Planned entry and exit.
    pub entry_q: u32,
    pub exit_q: u32,
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
    /// master steps) under the overrides `o`; `joins` when a move runs before it (else it
    /// starts from rest).
    #[inline(never)]
    pub fn new<const L: usize>(mv: Move<N>, profile: &Profile<L>, joins: bool, o: Overrides) -> Self {
        // f32 arithmetic, as the rest of the library (the inputs are stored as f32).
        let (table, per_mm) = (&profile.ramp, profile.per_mm);
        let total = mv.steps.get(mv.master as usize).map_or(0, |s| s.unsigned_abs());
        let t_accel = table.config().accel.max(1) as f32;
        // `per_mm > 0.0` on the f32's bits (positive: 1 ..= +inf): an integer compare, no call.
        let positive = (1..=0x7F80_0000).contains(&profile.per_mm.to_bits());
        let (ramp, budget, junction_q) = match (&mv.path, positive) {
            (Some(p), true) => {
                let (s, walk_q) = walk_of(p.share, p.accel, per_mm, t_accel);
                let r = walk_q as f32 / IDX_ONE as f32;
                let scale = u32_of((65536.0 / s).min(u32::MAX as f32));
                let dist_q = u32_of(((s / r) * 65536.0).min(u32::MAX as f32));
                let plan = RampPlan { cruise_q: 0, exit_q: 0, walk_q, scale, dist_q, cruise: mv.cruise };
                let budget = usable(total) * 256.0 * r / s;
                let v_j = if joins { p.junction * per_mm } else { 0.0 };
                (plan, budget, table.index_of_hz(v_j))
            }
            _ => (RampPlan::lone(0, mv.cruise), usable(total) * 256.0, 0),
        };
        // (`u32_of` saturates as a clamp to 0 ..= u32::MAX would, NaN to 0.)
        let budget = u32_of(budget);
        let mut b = Block { mv, ramp, budget, junction_q, max_entry_q: 0, rev_entry_q: u32::MAX, entry_q: 0, exit_q: 0 };
        b.price(profile, o);
        b
    }

    /// Sets the cruise (and what follows from it) for the overrides `o`; the passes must run
    /// again ([`replan`]).
    pub fn price<const L: usize>(&mut self, profile: &Profile<L>, o: Overrides) {
        let timing = match profile.timing {
            Timing::UNSET => Timing::DEFAULT,
            t => t,
        };
        let slaves = self.mv.steps.iter().filter(|s| **s != 0).count().saturating_sub(1) as u32;
        let min_bits = timing.min_period_for(slaves).saturating_mul(16);
        (self.ramp.cruise, self.ramp.cruise_q) = cruise_for(&self.mv.rates(), o, self.ramp.scale, min_bits, &profile.ramp);
        self.max_entry_q = self.junction_q.min(self.ramp.cruise_q);
        self.rev_entry_q = u32::MAX;
    }

    /// What the passes keep of it once it is handed over.
    pub fn tail(&self) -> Tail {
        Tail { entry_q: self.entry_q, budget: self.budget, cruise_q: self.ramp.cruise_q }
    }
}

/// A move's cruise under the overrides `o`: its floor period and its index on `table` (scaled
/// by `scale`, Q16; the engine holds no period below `min_bits`, the step timing's floor).
pub fn cruise_for<const L: usize>(rates: &Rates, o: Overrides, scale: u32, min_bits: u32, table: &RampTable<L>) -> (Period, u32) {
    let cruise = rates.cruise_at(o);
    (cruise, cruise_index(table, scale, cruise.to_bits().max(min_bits)))
}

/// How a move walks the table: its master's share of the table rate `s` (master steps per mm
/// of path `share` over the table's `per_mm`: ≤ 1 unless the table's units are below the
/// finest axis's, see `Settings::per_mm`; at most 2^16, so `scale` stays ≥ 1) and its walk
/// rate (Q20 entries per ms, at least one unit: its path acceleration `accel`, mm/s², as a
/// fraction of the table's `t_accel`, table steps/s²).
pub fn walk_of(share: f32, accel: f32, per_mm: f32, t_accel: f32) -> (f32, u32) {
    let s = (share / per_mm).clamp(1e-6, 65536.0);
    let r = (accel * per_mm / t_accel).clamp(0.0, 1.0);
    (s, u32_of(r * IDX_ONE as f32).max(1))
}

/// The lowest index (Q20) where the table, scaled by `scale` (Q16), is at least as fast as a
/// period of `cruise_bits` (1/16 tick); the top when it never is. So the table never holds a
/// move below its own cruise: a rate's index rounded down (`index_of_hz`) and the
/// interpolation's truncation would leave it slower by a 1/16 tick or more (59 996 Hz for a
/// 60 kHz G0). Integer binary search (the interpolated period never rises with the index).
fn cruise_index<const L: usize>(table: &RampTable<L>, scale: u32, cruise_bits: u32) -> u32 {
    let fast = |p: Period| (p.to_bits() as u64 * scale as u64) >> 16 <= cruise_bits as u64;
    let periods = table.periods();
    let (Some(&first), Some(&last)) = (periods.first(), periods.last()) else { return 0 };
    let (mut lo, mut hi) = (0u32, table.top_q());
    if fast(first) {
        return 0;
    }
    if !fast(last) {
        return hi;
    }
    // Invariant: !fast(lo), fast(hi). Whole entries first (entry `i` is `period_at(i << 20)`)
    // while they are more than one apart, then the fraction.
    while hi - lo > 1 {
        let (mid, p) = if hi - lo > IDX_ONE {
            let i = ((lo >> IDX_FRAC) + (hi >> IDX_FRAC)) / 2;
            (i << IDX_FRAC, table.period(i as usize))
        } else {
            let mid = lo + (hi - lo) / 2;
            (mid, table.period_at(mid))
        };
        if fast(p) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// Master steps a deceleration may plan on: the engine's trigger is conservative by
/// [`DECEL_MARGIN`] steps and by the step a millisecond boundary falls in.
fn usable(total: u32) -> f32 {
    total.saturating_sub(2 * DECEL_MARGIN + 1) as f32
}

/// Index reached from `from_q` walking `budget` of table distance up (or down) the table.
pub(crate) fn reach<const L: usize>(table: &RampTable<L>, from_q: u32, budget: u32) -> u32 {
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
    // (The two slices by index, as one sequence: smaller and faster than chained iterators.)
    let n = front.len() + back.len();
    let mut next_entry = 0;
    for k in (0..n).rev() {
        let Some(b) = at(front, back, k) else { break };
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
    for k in 0..n {
        let next_rev = at(front, back, k + 1).map_or(0, |n| n.rev_entry_q);
        let Some(b) = at(front, back, k) else { break };
        let e = b.rev_entry_q.min(entry);
        let bound = next_rev.min(b.ramp.cruise_q);
        // The reach from an unchanged entry is at least the exit it gave before (0 for a new
        // block): a bound at or below that exit is the exit, without the search.
        b.exit_q = if e == b.entry_q && bound <= b.exit_q { bound } else { bound.min(reach(table, e, b.budget)) };
        b.entry_q = e;
        entry = b.exit_q;
    }
}

// block `k` of the sequence `front` then `back`
fn at<'a, const N: usize>(front: &'a mut [Block<N>], back: &'a mut [Block<N>], k: usize) -> Option<&'a mut Block<N>> {
    match k.checked_sub(front.len()) {
        None => front.get_mut(k),
        Some(j) => back.get_mut(j),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::ramp::{period_of_hz, RampConfig, Shape};

    /// The search as it was: one bisection over every Q20 index.
    fn cruise_index_ref<const L: usize>(table: &RampTable<L>, scale: u32, cruise_bits: u32) -> u32 {
        let fast = |q: u32| (table.period_at(q).to_bits() as u64 * scale as u64) >> 16 <= cruise_bits as u64;
        let (mut lo, mut hi) = (0u32, table.top_q());
        if table.is_empty() || fast(lo) {
            return 0;
        }
        if !fast(hi) {
            return hi;
        }
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if fast(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }

    /// The passes as they were before the forward pass reused exits: every reach searched.
    fn replan_ref<const N: usize, const L: usize>(blocks: &mut [Block<N>], tail: Option<&Tail>, table: &RampTable<L>) {
        let mut next_entry = 0;
        for b in blocks.iter_mut().rev() {
            let e = b.max_entry_q.min(reach(table, next_entry, b.budget));
            if e == b.rev_entry_q {
                break;
            }
            b.rev_entry_q = e;
            next_entry = e;
        }
        let mut entry = tail.map_or(0, |t| reach(table, t.entry_q, t.budget).min(t.cruise_q));
        for k in 0..blocks.len() {
            let next_rev = blocks.get(k + 1).map_or(0, |n| n.rev_entry_q);
            let b = &mut blocks[k];
            b.entry_q = b.rev_entry_q.min(entry);
            b.exit_q = next_rev.min(reach(table, b.entry_q, b.budget)).min(b.ramp.cruise_q);
            entry = b.exit_q;
        }
    }

    /// Pushes, hand-overs (the front block becomes the tail, or the engine runs dry) and
    /// re-pricings in random order, the buffer as a ring (two slices): every entry and exit
    /// equal to the reference passes' on the same sequence.
    #[test]
    fn replan_matches_the_full_passes() {
        let mut rng = crate::num::xorshift(0x2545_F491_4F6C_DD1Du64);
        let mut next = |n: u64| rng() % n;
        let mut table = RampTable::<512>::new();
        table.build(RampConfig { v0: 100, vmax: 60_000, accel: 200_000, shape: Shape::Trapezoid }).unwrap();
        let top = table.top_q() as u64;
        let mv = Move::<2>::new([100, 30], 5_000).unwrap();
        for _ in 0..200 {
            let mut ring: heapless::Deque<Block<2>, LOOKAHEAD> = heapless::Deque::new();
            let mut flat: heapless::Vec<Block<2>, LOOKAHEAD> = heapless::Vec::new();
            let (mut tail, mut tail_ref): (Option<Tail>, Option<Tail>) = (None, None);
            for _ in 0..300 {
                match next(10) {
                    0..=5 if !ring.is_full() => {
                        let cruise_q = next(top + 1) as u32;
                        let junction_q = if next(4) == 0 { 0 } else { next(top + 1) as u32 };
                        let bits = 8 + next(20);
                        let mut ramp = RampPlan::lone(0, mv.cruise);
                        ramp.cruise_q = cruise_q;
                        let b = Block {
                            mv,
                            ramp,
                            budget: next(1 << bits) as u32,
                            junction_q,
                            max_entry_q: junction_q.min(cruise_q),
                            rev_entry_q: u32::MAX,
                            entry_q: 0,
                            exit_q: 0,
                        };
                        ring.push_back(b).unwrap();
                        flat.push(b).unwrap();
                    }
                    6..=7 => {
                        if let Some(b) = ring.pop_front() {
                            tail = Some(b.tail());
                            tail_ref = Some(flat.remove(0).tail());
                        }
                        continue; // (a hand-over replans nothing)
                    }
                    8 => {
                        (tail, tail_ref) = (None, None);
                    }
                    _ => {
                        for (b, f) in ring.iter_mut().zip(flat.iter_mut()) {
                            let c = next(top + 1) as u32;
                            for x in [b, f] {
                                x.ramp.cruise_q = c;
                                x.max_entry_q = x.junction_q.min(c);
                                x.rev_entry_q = u32::MAX;
                            }
                        }
                    }
                }
                let (front, back) = ring.as_mut_slices();
                replan(front, back, tail.as_ref(), &table);
                replan_ref(&mut flat, tail_ref.as_ref(), &table);
                assert_eq!(ring.len(), flat.len());
                for (b, f) in ring.iter().zip(&flat) {
                    assert_eq!((b.rev_entry_q, b.entry_q, b.exit_q), (f.rev_entry_q, f.entry_q, f.exit_q));
                }
            }
        }
    }

    /// The cruise index is the lowest one at which the scaled table is at least as fast as
    /// the cruise, for random tables (leads), scales and rates (also between entries, where
    /// rounding the index down would leave the table up to a 1/16 tick slow); the same index
    /// as one bisection over every Q20 index.
    #[test]
    fn cruise_index_is_the_first_index_fast_enough() {
        let mut rng = crate::num::xorshift(0x9E37_79B9_7F4A_7C15u64);
        let mut next = |n: u64| rng() % n;
        let mut table = RampTable::<1024>::new();
        for _ in 0..300 {
            let v0 = 1 + next(5_000) as u32;
            let vmax = v0 + next(300_000) as u32;
            let accel = 1_000 + next(20_000_000) as u32;
            let shape = if next(2) == 0 { Shape::Trapezoid } else { Shape::SCurve };
            let lead = next(IDX_ONE as u64 / 2 + 1) as u32;
            if table.build_led(RampConfig { v0, vmax, accel, shape }, lead).is_err() {
                continue;
            }
            for _ in 0..50 {
                let scale = (1 << 16) + next(3 << 16) as u32;
                let hz = 1 + next(vmax as u64 + 1_000) as u32;
                let cruise = period_of_hz(hz).to_bits();
                let fast = |q: u32| (table.period_at(q).to_bits() as u64 * scale as u64) >> 16 <= cruise as u64;
                let q = cruise_index(&table, scale, cruise);
                assert_eq!(q, cruise_index_ref(&table, scale, cruise), "{hz} Hz, scale {scale}");
                assert!(q <= table.top_q());
                if q > 0 {
                    assert!(!fast(q - 1), "{hz} Hz: {q} is not the first");
                }
                assert!(fast(q) || q == table.top_q(), "{hz} Hz: the table at {q} is slower");
            }
        }
    }
}
