//! Arcs (G2/G3): Grbl's geometry checks, then chords short enough for the arc tolerance `$12`.
//!
//! Who uses it: the G-code interpreter builds an [`Arc`] from a block (checking it the way
//! Grbl's `gcode.c` does, with Grbl's error numbers); the controller walks its [`Segments`] and
//! plans each chord end as an ordinary straight move, so the planner's absolute-step rounding
//! applies and the last chord ends exactly on the programmed point.
//!
//! Planes follow Grbl: G17 turns X→Y about Z, G18 Z→X about Y, G19 Y→Z about X; G2 is clockwise
//! seen from the positive third axis. Every axis outside the plane (the helix's linear axis and
//! any rotary axis) moves in proportion to the angle.
//!
//! Invariants, checked by `tests/arc_props.rs`:
//! - every chord ends on the circle and its sagitta `r(1 - cos(φ/2))` is at most `$12`: the
//!   chord angle is `|θ| / n` with `n = ⌈|θ| / φmax⌉`, `φmax` a lower bound of
//!   `4·asin(√(tol / 2r))`, at most π (where Grbl's `floor` of a small-angle estimate lets a
//!   chord exceed `$12` slightly);
//! - chord ends come from one exact rotation (cos/sin of the chord angle, computed once) and
//!   every [`CORRECTION`]th end is recomputed from the start vector with cos/sin of `i·φ`, so
//!   rounding never accumulates over long arcs (Grbl's `N_ARC_CORRECTION`, with an exact
//!   rotation in place of its third-order small-angle one);
//! - the last chord ends on the programmed target, bit for bit.
//!
//! `f32` like the rest of the library and like Grbl's arcs. (The target vector is taken from
//! the start-to-target differences, not from the rounded center, so a full circle's travel is
//! exactly a turn.)

use crate::planning::planner::{to_steps, MAX_MM};
use crate::error::Error;
use crate::num::sqrt;
use crate::planning::trig::{atan2, sin_cos};
use core::f32::consts::PI;

/// Chord ends computed by rotation between two exact ones (Grbl's `N_ARC_CORRECTION`).
pub const CORRECTION: u32 = 12;
/// Angular travel below which an arc whose target is its start is a full circle (Grbl's
/// `ARC_ANGULAR_TRAVEL_EPSILON`, rad).
const FULL_CIRCLE_EPSILON: f32 = 5e-7;

/// The plane of G17 / G18 / G19 as axis indices: first, second (counter-clockwise from the first
/// to the second is G3).
pub fn plane_axes(plane: u8) -> (usize, usize) {
    match plane {
        18 => (2, 0),
        19 => (1, 2),
        _ => (0, 1),
    }
}

/// How the block gives the center.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Center {
    /// I J K (mm, from the start), indexed X Y Z; only the plane's two matter.
    Offsets([Option<f32>; 3]),
    /// R (mm): negative asks for the arc longer than a half circle.
    Radius(f32),
}

/// A checked arc, absolute mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arc<const N: usize> {
    start: [f32; N],
    target: [f32; N],
    axes: (usize, usize),
    center: [f32; 2],
    radius: f32,
    /// Signed angular travel, rad (positive: counter-clockwise).
    travel: f32,
}

