//! External interrupt controller, lines 0–15 (RM0008 §10.2): IMR, EMR, RTSR, FTSR, SWIER, PR
//! (rc_w1). AFIO_EXTICR1–4 choose the port of each line. An edge of a GPIO input level (a test,
//! the CLI or the virtual machine driving it) sets the line's pending bit when its edge is
//! enabled; lines 0–4 raise IRQ 6–10 while pending and unmasked, lines 5–9 share IRQ 23 and
//! lines 10–15 IRQ 40 (EXTI15_10: the probe input, PC14). For `mcu.rs`.

/// IRQ number of EXTI line 0 (lines 1–4 follow).
pub const EXTI0_IRQ: u32 = 6;
/// Lines modeled.
pub const LINES: u32 = 16;

/// The IRQ that line `line` raises.
pub const fn irq_of(line: u32) -> u32 {
    match line {
        0..=4 => EXTI0_IRQ + line,
        5..=9 => 23,
        _ => 40,
    }
}

#[derive(Clone, Copy, Debug, Default)]
pub struct Exti {
    imr: u32,
    emr: u32,
    rtsr: u32,
    ftsr: u32,
    pub pr: u32,
}

impl Exti {
    pub fn read(&self, offset: u32) -> u32 {
        match offset {
            0x00 => self.imr,
            0x04 => self.emr,
            0x08 => self.rtsr,
            0x0C => self.ftsr,
            0x14 => self.pr,
            _ => 0,
        }
    }

    pub fn write(&mut self, offset: u32, v: u32) {
        let v = v & 0x7_FFFF;
        match offset {
            0x00 => self.imr = v,
            0x04 => self.emr = v,
            0x08 => self.rtsr = v,
            0x0C => self.ftsr = v,
            0x10 => self.pr |= v & self.imr, // SWIER
            0x14 => self.pr &= !v,
            _ => {}
        }
    }

    // input `line` changed to `level` (its port is the one AFIO selects)
    pub fn edge(&mut self, line: u32, level: bool) {
        let bit = 1 << line;
        let armed = if level { self.rtsr } else { self.ftsr };
        if armed & bit != 0 {
            self.pr |= bit;
        }
    }

    // is line `line`'s interrupt raised?
    pub fn irq(&self, line: u32) -> bool {
        self.pr & self.imr & 1 << line != 0
    }
}
