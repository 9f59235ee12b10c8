//! G93 inverse-time feed: the master cruise rate that makes a move last a given time, in
//! closed form (no iteration, unlike seed 002's search for the frequency).
//!
//! Who uses it: the controller, for each G93 line or arc chord, before planning it as a feed
//! move.
//!
//! A G93 move starts and ends at rest (the controller plans it with junction speed 0 on both
//! sides), so its profile is the engine's ramp up from rest, a cruise and the mirrored ramp
//! down. That ramp is the table walked at the move's own fraction ([`MasterRamp`]): in master
//! steps it starts at `v0` and accelerates at `a`. A move of `N` master steps that cruises at
//! `v ≥ v0` lasts `T(v) = 2(v - v0)/a + (N - (v² - v0²)/a)/v`, i.e. `a·v·T = (v - v0)² + N·a`.
//! For a requested `T` that is a quadratic in `v`; its smaller root is the trapezoid (the
//! larger one would need more steps for the ramps than the move has):
//! `v = 2c / (b + √(b² - 4c))` with `b = 2·v0 + a·T`, `c = v0² + N·a` (this form loses no digits
//! when `a·T ≫ v0`). A rate at or below `v0` needs no ramp: `v = N/T`. When the discriminant is
//! negative even the triangle (peak `√c`) is too slow: the move gets that peak, and the planner
//! then clamps it to the axes' max rates and the table's top, as Grbl clamps a G93 rate to
//! the axes' maximum rates (so the move takes longer than asked).
//!
//! The S-curve (`$41=1`) needs nothing of its own: each of its legs covers, in the same time,
//! what the trapezoid at `a / k` that the table and the walk run covers (`ramp/scurve.rs`),
//! so the closed form holds as it is (seed 002's "N pulses in time T", with S ramps).

use crate::planning::lookahead::walk_of;
use crate::motion::ramp::{RampConfig, IDX_ONE};
use crate::num::sqrt;

/// The ramp a move's master runs on, in master steps: start rate (steps/s) and acceleration
/// (steps/s²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MasterRamp {
    pub v0: f32,
    pub accel: f32,
}

impl MasterRamp {
    /// The ramp the engine runs for a move whose master makes `share` steps per mm of path,
    /// with path acceleration `accel` (mm/s²), on the table `cfg` (path units, `per_mm` table
    /// steps per mm/s; 0: the table is in master steps and every move walks it whole).
    ///
    /// The move walks `r` entries per ms (its acceleration over the table's, [`walk_of`]) and
    /// runs at `s` times the table's rate. Entry `i` holds the mean rate of millisecond `i`,
    /// `v0 + A·(i + ½) ms`, and millisecond `k` of the walk sits at index `k·r`, so the master
    /// runs `s·(v0 + A·(k·r + ½) ms)`: the mean of millisecond `k` of a ramp from
    /// `s·(v0 + A·(1 − r)/2 ms)` at `s·r·A`.
    pub fn new(share: f32, accel: f32, per_mm: f32, cfg: &RampConfig) -> Self {
        let v0 = cfg.v0 as f32;
        // (Both shapes: the S-curve's legs cover what the trapezoid at a / k covers in the same
        // time, and its table and walks are that trapezoid's.)
        let a = cfg.accel as f32;
        let (s, r) = if per_mm > 0.0 {
            let (s, walk_q) = walk_of(share, accel, per_mm, cfg.accel.max(1) as f32);
            (s, walk_q as f32 * (1.0 / IDX_ONE as f32))
        } else {
            (1.0, 1.0)
        };
        let sa = s * a;
        MasterRamp { v0: s * v0 + sa * (1.0 - r) * 0.0005, accel: sa * r }
    }
}

/// Master cruise rate (steps/s) for `steps` master steps to take `seconds`, starting and ending
/// at rest on the ramp `ramp`.
pub fn cruise_hz(steps: u64, seconds: f32, ramp: &MasterRamp) -> f32 {
    let n = steps as f32;
    let (v0, a) = (ramp.v0, ramp.accel);
    let flat = n / seconds;
    if flat <= v0 || a <= 0.0 {
        return flat;
    }
    let b = 2.0 * v0 + a * seconds;
    let c = v0 * v0 + n * a;
    let d = b * b - 4.0 * c;
    if d < 0.0 {
        return sqrt(c);
    }
    2.0 * c / (b + sqrt(d))
}

/// How long a move of `steps` master steps at cruise `v` lasts on the ramp `ramp`, s (the
/// forward formula the solver inverts; for tests and reports).
pub fn duration_s(steps: u64, v: f32, ramp: &MasterRamp) -> f32 {
    let (n, v0, a) = (steps as f32, ramp.v0, ramp.accel);
    if v <= v0 {
        return n / v;
    }
    let peak2 = v0 * v0 + n * a;
    if v * v >= peak2 {
        // Triangle: up to the peak and down again.
        return 2.0 * (sqrt(peak2) - v0) / a;
    }
    ((v - v0) * (v - v0) + n * a) / (a * v)
}
