//! ddastep firmware shell for the STM32F103C8T6 "Blue Pill" (RTIC 2).
//!
//! Thin glue only: `init` sets up clocks, pins, TIM2 and USART1; the TIM2 handler stores the
//! engine's precomputed BSRR word and calls `Stepper::tick`, which pends the ramp interrupt
//! (the TIM4 vector, `Ramper::run`) when it has ramp work; USART1 moves bytes; `idle` runs the
//! line protocol. Everything it calls is in the host-tested library.
//!
//! Priorities: TIM2 (step) above every RTIC task > limit/probe EXTIs 3 > USART1 2 > SysTick and
//! the ramp 1 > idle. The step handler shares nothing behind a lock: the move ring and the
//! engine's two halves share atomics only.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("ddastep is firmware: build it with `cargo build --release` (thumbv7m-none-eabi)");
}

#[cfg(target_os = "none")]
mod firmware;
