//! ddastep: a multi-axis step/direction pulse generator for one STM32F103 "Blue Pill".
//!
//! This library is the whole controller but the hardware shell, free of HAL and PAC types so
//! that every line the firmware runs is also run by host tests. It is organised by layer:
//!
//! - [`motion`]: the motion core the step interrupt runs — DDA interpolator, ramp tables and
//!   their walk, prepared moves and their ring, the control word, step engine, shared state,
//!   driver timing, and a TIM2 model for host tests.
//! - [`planning`]: the planner that turns targets into moves, the look-ahead that joins them,
//!   and the feeder that prepares them for the step interrupt.
//! - [`grbl`]: the Grbl 1.1 front end — protocol, G-code, settings, reports, controller.
//! - [`board`]: the Blue Pill pin map as numbers (the firmware shell in `src/firmware/`
//!   turns it into registers).
//! - [`encoder`]: encoder feedback — TIM3 count extension, speed, step-loss detection.
//! - [`error`]: Grbl's numbered errors, the one error type (a leaf: every layer returns it).
//! - [`steptime`]: the step interrupt's self-measurement (DWT cycles), reported by `$I`.
//!
//! Nothing is re-exported at the crate root: a path names its layer (`ddastep::motion::engine`).
#![no_std]
#![cfg_attr(not(test), deny(warnings))]

pub mod board;
pub mod encoder;
pub mod error;
pub mod grbl;
pub mod motion;
pub mod num;
pub mod planning;
pub mod steptime;
pub mod watchdog;


/// Timer clock of TIM2 (APB1 at 36 MHz, doubled for timers): one timer tick is 1/72 µs.
pub const TIMER_HZ: u32 = 72_000_000;
/// Timer ticks in one millisecond: the ramp table's time step.
pub const TICKS_PER_MS: u32 = TIMER_HZ / 1000;
/// Most axes a move can have: X Y Z A B C U (one master and six slaves).
pub const MAX_AXES: usize = 7;
/// Axis letters in pin-map order.
pub const AXIS_NAMES: [char; MAX_AXES] = ['X', 'Y', 'Z', 'A', 'B', 'C', 'U'];
