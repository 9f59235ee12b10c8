//! The step pulse's width: TIM2's compare 1 (the falling edge) in interrupt or DMA burst mode.

use ddastep::motion::timing::STORE_LATENCY_TICKS;

use super::burst;
use super::tim2::tim2;

/// New step pulse width: CCR1 is preloaded, so it takes effect at the next update event.
/// Nothing in dual-edge mode (`tim2::no_falling_edge`: the compare interrupt is off). `false` when
/// DMA burst mode's buffers cannot hold the pulse (their layout follows it: a rebuild).
pub fn set_pulse_ticks(ticks: u32) -> bool {
    let dier = tim2().dier().read();
    let ccr = if burst::active() {
        if dier.cc1de().bit_is_clear() {
            return true;
        }
        let Some(fall) = burst::fall_ticks(ticks) else { return false };
        fall
    } else {
        if dier.cc1ie().bit_is_clear() {
            return true;
        }
        ticks + STORE_LATENCY_TICKS
    };
    // (Preloaded: the step interrupt's period sees it from the next update.)
    tim2().ccr1().write(|w| w.ccr().set(ccr.min(0xFFFF) as u16));
    true
}
