//! Panic and fault handling: drivers off, step pins low, then stop.

use core::panic::PanicInfo;

use ddastep::board;

use super::gpio;

/// Disables the drivers (EN at the level `$4` makes "off": high unless inverted) and drives
/// every step pin low: one BSRR store.
fn safe_outputs() {
    let en = 1u32 << board::ENABLE_PIN;
    let off_high = gpio::ENABLE_OFF_HIGH.load(core::sync::atomic::Ordering::Relaxed);
    let mut word = if off_high { en } else { en << 16 };
    for p in board::STEP_PINS {
        word |= 1 << (p + 16);
    }
    // SAFETY: BSRR takes any word (an atomic set/reset); this one drives only EN and the step pins.
    gpio::gpiob().bsrr().write(|w| unsafe { w.bits(word) });
}

#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    safe_outputs();
    // Neither message nor location: reading `info` keeps every panic site's file name, line and
    // message arguments, with core's integer formatting, in flash (~2 KB); the debugger's
    // backtrace from this frame gives the site.
    defmt::error!("panic");
    loop {
        core::hint::spin_loop();
    }
}

#[cortex_m_rt::exception]
unsafe fn HardFault(_ef: &cortex_m_rt::ExceptionFrame) -> ! {
    safe_outputs();
    defmt::error!("hard fault");
    loop {
        core::hint::spin_loop();
    }
}
