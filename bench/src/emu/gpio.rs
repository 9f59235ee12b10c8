//! GPIO ports A–E (RM0008 §9): CRL/CRH, IDR, ODR, BSRR, BRR, LCKR. The output latch (ODR)
//! drives the traced pins; inputs read the level a test or CLI set, else the pull-up/down
//! chosen by ODR. A BSRR write changes all its pins at one cycle. For `mcu.rs`.

/// One pin change of an output latch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PinEdge {
    /// Modeled cycle of the store that changed the pin.
    pub cycle: u64,
    /// Port index: 0 = A, 1 = B, ...
    pub port: u8,
    pub pin: u8,
    pub level: bool,
}

/// One GPIO port's registers and external levels (`input::Port` names a port).
#[derive(Default, Clone)]
pub struct GpioPort {
    pub crl: u32,
    pub crh: u32,
    pub odr: u32,
    pub lckr: u32,
    /// Externally driven levels (bit set = high) and which pins are driven.
    pub ext_level: u32,
    pub ext_driven: u32,
}

impl GpioPort {
    // reset state: all pins floating inputs
    pub fn new() -> Self {
        Self { crl: 0x4444_4444, crh: 0x4444_4444, ..Self::default() }
    }

    // is `pin` configured as an output (MODE != 00)?
    pub fn is_output(&self, pin: u32) -> bool {
        let cr = if pin < 8 { self.crl } else { self.crh };
        (cr >> ((pin % 8) * 4)) & 3 != 0
    }

    // input data register: outputs read their latch, inputs the external level or the pull
    pub fn idr(&self) -> u32 {
        let mut v = 0;
        for pin in 0..16 {
            let bit = 1 << pin;
            let high = if self.is_output(pin) {
                self.odr & bit != 0
            } else if self.ext_driven & bit != 0 {
                self.ext_level & bit != 0
            } else {
                let cr = if pin < 8 { self.crl } else { self.crh };
                let cnf = (cr >> ((pin % 8) * 4 + 2)) & 3;
                cnf == 2 && self.odr & bit != 0
            };
            if high {
                v |= bit;
            }
        }
        v
    }

    // register read at `offset`
    pub fn read(&self, offset: u32) -> u32 {
        match offset {
            0x00 => self.crl,
            0x04 => self.crh,
            0x08 => self.idr(),
            0x0C => self.odr,
            0x18 => self.lckr,
            _ => 0,
        }
    }

    // register write at `offset`; returns the new ODR when the latch may have changed
    pub fn write(&mut self, offset: u32, value: u32) -> Option<u32> {
        match offset {
            0x00 => self.crl = value,
            0x04 => self.crh = value,
            0x0C => self.odr = value & 0xFFFF,
            0x10 => self.odr = (self.odr | (value & 0xFFFF)) & !(value >> 16) | (value & 0xFFFF),
            0x14 => self.odr &= !(value & 0xFFFF),
            0x18 => self.lckr = value,
            _ => return None,
        }
        matches!(offset, 0x0C | 0x10 | 0x14).then_some(self.odr)
    }
}
