//! The independent watchdog (IWDG, RM0008 §19) and the reset cause (RCC_CSR): registers only;
//! when to feed is `ddastep::watchdog`'s rule.

use ddastep::watchdog::{IWDG_PR, IWDG_RLR};
use stm32f1xx_hal::pac;

// PR is a 3-bit prescaler code, RLR a 12-bit reload value.
const _: () = assert!(IWDG_PR < 8 && IWDG_RLR < 0x1000);


/// Test hook: a bench writes a non-zero word here (symbol `DDASTEP_STALL_IDLE`) to stall the
/// idle loop and prove the watchdog trips. In .bss, so the reset clears it.
#[no_mangle]
static mut DDASTEP_STALL_IDLE: u32 = 0;

fn iwdg() -> &'static pac::iwdg::RegisterBlock {
    // SAFETY: only `init` (start) and `idle` (feed) touch the IWDG, never at the same time.
    unsafe { &*pac::IWDG::ptr() }
}

/// True when the last reset came from the IWDG; clears the reset flags (RMVF) either way.
pub fn take_reset_cause() -> bool {
    // SAFETY: RCC_CSR is read and its flags cleared once, first thing in `init`.
    let rcc = unsafe { &*pac::RCC::ptr() };
    let by_watchdog = rcc.csr().read().iwdgrstf().bit_is_set();
    // RMVF clears every reset flag.
    rcc.csr().modify(|_, w| w.rmvf().set_bit());
    by_watchdog
}

/// Starts the watchdog with `ddastep::watchdog`'s timeout (it cannot be stopped again).
pub fn start() {
    let w = iwdg();
    // The unlock key opens PR and RLR for writing.
    w.kr().write(|k| k.key().unlock());
    w.pr().write(|k| k.pr().set(IWDG_PR as u8));
    w.rlr().write(|k| k.rl().set(IWDG_RLR));
    w.kr().write(|k| k.key().feed());
    w.kr().write(|k| k.key().start());
}

/// Reloads the counter.
pub fn feed() {
    iwdg().kr().write(|k| k.key().feed());
}

/// Spins while the bench's stall flag is set (see [`DDASTEP_STALL_IDLE`]).
pub fn stall_hook() {
    // SAFETY: a volatile read of a word only a debugger/bench writes.
    while unsafe { core::ptr::read_volatile(core::ptr::addr_of!(DDASTEP_STALL_IDLE)) } != 0 {}
}
