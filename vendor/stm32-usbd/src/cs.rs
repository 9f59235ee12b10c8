//! ddastep's patch of stm32-usbd 0.8.0 (with the `crate::cs::free` calls that replace
//! `cortex_m::interrupt::free` in bus.rs and endpoint.rs; besides, `UsbBus::new_bare` and
//! `NUM_ENDPOINTS` = 3): the driver's critical sections raise BASEPRI to the lowest interrupt
//! priority instead of setting PRIMASK, so they never hold off an interrupt above it. On ddastep
//! every use of the driver runs in `init` or in the USB interrupt at RTIC's lowest priority (1), so
//! nothing that could preempt them touches it; the step interrupt (above RTIC) is no longer delayed
//! by a packet copy (bench/benches/usb_link.rs measured up to 1 744 modeled cycles with PRIMASK).

use cortex_m::interrupt::CriticalSection;

/// BASEPRI of the lowest of the 16 priority levels (RTIC's priority 1 on the F103's 4 bits).
const LOWEST: u8 = 0xF0;

/// Runs `f` with the interrupts at the lowest priority level masked.
#[inline]
pub fn free<R>(f: impl FnOnce(&CriticalSection) -> R) -> R {
    let old = cortex_m::register::basepri::read();
    // SAFETY: raising BASEPRI only masks; the previous value is restored below.
    unsafe { cortex_m::register::basepri_max::write(LOWEST) };
    // SAFETY: every context that uses this driver runs at or below LOWEST (see the module
    // note), and those are masked now.
    let r = f(unsafe { &CriticalSection::new() });
    // SAFETY: restores the level this function found.
    unsafe { cortex_m::register::basepri::write(old) };
    r
}
