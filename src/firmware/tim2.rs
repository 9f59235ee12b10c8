//! TIM2, the step timer, and DMA1, which it drives in burst mode: setup, start, the dual-edge
//! and DMA variants. The step interrupt (`step.rs`) and the DMA fill (`burst.rs`) own these
//! registers after init.

use ddastep::motion::engine::IDLE_TICKS;
use ddastep::motion::timing::{Timing, STORE_LATENCY_TICKS};
use stm32f1xx_hal::pac;

use super::gpio::gpiob;

/// TIM2 status: update interrupt flag.
pub const SR_UIF: u32 = 1 << 0;
/// TIM2 status: capture/compare 1 interrupt flag.
pub const SR_CC1IF: u32 = 1 << 1;

/// TIM2's registers (owned by the step interrupt after `init`).
#[inline(always)]
pub fn tim2() -> &'static pac::tim2::RegisterBlock {
    // SAFETY: a shared reference to MMIO; every access is one volatile load or store. After
    // init the step interrupt writes SR and ARR, `pulse` (idle) only CCR1, which is preloaded,
    // and the limit handler stops the timer (CR1, DIER, SR); `output::rebuild` (idle) sets it
    // up again only once it is stopped and its interrupts are masked.
    unsafe { &*pac::TIM2::ptr() }
}

/// DMA mode: compare 3 (the period store) one tick after the update.
const PERIOD_STORE_TICK: u16 = 1;

/// TIM2 DIER: DMA requests on update, compare 1, compare 3.
const DIER_UDE: u32 = 1 << 8;
const DIER_CC1DE: u32 = 1 << 9;
const DIER_CC3DE: u32 = 1 << 11;

/// DMA1's registers (the fill interrupt owns channel 1's flags after `init`).
#[inline(always)]
pub fn dma1() -> &'static pac::dma1::RegisterBlock {
    // SAFETY: after init only the fill interrupt touches DMA1 (ISR read, IFCR write), and
    // `burst::uninstall` (idle) once the fill interrupt is masked.
    unsafe { &*pac::DMA1::ptr() }
}

/// DMA burst mode (`ddastep::motion::burst`): TIM2 without interrupts, its update event storing
/// `words[k]` into GPIOB's BSRR (channel 2), its compare 3 event storing `periods[k]` into ARR
/// (channel 1, with the fill interrupt at each half), and with full pulses its compare 1
/// event, `fall` ticks after the update, storing `*off` into BSRR (channel 5). `n` entries,
/// circular; the first period is `first` ticks.
pub fn setup_dma(words: u32, periods: u32, off: u32, n: u32, first: u32, fall: u32, dual: bool) {
    // SAFETY: one bit of the clock enables (DMA1EN), set once in init, interrupts off.
    unsafe { (*pac::RCC::ptr()).ahbenr().modify(|_, w| w.dma1en().set_bit()) };
    let t = tim2();
    // Every TIM2 interrupt and DMA request off (DIER's reset value).
    t.dier().reset();
    // SAFETY: ARR: `first` is the layout's longest entry, which fits the 16-bit counter.
    t.arr().write(|w| unsafe { w.bits(first - 1) });
    // Compare 3 frozen, not preloaded (CCMR2's reset value), one tick after the update: the
    // period store.
    t.ccmr2_output().reset();
    t.ccr3().write(|w| w.ccr().set(PERIOD_STORE_TICK));
    // SAFETY: CCR1: the falling edge's compare value, inside the 16-bit period.
    t.ccr1().write(|w| unsafe { w.bits(fall) });
    t.egr().write(|w| w.ug().set_bit());
    // Counting starts past compare 3, so the first period store follows the first update.
    t.cnt().write(|w| w.cnt().set(PERIOD_STORE_TICK + 1));
    // Every flag cleared (SR's reset value).
    t.sr().reset();
    // DMA CCRx: memory to peripheral (DIR), circular, memory increment, very high priority, on.
    const DIR: u32 = 1 << 4;
    const CIRC: u32 = 1 << 5;
    const MINC: u32 = 1 << 7;
    const P32: u32 = 0b10 << 8;
    const M16: u32 = 0b01 << 10;
    const M32: u32 = 0b10 << 10;
    const VERY_HIGH: u32 = 0b11 << 12;
    const HTIE: u32 = 1 << 2;
    const TCIE: u32 = 1 << 1;
    const EN: u32 = 1;
    let gpiob_bsrr = gpiob().bsrr().as_ptr() as u32;
    let dma = dma1();
    let channel = |ch: &pac::dma1::CH, par: u32, mar: u32, n: u32, cr: u32| {
        // Channel off first (CR's reset value): PAR, MAR and NDTR are writable only while EN is 0.
        ch.cr().reset();
        // SAFETY: PAR: a 32-bit peripheral register (GPIOB_BSRR or TIM2_ARR) that DMA may store into.
        ch.par().write(|w| unsafe { w.bits(par) });
        // SAFETY: MAR: a static buffer of `burst` (never freed) that DMA only reads.
        ch.mar().write(|w| unsafe { w.bits(mar) });
        // SAFETY: NDTR: the entry count, at most 2 · HALF_MAX, within its 16 bits.
        ch.ndtr().write(|w| unsafe { w.bits(n) });
        // SAFETY: CR: the named mode bits above (defined fields only) plus EN, which starts the channel.
        ch.cr().write(|w| unsafe { w.bits(cr | EN) });
    };
    channel(dma.ch2(), gpiob_bsrr, words, n, DIR | CIRC | MINC | P32 | M32 | VERY_HIGH);
    channel(dma.ch1(), t.arr().as_ptr() as u32, periods, n, DIR | CIRC | MINC | P32 | M16 | VERY_HIGH | HTIE | TCIE);
    let mut dier = DIER_UDE | DIER_CC3DE;
    if !dual {
        channel(dma.ch5(), gpiob_bsrr, off, 1, DIR | CIRC | P32 | M32 | VERY_HIGH);
        dier |= DIER_CC1DE;
    }
    // SAFETY: DIER: the DMA request enables named above, no interrupt enable.
    t.dier().write(|w| unsafe { w.bits(dier) });
}

