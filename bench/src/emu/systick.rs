//! SysTick (ARMv7-M B3.3), evaluated lazily from the cycle of its next wrap to zero. For the
//! PPB bus and the run loop. CLKSOURCE = 1 counts core cycles, 0 counts HCLK/8.

/// SysTick registers and the time of the next wrap.
#[derive(Default)]
pub struct SysTick {
    csr: u32,
    rvr: u32,
    /// Cycle at which the counter next reaches 0 (valid while enabled).
    zero_at: u64,
    /// Counter value when disabled.
    held: u32,
    pub wraps: u64,
}

impl SysTick {
    fn enabled(&self) -> bool {
        self.csr & 1 != 0
    }

    fn tick(&self) -> u64 {
        if self.csr & 4 != 0 {
            1
        } else {
            8
        }
    }

    // the cycle of the next wrap to zero, if counting
    pub fn next_event(&self) -> Option<u64> {
        (self.enabled() && self.rvr != 0).then_some(self.zero_at)
    }

    // replay wraps up to cycle `t`; returns how many raised the exception (TICKINT)
    pub fn advance(&mut self, t: u64) -> u64 {
        let mut raised = 0;
        while let Some(z) = self.next_event() {
            if z > t {
                break;
            }
            self.csr |= 1 << 16;
            self.wraps += 1;
            if self.csr & 2 != 0 {
                raised += 1;
            }
            self.zero_at = z + (self.rvr as u64 + 1) * self.tick();
        }
        raised
    }

    fn current(&self, t: u64) -> u32 {
        if !self.enabled() {
            return self.held;
        }
        let left = self.zero_at.saturating_sub(t);
        (left.div_ceil(self.tick()) as u32).min(self.rvr)
    }

    // register read at `offset` from 0xE000_E010
    pub fn read(&mut self, offset: u32, t: u64) -> u32 {
        match offset {
            0x0 => {
                let v = self.csr;
                self.csr &= !(1 << 16);
                v
            }
            0x4 => self.rvr,
            0x8 => self.current(t),
            0xC => 0x4000_0000 | 8999, // CALIB: no reference clock, 1 ms at 9 MHz
            _ => 0,
        }
    }

    // register write at `offset` from 0xE000_E010
    pub fn write(&mut self, offset: u32, value: u32, t: u64) {
        match offset {
            0x0 => {
                let was = self.enabled();
                let cur = self.current(t);
                self.csr = (self.csr & (1 << 16)) | (value & 7);
                if self.enabled() && !was {
                    self.zero_at = t + cur as u64 * self.tick();
                    if cur == 0 {
                        self.zero_at = t + (self.rvr as u64 + 1) * self.tick();
                    }
                } else if !self.enabled() {
                    self.held = cur;
                }
            }
            0x4 => self.rvr = value & 0x00FF_FFFF,
            0x8 => {
                self.csr &= !(1 << 16);
                self.held = 0;
                self.zero_at = t + (self.rvr as u64 + 1) * self.tick();
            }
            _ => {}
        }
    }
}
