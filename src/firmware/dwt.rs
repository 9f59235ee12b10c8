//! The DWT cycle counter: the step interrupt and the DMA fill time themselves with it (`$I`,
//! `ddastep::steptime`).

/// Starts the DWT cycle counter (DEMCR.TRCENA, DWT_CTRL.CYCCNTENA) for the step path's
/// self-measurement.
pub fn start_cycle_counter(dcb: &mut cortex_m::peripheral::DCB, dwt: &mut cortex_m::peripheral::DWT) {
    dcb.enable_trace();
    dwt.enable_cycle_counter();
}

/// DWT_CYCCNT: core cycles, wrapping (one load from the private peripheral bus).
#[inline(always)]
pub fn cycles() -> u32 {
    cortex_m::peripheral::DWT::cycle_count()
}
