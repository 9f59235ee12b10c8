//! Planning: turns G-code targets into moves the motion core can run (steps per axis, master
//! choice, rate limits clamped to what the engine can hold).

pub mod planner;
pub mod arc;
pub mod inverse_time;
pub mod trig;
