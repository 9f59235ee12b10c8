//! The independent watchdog (IWDG, RM0008 §19) and the reset cause (RCC_CSR): registers only;
//! when to feed is `ddastep::watchdog`'s rule.

use ddastep::watchdog::{IWDG_PR, IWDG_RLR};
use stm32f1xx_hal::pac;

/// IWDG_KR keys: unlock PR/RLR, reload the counter, start the watchdog.
const KEY_UNLOCK: u16 = 0x5555;
const KEY_RELOAD: u16 = 0xAAAA;
const KEY_START: u16 = 0xCCCC;
/// RCC_CSR: independent-watchdog reset flag, and the bit that clears every reset flag.
const CSR_IWDGRSTF: u32 = 1 << 29;
const CSR_RMVF: u32 = 1 << 24;

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
    let by_watchdog = rcc.csr().read().bits() & CSR_IWDGRSTF != 0;
    // SAFETY: CSR: sets RMVF (clears the reset flags) and keeps the rest; init only.
    rcc.csr().modify(|r, w| unsafe { w.bits(r.bits() | CSR_RMVF) });
    by_watchdog
}

/// Starts the watchdog with `ddastep::watchdog`'s timeout (it cannot be stopped again).
pub fn start() {
    let w = iwdg();
    // SAFETY: KR: the unlock key (RM0008 19.4.1), which enables writes to PR and RLR.
    w.kr().write(|k| unsafe { k.bits(KEY_UNLOCK) });
    // SAFETY: PR: `ddastep::watchdog`'s prescaler code, within its 3 bits.
    w.pr().write(|k| unsafe { k.bits(IWDG_PR) });
    // SAFETY: RLR: `ddastep::watchdog`'s reload value, within its 12 bits.
    w.rlr().write(|k| unsafe { k.bits(IWDG_RLR) });
    // SAFETY: KR: the reload key.
    w.kr().write(|k| unsafe { k.bits(KEY_RELOAD) });
    // SAFETY: KR: the start key (the IWDG cannot be stopped again; that is the point).
    w.kr().write(|k| unsafe { k.bits(KEY_START) });
}

/// Reloads the counter.
pub fn feed() {
    // SAFETY: KR: the reload key; only `idle` feeds, after `init` started the IWDG.
    iwdg().kr().write(|k| unsafe { k.bits(KEY_RELOAD) });
}

/// Spins while the bench's stall flag is set (see [`DDASTEP_STALL_IDLE`]).
pub fn stall_hook() {
    // SAFETY: a volatile read of a word only a debugger/bench writes.
    while unsafe { core::ptr::read_volatile(core::ptr::addr_of!(DDASTEP_STALL_IDLE)) } != 0 {}
}
