//! The planner: G-code targets in mm to [`Move`]s (signed steps and a master cruise rate).
//!
//! Who uses it: the controller, once per G0/G1/G92 (outside any interrupt; `f32` math).
//!
//! Invariant: the planner keeps the programmed target in mm and the absolute step position
//! `round(target × steps/mm)` of every axis (halves away from zero, as Grbl's `lround`; from
//! the decimal as written where the G-code front end gives it, [`crate::planning::exact`]); a
//! move is the difference between two such step positions, so rounding never accumulates (a
//! thousand G91 moves of 0.001 mm at 100 steps/mm make exactly 100 steps, in ten single steps).
//!
//! Rates (Grbl's): a G1 runs at F along its path (length over all moving axes, from the
//! rounded steps), a G0 at the fastest speed its axes allow; no axis may exceed its `$110+i`
//! (the path speed is at most `min $110+i / |unitᵢ|`), and its acceleration is
//! `min $120+i / |unitᵢ|` over the axes it moves: axes that do not move never slow it. The
//! master's cruise rate is then clamped to what the step interrupt sustains for the move's
//! slave count (`Timing::max_rate_for`) and to the ramp table's top (both printed by `$I`).
//! Each move also carries its junction speed with the move before it (junction deviation
//! `$11`, Grbl's formula); the look-ahead ([`crate::planning::lookahead`]) does the rest.

use crate::num::{f32_of_i64, f32_of_u64, sqrt};
use crate::error::Error;
use crate::motion::moves::{Move, Ovr, Path};
use crate::motion::timing::Timing;
use crate::planning::exact::Decimal;

/// Largest axis target accepted, mm (beyond it: `error:33`; G-code words and arc chord ends).
pub const MAX_MM: f32 = 1e6;

/// Junction deviation `$11`, mm (Grbl's default; the setting is shown fixed at this value).
pub const JUNCTION_DEVIATION_MM: f32 = 0.010;

/// What the planner needs from the settings, for `N` axes (`Settings::planner_limits` builds it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits<const N: usize> {
    /// `$100+i`, steps/mm.
    pub steps_per_mm: [f32; N],
    /// `$110+i`, mm/min.
    pub max_rate: [f32; N],
    /// `$120+i`, mm/s².
    pub accel: [f32; N],
    /// What a move's path acceleration is walked at, as a fraction of it (`1 / k` in S-curve
    /// mode, whose legs peak at the full acceleration: `ramp/scurve.rs`; junctions use `accel`).
    pub ramp_accel: f32,
    /// Top of the ramp table (table rate = path speed × `per_mm`).
    pub vmax_hz: u32,
    /// Table rate per mm/s of path speed (`Settings::per_mm`: the largest `$100+i`, or less
    /// where the table's top could not hold every move's cap otherwise).
    pub per_mm: f32,
    /// Junction deviation, mm.
    pub junction_dev: f32,
    /// Step timing: a move with more slave axes has a lower ceiling (`Timing::max_rate_for`).
    pub timing: Timing,
}

/// A planned move and what status reports need to know about it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Planned<const N: usize> {
    pub mv: Move<N>,
    /// Path length per master step, mm (turns the master rate into a feed).
    pub mm_per_step: f32,
    /// The master rate the feed and axis limits allow, before rounding and clamping (steps/s).
    pub wanted_hz: f32,
}

/// Planner position: programmed mm and absolute steps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Planner<const N: usize> {
    mm: [f32; N],
    steps: [i64; N],
    /// The last planned move (for the junction): its direction, master steps per mm and
    /// slave count.
    prev: Option<([f32; N], f32, u32)>,
}

impl<const N: usize> Default for Planner<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Planner<N> {
    /// At the origin.
    pub const fn new() -> Self {
        Planner { mm: [0.0; N], steps: [0; N], prev: None }
    }

    /// Programmed position, mm.
    pub fn position_mm(&self) -> &[f32; N] {
        &self.mm
    }

    /// Absolute step position of the last planned target.
    pub fn position_steps(&self) -> &[i64; N] {
        &self.steps
    }

    /// The next move starts from rest: its junction speed with the last one is 0 (G93 moves,
    /// whose closed-form time assumes rest at both ends, call it before and after planning).
    pub fn rest(&mut self) {
        self.prev = None;
    }

    /// Takes the engine's step counters as the position (after a reset or new steps/mm).
    pub fn sync(&mut self, steps: [i32; N], lim: &Limits<N>) {
        self.steps = steps.map(i64::from);
        self.mm = core::array::from_fn(|i| steps[i] as f32 / lim.steps_per_mm[i]);
        self.prev = None;
    }

