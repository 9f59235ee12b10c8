//! The DWT cycle counter (CYCCNT) as the firmware's self-timing reads it. For the MMIO dispatch.

/// DWT cycle counter: counts core cycles while DEMCR.TRCENA and DWT_CTRL.CYCCNTENA are set,
/// holds its value otherwise (ARMv7-M ARM C1.8.8). Sleep is not distinguished: it counts
/// through WFI like the bench's clock.
#[derive(Clone, Copy, Debug, Default)]
pub struct Dwt {
    pub ctrl: u32,
    running: bool,
    /// Cycle at which a running counter read 0 (mod 2^32).
    base: u64,
    /// Value while stopped.
    held: u32,
}

impl Dwt {
    // CYCCNT at cycle `t`
    pub fn cyccnt(&self, t: u64) -> u32 {
        if self.running {
            t.wrapping_sub(self.base) as u32
        } else {
            self.held
        }
    }

    // new CTRL / DEMCR (and optionally a CYCCNT write) at cycle `t`
    pub(super) fn set(&mut self, t: u64, ctrl: u32, demcr: u32, cyccnt: Option<u32>) {
        let value = cyccnt.unwrap_or_else(|| self.cyccnt(t));
        self.ctrl = ctrl;
        self.running = ctrl & 1 != 0 && demcr & 1 << 24 != 0;
        self.held = value;
        self.base = t.wrapping_sub(value as u64);
    }
}