/// Dual-edge mode: no compare event (interrupt off, CCR1 past every period the engine sets).
pub fn no_falling_edge() {
    tim2().dier().write(|w| w.uie().set_bit());
    tim2().ccr1().write(|w| w.ccr().set(u16::MAX));
}

/// The idle period (ARR) and the default pulse's falling edge (CCR1) TIM2 starts with.
const IDLE_ARR: u16 = (IDLE_TICKS - 1) as u16;
const DEFAULT_CCR1: u16 = (Timing::DEFAULT.pulse_ticks + STORE_LATENCY_TICKS) as u16;
const _: () = assert!(IDLE_TICKS - 1 <= 0xFFFF && DEFAULT_CCR1 as u32 == Timing::DEFAULT.pulse_ticks + STORE_LATENCY_TICKS);

/// TIM2 as the step timer: 72 MHz, no prescaler, buffered ARR, update and compare-1 interrupts.
pub fn setup(rcc: &mut stm32f1xx_hal::rcc::Rcc) {
    use stm32f1xx_hal::rcc::{Enable, Reset};
    pac::TIM2::enable(rcc);
    pac::TIM2::reset(rcc);
    configure();
}

/// TIM2's registers for interrupt mode, stopped (at boot, and when the output is rebuilt).
pub fn configure() {
    let t = tim2();
    t.psc().write(|w| w.psc().set(0));
    t.arr().write(|w| w.arr().set(IDLE_ARR));
    // Compare 1 "frozen" (no pin), CCR1 preloaded so a new pulse width starts at an update.
    t.ccmr1_output().write(|w| w.oc1pe().enabled());
    t.ccr1().write(|w| w.ccr().set(DEFAULT_CCR1));
    t.egr().write(|w| w.ug().set_bit());
    t.sr().reset();
    t.dier().write(|w| w.uie().enabled().cc1ie().enabled());
    // Counting starts in `start`.
    t.cr1().write(|w| w.arpe().enabled().urs().counter_only());
}

/// Stops TIM2: the counter, every interrupt and DMA request, the flags (the output is rebuilt
/// next; the step pins stay as they are).
pub fn stop() {
    let t = tim2();
    t.cr1().modify(|_, w| w.cen().disabled());
    t.dier().reset();
    t.sr().reset();
}

/// Starts TIM2 counting: the last thing `init` does, so the first update event does not wait
/// behind the rest of init (which runs with interrupts off).
pub fn start() {
    tim2().cr1().modify(|_, w| w.cen().enabled());
}
