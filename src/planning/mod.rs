//! Planning: turns G-code targets into moves the motion core can run (steps per axis, master
//! choice, rate limits clamped to what the engine can hold), joins them with look-ahead and
//! hands them to the step interrupt prepared.
//!
//! - [`planner`]: targets in mm to moves (steps, nominal speed, acceleration, junction speed).
//! - [`exact`]: step targets from a decimal as written, rounded as Grbl's `lround`.
//! - [`lookahead`]: reverse and forward passes over the buffered moves, on the ramp table.
//! - [`feeder`]: the look-ahead buffer and the just-in-time hand-over to the engine's ring.

pub mod feeder;
pub mod lookahead;
pub mod planner;
pub mod arc;
pub mod inverse_time;
pub mod trig;
pub mod exact;