impl<const N: usize> Arc<N> {
    /// Checks an arc the way Grbl's `gcode.c` does (after its feed-rate and axis-word checks):
    /// R form: target equal to the start → `error:33`, radius too small for the chord →
    /// `error:34`; IJK form: no offset in the plane → `error:35`, start and target radii differing
    /// by more than 0.005 mm and more than 0.5 mm or 0.1 % → `error:33`.
    #[inline(never)]
    pub fn new(plane: u8, start: [f32; N], target: [f32; N], clockwise: bool, center: Center) -> Result<Self, Error> {
        let axes = plane_axes(plane);
        let (a, b) = axes;
        if a >= N || b >= N {
            return Err(Error::NoAxisWordsInPlane);
        }
        let (dx, dy) = (target[a] - start[a], target[b] - start[b]);
        let offset = match center {
            Center::Radius(r) => {
                if start == target {
                    return Err(Error::InvalidTarget);
                }
                let d2 = dx * dx + dy * dy;
                let h4 = 4.0 * r * r - d2;
                if h4 < 0.0 {
                    return Err(Error::ArcRadiusError);
                }
                if d2 == 0.0 {
                    // Only the helix axis moves: no circle passes through one point with a chord.
                    return Err(Error::InvalidTarget);
                }
                // Center on the perpendicular bisector, h from the chord's middle; G2 with a
                // positive R takes the short way (center to the right of the travel).
                let mut k = -sqrt(h4) / sqrt(d2);
                if !clockwise {
                    k = -k;
                }
                if r < 0.0 {
                    k = -k;
                }
                [0.5 * (dx - dy * k), 0.5 * (dy + dx * k)]
            }
            Center::Offsets(ijk) => {
                let (i, j) = (ijk.get(a).copied().flatten(), ijk.get(b).copied().flatten());
                if i.is_none() && j.is_none() {
                    return Err(Error::NoOffsetsInPlane);
                }
                let off = [i.unwrap_or(0.0), j.unwrap_or(0.0)];
                let r_start = hypot(off[0], off[1]);
                let r_end = hypot(dx - off[0], dy - off[1]);
                let dr = libm::fabsf(r_end - r_start);
                if dr > 0.005 && (dr > 0.5 || dr > 0.001 * r_start) {
                    return Err(Error::InvalidTarget);
                }
                off
            }
        };
        let center = [start[a] + offset[0], start[b] + offset[1]];
        let radius = hypot(offset[0], offset[1]);
        // Angle from the start vector to the target vector, then the way round G2/G3 asks.
        let (sx, sy) = (-offset[0], -offset[1]);
        // (From the differences, not from the rounded center: a full circle's target vector
        // is then exactly minus the offset, and its travel exactly 0 before the turn is added.)
        let (tx, ty) = (dx - offset[0], dy - offset[1]);
        let mut travel = atan2(sx * ty - sy * tx, sx * tx + sy * ty);
        if clockwise {
            if travel >= -FULL_CIRCLE_EPSILON {
                travel -= 2.0 * PI;
            }
        } else if travel <= FULL_CIRCLE_EPSILON {
            travel += 2.0 * PI;
        }
        if !radius.is_finite() || !travel.is_finite() {
            return Err(Error::InvalidTarget);
        }
        Ok(Arc { start, target, axes, center, radius, travel })
    }

    /// Radius, mm (from the start point).
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Signed angular travel, rad (positive: counter-clockwise in the plane).
    pub fn travel(&self) -> f32 {
        self.travel
    }

    /// The center in the plane's two axes, mm.
    pub fn center(&self) -> [f32; 2] {
        self.center
    }

    /// The plane's two axis indices.
    pub fn axes(&self) -> (usize, usize) {
        self.axes
    }

    /// The programmed end point.
    pub fn target(&self) -> &[f32; N] {
        &self.target
    }

    /// Path length of the helix, mm (what G93 divides by its time).
    pub fn length(&self) -> f32 {
        let mut l2 = self.radius * self.travel * self.radius * self.travel;
        for (i, (s, t)) in self.start.iter().zip(&self.target).enumerate() {
            if i != self.axes.0 && i != self.axes.1 {
                l2 += (t - s) * (t - s);
            }
        }
        sqrt(l2)
    }

    /// `Ok` when every chord end lies within ±[`MAX_MM`] and every chord end and chord fits in
    /// the step range, so planning the chords cannot fail once the block has been accepted
    /// (else `error:33`).
    pub fn check_range(&self, steps_per_mm: &[f32; N]) -> Result<(), Error> {
        let (a, b) = self.axes;
        for (c, ax) in self.center.into_iter().zip([a, b]) {
            for v in [c - self.radius, c + self.radius] {
                if !(libm::fabsf(v) <= MAX_MM) {
                    return Err(Error::InvalidTarget);
                }
                to_steps(v, at(steps_per_mm, ax))?;
            }
            // A chord spans at most the diameter: its step count must fit a move.
            to_steps(2.0 * self.radius, at(steps_per_mm, ax))?;
        }
        Ok(())
    }

