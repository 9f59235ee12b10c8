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
//! - [`usb`]: the USB CDC ACM device side (descriptors, control requests, bulk IN packets),
//!   HAL-free; the firmware glue moves its packets through stm32-usbd.
//!
//! Nothing is re-exported at the crate root: a path names its layer (`ddastep::motion::engine`).
//!
//! # Driving the engine from another firmware
//!
//! The firmware shell (`src/firmware/`) is one way to run the library; another firmware can
//! wire up the same pieces. `examples/step_move.rs` does it on the host, with seed 001's
//! per-motor `step_move(id, steps, freq)` and the 5:3:2 move one call each
//! (`cargo run --example step_move --target host-tuple` prints the first BSRR words and the
//! counts). The pieces, all `static` on a board:
//!
//! 1. **Shared state and profile:** a [`motion::shared::Shared`] (positions, state, hold and
//!    stop requests) and a [`motion::ramp::RampSlot`]; through
//!    [`RampSlot::try_write`](motion::ramp::RampSlot::try_write) build its ramp table
//!    ([`RampTable::build`](motion::ramp::RampTable::build) from a
//!    [`RampConfig`](motion::ramp::RampConfig): start rate, top rate, acceleration, shape) and
//!    set its [`Timing`](motion::timing::Timing) (pulse width, direction setup, shortest
//!    period, in timer ticks of 1/72 µs).
//! 2. **The queue:** split a [`motion::ring::MoveRing`] into its producer and consumer; the
//!    producer goes to a [`planning::feeder::Feeder`] (with a
//!    [`planning::lookahead::Buffer`] and the pin map [`board::pin_map`]), the consumer to a
//!    [`motion::engine::Engine`], which [`Engine::split`](motion::engine::Engine::split)s into
//!    the step half ([`motion::engine::Stepper`]) and the ramp half
//!    ([`motion::engine::Ramper`]).
//! 3. **Plan a move:** [`motion::moves::Move::new`]`(steps, cruise_hz)` (signed steps per axis,
//!    the rate of the axis with the most steps; the others follow in exact ratio) and
//!    [`Feeder::push`](planning::feeder::Feeder::push) it; call
//!    [`Feeder::service`](planning::feeder::Feeder::service) from the idle loop. (The Grbl
//!    front end's planner, [`planning::planner`], makes moves from G-code targets in mm.)
//! 4. **The step interrupt** (TIM2 update, prescaler 0, ARR preloaded): store
//!    [`Stepper::word`](motion::engine::Stepper::word) into the step port's BSRR first, then
//!    write the value [`Stepper::tick`](motion::engine::Stepper::tick) (or `tick_quick`)
//!    returns into ARR; at the compare event `pulse_ticks` later store
//!    [`Stepper::step_off`](motion::engine::Stepper::step_off) into BSRR (the falling edges).
//!    The pins are those of [`board`] (all step and direction pins on one port).
//! 5. **The ramp interrupt:** a lower-priority vector that the step half pends
//!    ([`Stepper::set_pend`](motion::engine::Stepper::set_pend) gives it the NVIC's ISPR word
//!    and bit) and that runs [`Ramper::run`](motion::engine::Ramper::run).
//!
//! [`motion::engine`] states the contract of one tick; [`motion::tim2_model`] is the host model
//! of the timer the tests (and the example) drive the engine with.
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
pub mod usb;
pub mod watchdog;


/// Timer clock of TIM2 (APB1 at 36 MHz, doubled for timers): one timer tick is 1/72 µs.
pub const TIMER_HZ: u32 = 72_000_000;
/// Timer ticks in one millisecond: the ramp table's time step.
pub const TICKS_PER_MS: u32 = TIMER_HZ / 1000;
/// Most axes a move can have: X Y Z A B C U (one master and six slaves).
pub const MAX_AXES: usize = 7;
/// Axis letters in pin-map order.
pub const AXIS_NAMES: [char; MAX_AXES] = ['X', 'Y', 'Z', 'A', 'B', 'C', 'U'];
