//! The step interrupt and the ramp interrupt, bound outside RTIC: no framework code on the step
//! path (no BASEPRI save and restore, no ISB). TIM2 (the engine's step half) sits one level
//! above everything RTIC runs, so nothing delays an edge. The ramp half runs in the TIM4 vector
//! (TIM4 itself stays off: the step interrupt pends the vector when it has ramp work) at RTIC's
//! priority 1, below the serial interrupt: near the rate cap the step interrupt leaves little
//! time, and a ramp run there must not hold off a received byte (the USART keeps one). Its
//! work tolerates the short delays (a trigger's walk down starting some steps late ends a
//! fraction of a walk high). Neither half shares anything with RTIC's resources: `install`
//! moves each in (in `init`, or at rest with the vectors masked) and only its handler touches
//! it until `uninstall` masks the vectors and takes it back.

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;

use ddastep::motion::engine::{Engine, Ramper, Stepper};
use ddastep::steptime::STEP_TIME;
use stm32f1xx_hal::pac::{self, interrupt};

use super::axes::AXES;
use super::dwt::cycles;
use super::gpio::gpiob;
use super::tim2::{tim2, SR_CC1IF, SR_UIF};

/// One half of the engine, owned by its interrupt.
struct Slot<T>(UnsafeCell<MaybeUninit<T>>);

// SAFETY: written by `install` and read back by `uninstall` while its vector is masked (or
// before interrupts are on), otherwise touched only by its handler (one context, never
// re-entered).
unsafe impl<T> Sync for Slot<T> {}

static STEPPER: Slot<Stepper<'static, AXES>> = Slot(UnsafeCell::new(MaybeUninit::uninit()));
static RAMPER: Slot<Ramper<'static, AXES>> = Slot(UnsafeCell::new(MaybeUninit::uninit()));

/// NVIC priority of RTIC's logical priority `p` (4 priority bits, higher logical = lower
/// number): `((1 << 4) - p) << 4`.
pub(super) const fn nvic_priority(p: u8) -> u8 {
    ((1 << pac::NVIC_PRIO_BITS) - p) << (8 - pac::NVIC_PRIO_BITS)
}

/// The vector the ramp half runs in.
const RAMP_IRQ: pac::Interrupt = pac::Interrupt::TIM4;

/// Hands the two halves to their interrupts and enables them (in `init`, interrupts still off,
/// or at rest from `output::rebuild`, TIM2 stopped).
pub fn install(engine: Engine<'static, AXES>, nvic: &mut cortex_m::peripheral::NVIC) {
    let (mut stepper, ramper) = engine.split();
    // The NVIC's ISPR word for the ramp vector (what `NVIC::pend` writes), as a plain store.
    let irq = RAMP_IRQ as usize;
    // SAFETY: the set-pending register is always writable; this bit pends only the ramp vector.
    unsafe {
        let ispr = core::ptr::addr_of!((*cortex_m::peripheral::NVIC::PTR).ispr[irq / 32]);
        stepper.set_pend(ispr.cast::<u32>().cast_mut(), 1 << (irq % 32));
    }
    // SAFETY: both vectors are masked (not yet unmasked, or by `uninstall`): no other access.
    unsafe {
        (*STEPPER.0.get()).write(stepper);
        (*RAMPER.0.get()).write(ramper);
    }
    // SAFETY: the priorities are above RTIC's tasks (TIM2) and at its lowest (the ramp);
    // the halves are in place.
    unsafe {
        nvic.set_priority(pac::Interrupt::TIM2, nvic_priority(4));
        nvic.set_priority(RAMP_IRQ, nvic_priority(1));
        cortex_m::peripheral::NVIC::unmask(RAMP_IRQ);
        cortex_m::peripheral::NVIC::unmask(pac::Interrupt::TIM2);
    }
}

/// Masks both vectors (TIM2 stopped) and takes the halves back, as one engine.
pub fn uninstall() -> Engine<'static, AXES> {
    for irq in [pac::Interrupt::TIM2, RAMP_IRQ] {
        cortex_m::peripheral::NVIC::mask(irq);
        cortex_m::peripheral::NVIC::unpend(irq);
    }
    // SAFETY: `install` wrote both slots (interrupt mode is on); their handlers are masked now,
    // and `install` writes them again before unmasking (the copies read here are the only ones used).
    unsafe { Engine::join((*STEPPER.0.get()).assume_init_read(), (*RAMPER.0.get()).assume_init_read()) }
}

/// The step interrupt: store the precomputed word first, then compute the next one (a tick
/// that leaves the ramp half work pends its interrupt). The body times itself with the DWT cycle
/// counter (`$I` reports it, see `ddastep::steptime`). It runs from SRAM (`.data.ramfunc.*`,
/// copied there with `.data` at boot), as do `Stepper::tick` and the plain step: no flash wait
/// states or refills on the step path (SRAM fetches share the System bus with data instead).
#[interrupt]
#[link_section = ".data.ramfunc.tim2"]
fn TIM2() {
    let t0 = cycles();
    // SAFETY: installed before TIM2 was unmasked; this handler is its only user.
    let engine = unsafe { (*STEPPER.0.get()).assume_init_mut() };
    let sr = tim2().sr().read().bits();
    if sr & SR_UIF != 0 {
        // SAFETY: BSRR takes any word; the engine's word sets and resets only its own step and direction pins.
        gpiob().bsrr().write(|w| unsafe { w.bits(engine.word()) });
        // SAFETY: SR is rc_w0: writing 0 to UIF and 1 elsewhere clears only the update flag.
        tim2().sr().write(|w| unsafe { w.bits(!SR_UIF) });
        let arr = engine.tick_quick();
        // SAFETY: ARR: the engine's next period, a u16, fits the 16-bit counter.
        tim2().arr().write(|w| unsafe { w.bits(arr as u32) });
    }
    // The compare event ends the pulse; if it came while we computed, end it now.
    if tim2().sr().read().bits() & SR_CC1IF != 0 {
        // SAFETY: BSRR takes any word; `step_off` resets only the step pins.
        gpiob().bsrr().write(|w| unsafe { w.bits(engine.step_off()) });
        // SAFETY: SR is rc_w0: writing 0 to CC1IF and 1 elsewhere clears only the compare 1 flag.
        tim2().sr().write(|w| unsafe { w.bits(!SR_CC1IF) });
    }
    STEP_TIME.record(cycles().wrapping_sub(t0));
}

/// The ramp interrupt: the engine's ramp half, preempted by every step.
#[interrupt]
fn TIM4() {
    // SAFETY: installed before the vector was unmasked; this handler is its only user.
    unsafe { (*RAMPER.0.get()).assume_init_mut() }.run();
}