    /// G92: the named axes are now at the given mm. Returns the step position to publish
    /// (`Shared::set_positions`, once the engine is idle).
    pub fn set_position(&mut self, set: &[Option<f32>; N], lim: &Limits<N>) -> Result<[i32; N], Error> {
        let mut steps = self.steps;
        for ((s, mm), spm) in steps.iter_mut().zip(set).zip(&lim.steps_per_mm) {
            if let Some(mm) = mm {
                *s = to_steps(*mm, *spm)?;
            }
        }
        for (m, v) in self.mm.iter_mut().zip(set) {
            *m = v.unwrap_or(*m);
        }
        self.steps = steps;
        Ok(core::array::from_fn(|i| steps[i] as i32))
    }

    /// A straight move to `target` (mm): `feed` in mm/min for G1, `None` for G0. `Ok(None)` when
    /// no axis moves a whole step (the position still advances, so nothing is lost).
    pub fn line(&mut self, target: &[f32; N], feed: Option<f32>, lim: &Limits<N>) -> Result<Option<Planned<N>>, Error> {
        self.line_exact(target, &[None; N], feed, lim)
    }

    /// [`Self::line`], with the target of some axes also given exactly (`exact[i]`, the same
    /// position as `target[i]` but as written, see [`crate::planning::exact`]): those axes'
    /// step targets are rounded from the decimal in integers (`Y4.595` at 100 steps/mm: 460,
    /// as Grbl), the others from the `f32` target. An axis whose `f32` target is the position
    /// already planned keeps its step position (an exact target before may differ by one
    /// step from its `f32`'s rounding).
    pub fn line_exact(
        &mut self,
        target: &[f32; N],
        exact: &[Option<Decimal>; N],
        feed: Option<f32>,
        lim: &Limits<N>,
    ) -> Result<Option<Planned<N>>, Error> {
        let mut to = [0i64; N];
        for i in 0..N {
            let spm = lim.steps_per_mm[i];
            to[i] = match exact[i] {
                Some(d) => d.steps(spm)?,
                None if same(target[i], self.mm[i]) => self.steps[i],
                None => to_steps(target[i], spm)?,
            };
        }
        let delta: [i64; N] = core::array::from_fn(|i| to[i] - self.steps[i]);
        let master_steps = delta.iter().map(|d| d.unsigned_abs()).max().unwrap_or(0);
        if master_steps == 0 {
            self.mm = *target;
            return Ok(None);
        }
        // Path length from the rounded steps; per-axis unit vector.
        // (Axes that do not move are skipped: soft float costs ~50–200 cycles an operation on
        // the M3 even for zeros. One division for the unit vector.)
        // (Loops over the moving axes' bits: over all N the compiler computes every product
        // and selects, a soft-float call each.)
        let moving = delta.iter().enumerate().fold(0u32, |m, (i, s)| m | ((*s != 0) as u32) << i);
        // Per-axis mm, and the squared length (a sum from -0.0, as `Sum`).
        let mut unit = [0.0f32; N];
        let mut len2 = -0.0f32;
        for i in set_bits(moving) {
            let (Some(u), Some(s), Some(spm)) = (unit.get_mut(i), delta.get(i), lim.steps_per_mm.get(i)) else { continue };
            *u = f32_of_i64(*s) / spm;
            if nonzero(*u) {
                len2 += *u * *u;
            }
        }
        let len = sqrt(len2);
        let inv_len = 1.0 / len;
        // The unit vector, and the path speed and acceleration every moving axis allows
        // (Grbl's limit by axis).
        let mut vmax = f32::MAX;
        let mut accel = f32::MAX;
        for i in set_bits(moving) {
            let (Some(v), Some(rate), Some(acc)) = (unit.get_mut(i), lim.max_rate.get(i), lim.accel.get(i)) else { continue };
            *v *= inv_len;
            let u = libm::fabsf(*v);
            if above(u, 0.0) {
                vmax = vmax.min(rate / (60.0 * u));
                accel = accel.min(acc / u);
            }
        }
        // The overrides scale the asked speed later, in the feeder ([`crate::motion::moves::Rates`]).
        let (asked, ovr) = match feed {
            Some(f) => (f / 60.0, Ovr::Feed),
            None => (vmax, Ovr::Rapid),
        };
        let share = f32_of_u64(master_steps) / len;
        let wanted_hz = asked.min(vmax) * share;
        // The step handler's ceiling for this many slave axes, and the ramp table's top.
        let slaves = delta.iter().filter(|d| **d != 0).count() as u32 - 1;
        let top = (lim.timing.max_rate_for(slaves) as f32).min(lim.vmax_hz as f32 * share / lim.per_mm.max(1e-9));
        // max/min, not f32::clamp: its panic message would link float formatting into the firmware.
        // Milli-steps/s: G93 times need more than whole steps/s at low rates.
        let top_millihz = crate::motion::ramp::MAX_RATE_HZ as u64 * 1000;
        let cruise_millihz = crate::num::u64_of(libm::roundf(wanted_hz.max(1.0).min(top) * 1000.0)).min(top_millihz);
        let mut mv = Move::new_millihz(delta, cruise_millihz).map_err(|_| Error::InvalidTarget)?;
        mv.ovr = ovr;
        // Junction deviation only: the look-ahead caps it by both moves' speeds under the
        // overrides in force.
        // And the step path's move change: at most the mode's junction rate on both sides
        // (`Timing::max_junction_rate_for`: DMA mode changes moves inside a buffer fill).
        let junction = match self.prev {
            Some((pu, pshare, pslaves)) => {
                let jcap = lim.timing.max_junction_rate_for(slaves.max(pslaves)) as f32;
                junction_speed(&pu, &unit, &lim.accel, lim.junction_dev).min(jcap / share.max(pshare))
            }
            None => 0.0,
        };
        self.prev = Some((unit, share, slaves));
        let path = Path {
            share: share as f32,
            accel: (accel * lim.ramp_accel).min(1e12),
            asked_hz: (asked * share) as f32,
            cap_hz: (vmax * share).min(top) as f32,
            junction: junction as f32,
        };
        self.mm = *target;
        self.steps = to;
        Ok(Some(Planned { mv: mv.with_path(path), mm_per_step: (len / f32_of_u64(master_steps)) as f32, wanted_hz }))
    }
}

