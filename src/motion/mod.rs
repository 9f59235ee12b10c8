//! Motion core: everything the step and ramp interrupts run, and the data they run on.
//!
//! - [`interp`]: the DDA (Bresenham) interpolator — master axis plus up to six slaves in
//!   exact integer ratio, every slave within ½ step of the ideal line.
//! - [`ramp`]: per-millisecond ramp tables (trapezoid or S-curve) of timer periods, with the
//!   distance walked up to each entry.
//! - [`rate`]: step rates and timer periods ([`rate::Period`]), the rate limits.
//! - [`prepared`]: a move as the step interrupt needs it, computed outside it.
//! - [`ring`]: the lock-free ring of prepared moves (run in place by the engine).
//! - [`walk`]: the ramp walk — the table index, its per-millisecond update and the
//!   deceleration trigger.
//! - [`control`]: the control word (feed hold + immediate-stop epoch), one type for both sides.
//! - [`engine`]: the step engine in two halves: behind TIM2, one [`engine::Stepper::tick`]
//!   computes the next GPIO BSRR word and the next timer period; the ramp walk runs in
//!   [`engine::Ramper::run`], a lower-priority interrupt ([`engine::Engine`] runs both on the
//!   host).
//! - [`burst`]: DMA burst output — the engine fills the buffers DMA plays out at TIM2's
//!   events (no interrupt per edge).
//! - [`moves`]: moves as the planner hands them over, their rates and the override
//!   percentages that scale them.
//! - [`shared`]: the state shared lock-free with the step interrupt (the position record's
//!   sequence lock, the engine's state, control word, overrides, probe).
//! - [`timing`]: driver timing (pulse width, direction setup) as typed constants.
//! - [`tim2_model`]: a model of the TIM2 preload pipeline that turns ticks into timed edges (host
//!   tests, benchmarks).

pub mod burst;
pub mod control;
pub mod engine;
pub mod interp;
pub mod moves;
pub mod prepared;
pub mod ramp;
pub mod rate;
pub mod ring;
pub mod shared;
pub mod tim2_model;
pub mod timing;
pub mod walk;
