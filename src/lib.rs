//! ddastep: a multi-axis step/direction pulse generator for one STM32F103 "Blue Pill".
//!
//! This library is the whole motion core, free of HAL and PAC types so that every line the
//! step interrupt runs is also run by host tests:
//!
//! - [`interp`]: the DDA (Bresenham) interpolator — master axis plus up to six slaves in
//!   exact integer ratio, every slave within ½ step of the ideal line.
//! - [`ramp`]: per-millisecond ramp tables (trapezoid or S-curve) of master timer periods.
//! - [`engine`]: the step engine behind TIM2; one [`engine::Engine::tick`] computes the next
//!   GPIO BSRR word and the next timer period.
//! - [`timing`]: driver timing (pulse width, direction setup) as typed constants.
//! - [`sim`]: a model of the TIM2 preload pipeline that turns ticks into timed edges (host tests,
//!   benchmarks).
#![no_std]
#![cfg_attr(not(test), deny(warnings))]

pub mod board;
pub mod controller;
pub mod engine;
pub mod gcode;
pub mod interp;
pub mod planner;
pub mod protocol;
pub mod queue;
pub mod ramp;
pub mod report;
pub mod settings;
pub mod sim;
pub mod timing;

/// Timer clock of TIM2 (APB1 at 36 MHz, doubled for timers): one timer tick is 1/72 µs.
pub const TIMER_HZ: u32 = 72_000_000;
/// Timer ticks in one millisecond: the ramp table's time step.
pub const TICKS_PER_MS: u32 = TIMER_HZ / 1000;
/// Most axes a move can have: X Y Z A B C U (one master and six slaves).
pub const MAX_AXES: usize = 7;
/// Axis letters in pin-map order.
pub const AXIS_NAMES: [char; MAX_AXES] = ['X', 'Y', 'Z', 'A', 'B', 'C', 'U'];