    /// Chord ends for arc tolerance `tol` (mm, > 0).
    #[inline(never)]
    pub fn segments(&self, tol: f32) -> Segments<N> {
        let n = segment_count(self.radius, self.travel, tol);
        let phi = self.travel / n as f32;
        let (a, b) = self.axes;
        let r0 = [at(&self.start, a) - self.center[0], at(&self.start, b) - self.center[1]];
        let (sin, cos) = sin_cos(phi);
        Segments { arc: *self, n, i: 0, cos, sin, r: r0 }
    }
}

/// Chords for a circle of `radius` turning `travel` rad with sagitta at most `tol` (at least 1;
/// NaN or infinite inputs also give 1).
pub fn segment_count(radius: f32, travel: f32, tol: f32) -> u32 {
    // Sagitta r(1 - cos(φ/2)) = 2r·sin²(φ/4) ≤ tol: φmax = 4·asin(√(tol/2r)), taken from
    // below by asin x ≥ x + x³/6 (about 3x⁴/40 more chords: 0.02 % at tol/r = 0.1); no chord
    // beyond a half circle.
    let x = sqrt(tol / (2.0 * radius));
    let phi_max = if x >= 1.0 { PI } else { (4.0 * (x + x * x * x / 6.0)).min(PI) };
    let n = libm::ceilf(libm::fabsf(travel) / phi_max);
    if n >= 1.0 && n < u32::MAX as f32 {
        crate::num::u32_of(n)
    } else {
        1 // no travel (a zero radius), or NaN from a zero tolerance: one straight chord
    }
}

/// Chord ends of an [`Arc`], first chord first; the last is the programmed target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segments<const N: usize> {
    arc: Arc<N>,
    n: u32,
    i: u32,
    cos: f32,
    sin: f32,
    /// Vector from the center to the last chord end.
    r: [f32; 2],
}

impl<const N: usize> Segments<N> {
    /// Chords in all.
    pub fn chords(&self) -> u32 {
        self.n
    }

    /// Chords not yet handed out.
    pub fn remaining(&self) -> u32 {
        self.n - self.i
    }
}

impl<const N: usize> Iterator for Segments<N> {
    type Item = [f32; N];

    fn next(&mut self) -> Option<[f32; N]> {
        if self.i >= self.n {
            return None;
        }
        self.i += 1;
        let arc = &self.arc;
        if self.i == self.n {
            return Some(arc.target);
        }
        let [x, y] = self.r;
        self.r = if self.i % CORRECTION == 0 {
            // Exact: the start vector turned by i·φ.
            let (a, b) = arc.axes;
            let (sx, sy) = (at(&arc.start, a) - arc.center[0], at(&arc.start, b) - arc.center[1]);
            let angle = arc.travel * (self.i as f32 / self.n as f32);
            let (s, c) = sin_cos(angle);
            [sx * c - sy * s, sx * s + sy * c]
        } else {
            [x * self.cos - y * self.sin, x * self.sin + y * self.cos]
        };
        let frac = self.i as f32 / self.n as f32;
        let mut p: [f32; N] = core::array::from_fn(|k| arc.start[k] + (arc.target[k] - arc.start[k]) * frac);
        for ((ax, c), r) in [arc.axes.0, arc.axes.1].into_iter().zip(arc.center).zip(self.r) {
            if let Some(v) = p.get_mut(ax) {
                *v = c + r;
            }
        }
        Some(p)
    }
}

/// `v[i]` of a plane axis (always below `N`): no bounds-check panic path. (Out of line: six
/// callers.)
#[inline(never)]
fn at<const N: usize>(v: &[f32; N], i: usize) -> f32 {
    v.get(i).copied().unwrap_or(0.0)
}

fn hypot(x: f32, y: f32) -> f32 {
    sqrt(x * x + y * y)
}
