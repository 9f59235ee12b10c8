//! Motion core: everything the step interrupt runs, and the data it runs on.
//!
//! - [`interp`]: the DDA (Bresenham) interpolator — master axis plus up to six slaves in
//!   exact integer ratio, every slave within ½ step of the ideal line.
//! - [`ramp`]: per-millisecond ramp tables (trapezoid or S-curve) of master timer periods.
//! - [`engine`]: the step engine behind TIM2; one [`engine::Engine::tick`] computes the next
//!   GPIO BSRR word and the next timer period.
//! - [`queue`]: the lock-free move queue and the atomics shared with the step interrupt.
//! - [`timing`]: driver timing (pulse width, direction setup) as typed constants.
//! - [`sim`]: a model of the TIM2 preload pipeline that turns ticks into timed edges (host
//!   tests, benchmarks).

pub mod engine;
pub mod interp;
pub mod queue;
pub mod ramp;
pub mod sim;
pub mod timing;
