//! TIM3 as the quadrature encoder counter on PA6 (TI1, A) and PA7 (TI2, B): x4 encoder mode
//! (every edge of A and B counts, up or down), both inputs filtered. The 16-bit count is
//! extended to 32 bits by SysTick every millisecond and fresh by the idle loop
//! (`ddastep::encoder::count`); TIM3 raises no interrupt.

use ddastep::encoder::count::{Published, Sampler};
use stm32f1xx_hal::pac;

/// The last SysTick sample (SysTick writes, idle reads).
static ENC: Published = Published::new();

/// CCMR1 (input): CC1S = 01 (IC1 on TI1), CC2S = 01 (IC2 on TI2), IC1F = IC2F = 0011: a level
/// counts once it held for 8 samples of the 72 MHz timer clock (111 ns), so glitches shorter
/// than that are ignored and each input may change every ~111 ns (≤ 18 M counts/s in x4).
const CCMR1_ENCODER: u32 = 0b01 | 0b0011 << 4 | 0b01 << 8 | 0b0011 << 12;

#[inline(always)]
fn tim3() -> &'static pac::tim3::RegisterBlock {
    // SAFETY: TIM3 is set up once in `setup`; afterwards its counter is only read.
    unsafe { &*pac::TIM3::ptr() }
}

/// TIM3 counting PA6/PA7 in x4 encoder mode, full 16-bit range, from 0.
pub fn setup(rcc: &mut stm32f1xx_hal::rcc::Rcc) {
    use stm32f1xx_hal::rcc::{Enable, Reset};
    pac::TIM3::enable(rcc);
    pac::TIM3::reset(rcc);
    let t = tim3();
    // SAFETY: CCMR1 (input): the capture selections and filters named in CCMR1_ENCODER, defined fields only; TIM3 just reset, stopped.
    t.ccmr1_input().write(|w| unsafe { w.bits(CCMR1_ENCODER) });
    // Encoder mode 3: counts on both TI1 and TI2 edges (x4).
    t.smcr().write(|w| w.sms().encoder_mode_3());
    t.arr().write(|w| w.arr().set(u16::MAX));
    t.cr1().write(|w| w.cen().enabled());
}

/// The raw 16-bit count.
#[inline(always)]
fn raw() -> u16 {
    tim3().cnt().read().bits() as u16
}

/// SysTick's sample: extend and keep the speed window.
pub fn sample(s: &mut Sampler) {
    ENC.publish(s.sample(raw()));
}

/// The extended count now and the counts of the last window (idle loop).
pub fn read() -> (i32, i32) {
    (ENC.count_now(raw()), ENC.window())
}
