//! TIM1 as the spindle PWM on PA8 (TIM1_CH1): written only by `idle` after init.

use ddastep::grbl::settings::Settings;
use ddastep::grbl::spindle::PwmTiming;
use stm32f1xx_hal::pac;

/// TIM1's registers (written only by `idle` after init).
#[inline(always)]
fn tim1() -> &'static pac::tim1::RegisterBlock {
    // SAFETY: only `idle` (one context) writes TIM1 after init; no interrupt uses it.
    unsafe { &*pac::TIM1::ptr() }
}

/// New spindle PWM frequency: prescaler and period, taken at the next update event.
pub fn set_timing(t: PwmTiming) {
    tim1().psc().write(|w| w.psc().set(t.psc));
    // (Preloaded, ARPE: a period is never cut.)
    tim1().arr().write(|w| w.arr().set(t.arr));
}

/// Spindle PWM compare value (preloaded: one whole period at a time).
pub fn set_duty(ccr: u16) {
    tim1().ccr1().write(|w| w.ccr().set(ccr));
}

/// PWM mode 1 on channel 1 with CCR1 preloaded, main output on, duty 0, at the default
/// frequency (the first poll sets `$33`'s).
pub fn setup(rcc: &mut stm32f1xx_hal::rcc::Rcc) {
    use stm32f1xx_hal::rcc::{Enable, Reset};
    pac::TIM1::enable(rcc);
    pac::TIM1::reset(rcc);
    set_timing(PwmTiming::new(Settings::DEFAULT.spindle_pwm_hz));
    let t = tim1();
    t.ccr1().write(|w| w.ccr().set(0));
    t.ccmr1_output().write(|w| w.oc1m().pwm_mode1().oc1pe().enabled());
    // Channel 1 output on, active high.
    t.ccer().write(|w| w.cc1e().set_bit());
    // Main output on: an advanced timer's outputs stay off without it.
    t.bdtr().write(|w| w.moe().set_bit());
    t.egr().write(|w| w.ug().set_bit());
    t.cr1().write(|w| w.arpe().enabled().cen().enabled());
}