/// Grbl's junction speed (mm/s) from direction `a` into direction `b` (unit vectors): the
/// speed at which a circle of deviation `dev` tangent to both moves is driven at the largest
/// acceleration the axes allow along the change of direction,
/// `v² = acc·dev·sin(θ/2)/(1 − sin(θ/2))`; 0 for a reversal, unlimited straight on.
/// In f32 like the rest of the planner (and Grbl).
pub fn junction_speed<const N: usize>(a: &[f32; N], b: &[f32; N], axis_accel: &[f32; N], dev: f32) -> f32 {
    let mut cos = 0.0f32;
    let mut ju = [0.0f32; N];
    // The change of direction and its squared norm (a sum from -0.0, as `Sum`), over the
    // axes either move has (see `line_exact`'s sum).
    let mut n2 = -0.0f32;
    let turning = (0..N).fold(0u32, |m, i| m | ((nonzero(a[i]) || nonzero(b[i])) as u32) << i);
    for i in set_bits(turning) {
        if let (Some(x), Some(y), Some(j)) = (a.get(i), b.get(i), ju.get_mut(i)) {
            cos -= x * y;
            *j = y - x;
            if nonzero(*j) {
                n2 += *j * *j;
            }
        }
    }
    if above(cos, 0.999_999) {
        return 0.0;
    }
    if above(-cos, 0.999_999) {
        return f32::MAX;
    }
    let inv_n = 1.0 / sqrt(n2);
    let mut acc = f32::MAX;
    // (`ju` is +0.0 off `turning`: no bound there.)
    for i in set_bits(turning) {
        let (Some(j), Some(a)) = (ju.get(i), axis_accel.get(i)) else { continue };
        let u = libm::fabsf(*j) * inv_n;
        if above(u, 1e-9) {
            acc = acc.min(a / u);
        }
    }
    let sin_d2 = sqrt(0.5 * (1.0 - cos));
    sqrt(acc * dev * sin_d2 / (1.0 - sin_d2))
}

// The f32 compares of the per-line path on the bits: the same answers as the operators, for
// every input (NaN included), without the soft-float compare calls (~40 cycles each on the M3).

// the indices of the set bits of `mask`, lowest first
fn set_bits(mut mask: u32) -> impl Iterator<Item = usize> {
    core::iter::from_fn(move || {
        let i = mask.trailing_zeros() as usize;
        mask &= mask.wrapping_sub(1);
        (i < 32).then_some(i)
    })
}

// `x != 0.0`
#[inline(always)]
fn nonzero(x: f32) -> bool {
    x.to_bits() << 1 != 0
}

// `x > c`, for a constant `c` that is +0.0 or positive and finite
#[inline(always)]
fn above(x: f32, c: f32) -> bool {
    (c.to_bits() + 1..=0x7F80_0000).contains(&x.to_bits())
}

// `a == b`: the same bits and not NaN, or both zeros
#[inline(always)]
fn same(a: f32, b: f32) -> bool {
    (a.to_bits() == b.to_bits() && a.to_bits() << 1 <= 0xFF00_0000) || (a.to_bits() | b.to_bits()) << 1 == 0
}

/// Absolute steps of a position in mm: `round(mm × steps/mm)`, within ±(2^31 - 1).
pub fn to_steps(mm: f32, steps_per_mm: f32) -> Result<i64, Error> {
    let s = libm::roundf(mm * steps_per_mm);
    // Below 2^31 (exact in f32; `i32::MAX as f32` rounds up to it): whole, so within ±(2^31 - 1).
    if s.is_finite() && libm::fabsf(s) < 2_147_483_648.0 {
        // Through i32 (the value fits): the f32-to-i64 routine costs flash.
        Ok(crate::num::i32_of(s) as i64)
    } else {
        Err(Error::InvalidTarget)
    }
}

#[cfg(test)]
#[path = "planner_tests.rs"]
mod tests;
