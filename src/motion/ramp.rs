//! Ramp tables: the master timer period for every millisecond of an acceleration.
//!
//! Who uses it: the firmware builds one table when settings change (outside any interrupt);
//! the step engine walks it at a move's own fraction of an entry per millisecond (so one table
//! built for the fastest acceleration serves every slower move), interpolating between
//! entries; the look-ahead maps path speeds and distances onto its indices.
//!
//! Invariant: entry `i` holds the period (timer ticks, 1/16 resolution, [`Period`]) of the
//! ideal profile's rate `lead` after millisecond `i` starts: `v0 + a·(i + lead) ms` for the
//! trapezoid (with `lead` = ½ the mean of millisecond `i`), clamped at `vmax` in its last
//! entry (the S-curve's table too, at `a / k`: see `scurve`). The settings pass as `lead` the
//! slowest move's walk rate (at most ½), so entry 0, where every move starts from rest and
//! where a hold stops, is never more than one ms of a move's own acceleration above `v0`
//! (a table built for the fastest axis once started a slow one far above it). Between entries
//! the *rate* is interpolated linearly, so a walk at a constant fraction of an entry per ms
//! changes the rate by the same amount each ms.
//! Entries strictly never rise in rate past `vmax` and never fall in rate along the table. The
//! engine decelerates by walking the same entries down, so one table serves every move that
//! shares the acceleration, and a move's step count never depends on the table. Beside each
//! period the table keeps the distance walked up to it (`sums`, 1/256 step), which is what
//! turns "decelerate from index a to b" into steps without a division. With
//! [`RAMP_LEN`] = 512 entries of 8 bytes the table is 4 KiB of RAM and covers 0.512 s of
//! acceleration; a longer one is refused with [`RampError::TooLong`] naming the highest `vmax`
//! that fits (the settings code then builds a steeper table instead, which slower moves walk at
//! a smaller fraction: see `Settings::build_profile`).
//!
//! - `shape`: the ideal profile (the trapezoid, for both shapes) the entries take their mean
//!   rates from.
//! - `scurve`: the S-curve (`$41=1`): each ramp leg mapped through the seeds' logistic.
//! - `table`: the table, its build and the engine's interpolated lookups.
//! - `search`: the look-ahead's searches on it (the index of a rate, of a distance).
//! - `slot`: the [`Profile`] (table and step timing) shared with the engine, and its
//!   write protocol.

mod scurve;
mod search;
mod shape;
mod slot;
mod table;

pub use scurve::{peak, peak_slope, Leg, SCurve, FLEX_DEFAULT, FLEX_MAX, FLEX_MIN};
pub use shape::{RampConfig, Shape};
pub use slot::{Profile, RampSlot, RampWriteGuard};
pub use table::{RampError, RampTable, IDX_FRAC, IDX_ONE, RAMP_LEN, SUM_ONE};
// (A ramp is in periods: the rate module's items, where the ramp's users have found them.)
pub use crate::motion::rate::{hz_of_period, period_of_hz, period_of_millihz, Period, MAX_RATE_HZ, MIN_RATE_HZ};
