//! The step interrupt, bound to TIM2 outside RTIC: no framework code on the step path (no
//! BASEPRI save and restore, no ISB), at RTIC's priority 3 like the limit interrupts, so it
//! preempts every RTIC task (their locks go no higher than priority 2) and never preempts a
//! limit interrupt or is preempted by one. It shares nothing with RTIC's resources: the engine
//! is moved in once by `init` (before interrupts are on) and used only here afterwards.

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;

use ddastep::engine::Engine;
use ddastep::steptime::STEP_TIME;
use stm32f1xx_hal::pac::{self, interrupt};

use super::app::AXES;
use super::hw;

/// The engine, owned by the step interrupt.
struct Slot(UnsafeCell<MaybeUninit<Engine<'static, AXES>>>);

// SAFETY: written once by `init` with interrupts off, then touched only by the TIM2 handler
// (one context, never re-entered).
unsafe impl Sync for Slot {}

static ENGINE: Slot = Slot(UnsafeCell::new(MaybeUninit::uninit()));

/// RTIC's logical priority 3 in the NVIC's terms (4 priority bits, higher logical = lower
/// number): `((1 << 4) - 3) << 4`.
const PRIORITY: u8 = ((1 << pac::NVIC_PRIO_BITS) - 3) << (8 - pac::NVIC_PRIO_BITS);

/// Hands the engine to the step interrupt and enables it (in `init`, interrupts still off).
pub fn install(engine: Engine<'static, AXES>, nvic: &mut cortex_m::peripheral::NVIC) {
    // SAFETY: interrupts are off and TIM2's handler has not run yet: no other access.
    unsafe { (*ENGINE.0.get()).write(engine) };
    // SAFETY: the priority is the limit interrupts'; unmasking is what `init` is for.
    unsafe {
        nvic.set_priority(pac::Interrupt::TIM2, PRIORITY);
        cortex_m::peripheral::NVIC::unmask(pac::Interrupt::TIM2);
    }
}

/// The step interrupt: store the precomputed word first, then compute the next one. The body
/// times itself with the DWT cycle counter (`$I` reports it, see `ddastep::steptime`).
#[interrupt]
fn TIM2() {
    let t0 = hw::cycles();
    // SAFETY: installed before TIM2 was unmasked; this handler is its only user.
    let engine = unsafe { (*ENGINE.0.get()).assume_init_mut() };
    let sr = hw::tim2().sr().read().bits();
    if sr & hw::SR_UIF != 0 {
        hw::gpiob().bsrr().write(|w| unsafe { w.bits(engine.word()) });
        hw::tim2().sr().write(|w| unsafe { w.bits(!hw::SR_UIF) });
        let arr = engine.tick();
        hw::tim2().arr().write(|w| unsafe { w.bits(arr as u32) });
    }
    // The compare event ends the pulse; if it came while we computed, end it now.
    if hw::tim2().sr().read().bits() & hw::SR_CC1IF != 0 {
        hw::gpiob().bsrr().write(|w| unsafe { w.bits(engine.step_off()) });
        hw::tim2().sr().write(|w| unsafe { w.bits(!hw::SR_CC1IF) });
    }
    STEP_TIME.record(hw::cycles().wrapping_sub(t0));
}
