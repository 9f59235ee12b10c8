//! NVIC and SCB state: which exceptions are pending, enabled and active, their priorities,
//! and the decision "may exception N preempt now?". Unicorn has no NVIC, so the bench keeps
//! this and `exception.rs` does the stacking. For the run loop and the PPB register bus.
//!
//! Exception numbers follow the ARMv7-M convention: 15 = SysTick, 16 + n = IRQ n.
//! Priorities are 8-bit with 4 implemented bits (STM32F1: top nibble). Group priority uses
//! AIRCR.PRIGROUP. Peripheral IRQ lines are level inputs: while a line is high and the IRQ is
//! not active it is pending, as on the real NVIC.

/// Exception number of SysTick.
pub const SYSTICK: u32 = 15;
/// Exception number of PendSV.
pub const PENDSV: u32 = 14;
/// Exception number of SVCall.
pub const SVCALL: u32 = 11;
/// Exception number of IRQ 0.
pub const IRQ0: u32 = 16;
/// Exceptions modeled (68 IRQs on the STM32F103 plus 16 system exceptions, rounded up).
pub const COUNT: usize = 96;
/// Implemented priority bits mask (4 bits, top nibble).
const PRIO_MASK: u8 = 0xF0;

/// NVIC + SCB exception state.
pub struct Nvic {
    pub enabled: [bool; COUNT],
    pub pending: [bool; COUNT],
    /// Peripheral interrupt request lines (level).
    pub level: [bool; COUNT],
    pub active: [bool; COUNT],
    /// Held back by the bench (`Board::hold_irq`), whatever the firmware enabled: for tests of
    /// what the firmware does when an interrupt comes late.
    pub held: [bool; COUNT],
    pub priority: [u8; COUNT],
    /// Active exceptions, innermost last.
    pub stack: Vec<u32>,
    pub vtor: u32,
    pub aircr_prigroup: u32,
    pub scr: u32,
    pub ccr: u32,
}

impl Default for Nvic {
    fn default() -> Self {
        Self {
            enabled: [false; COUNT],
            pending: [false; COUNT],
            level: [false; COUNT],
            active: [false; COUNT],
            held: [false; COUNT],
            priority: [0; COUNT],
            stack: Vec::new(),
            vtor: 0,
            aircr_prigroup: 0,
            scr: 0,
            ccr: 0x200,
        }
    }
}

impl Nvic {
    // the exception number now executing (0 = thread mode)
    pub fn ipsr(&self) -> u32 {
        self.stack.last().copied().unwrap_or(0)
    }

    // is exception `n` pending (sticky bit or a high level line)?
    pub fn is_pending(&self, n: usize) -> bool {
        self.pending[n] || (self.level[n] && !self.active[n])
    }

    // is exception `n` enabled (system exceptions always are)?
    fn is_enabled(&self, n: usize) -> bool {
        n < IRQ0 as usize || (self.enabled[n] && !self.held[n])
    }

    // group priority of exception `n` (lower = more urgent); fixed ones are negative
    fn group(&self, n: usize) -> i32 {
        match n {
            1 => -3,
            2 => -2,
            3 => -1,
            _ => (self.priority[n] & PRIO_MASK & self.group_mask()) as i32,
        }
    }

    fn group_mask(&self) -> u8 {
        (0xFFu32 << (self.aircr_prigroup + 1)) as u8
    }

    // current execution priority from active exceptions, BASEPRI and PRIMASK (256 = thread)
    pub fn execution_priority(&self, basepri: u32, primask: bool) -> i32 {
        let mut prio = 256;
        for &n in &self.stack {
            prio = prio.min(self.group(n as usize));
        }
        let basepri = basepri as u8 & PRIO_MASK;
        if basepri != 0 {
            prio = prio.min((basepri & self.group_mask()) as i32);
        }
        if primask {
            prio = prio.min(0);
        }
        prio
    }

    // the most urgent pending and enabled exception (lowest group, then lowest number)
    pub fn best_pending(&self) -> Option<u32> {
        let mut best: Option<(i32, usize)> = None;
        for n in 1..COUNT {
            if self.is_pending(n) && self.is_enabled(n) {
                let g = self.group(n);
                if best.is_none_or(|(bg, _)| g < bg) {
                    best = Some((g, n));
                }
            }
        }
        best.map(|(_, n)| n as u32)
    }

    // the exception that preempts now, if any
    pub fn preempting(&self, basepri: u32, primask: bool) -> Option<u32> {
        let n = self.best_pending()?;
        (self.group(n as usize) < self.execution_priority(basepri, primask)).then_some(n)
    }

    // true when some exception is pending and enabled (cheap pre-check)
    pub fn any_pending(&self) -> bool {
        self.best_pending().is_some()
    }

    // mark `n` active on exception entry
    pub fn activate(&mut self, n: u32) {
        self.pending[n as usize] = false;
        self.active[n as usize] = true;
        self.stack.push(n);
    }

    // deactivate the innermost exception on return; returns its number
    pub fn deactivate(&mut self) -> u32 {
        let n = self.stack.pop().unwrap_or(0);
        self.active[n as usize] = false;
        n
    }

    // read an NVIC/SCB register at `offset` from 0xE000_E000 (`None` if not modeled here)
    pub fn read(&self, offset: u32) -> Option<u32> {
        let bits = |f: &dyn Fn(usize) -> bool, base: u32| {
            let first = ((offset - base) * 8) as usize;
            (0..32).filter(|i| first + i + 16 < COUNT && f(first + i + 16)).fold(0u32, |v, i| v | 1 << i)
        };
        Some(match offset {
            0x100..=0x11C => bits(&|n| self.enabled[n], 0x100),
            0x180..=0x19C => bits(&|n| self.enabled[n], 0x180),
            0x200..=0x21C => bits(&|n| self.is_pending(n), 0x200),
            0x280..=0x29C => bits(&|n| self.is_pending(n), 0x280),
            0x300..=0x31C => bits(&|n| self.active[n], 0x300),
            0x400..=0x4EC => {
                let first = (offset - 0x400) as usize + 16;
                (0..4).fold(0, |v, i| v | (*self.priority.get(first + i).unwrap_or(&0) as u32) << (8 * i))
            }
            0xD04 => self.icsr(),
            0xD08 => self.vtor,
            0xD0C => 0xFA05_0000 | self.aircr_prigroup << 8,
            0xD10 => self.scr,
            0xD14 => self.ccr,
            0xD18..=0xD20 => {
                let first = (offset - 0xD18) as usize + 4;
                (0..4).fold(0, |v, i| v | (self.priority[first + i] as u32) << (8 * i))
            }
            _ => return None,
        })
    }

    fn icsr(&self) -> u32 {
        let vectpending = self.best_pending().unwrap_or(0);
        let mut v = self.ipsr() | vectpending << 12;
        if (IRQ0 as usize..COUNT).any(|n| self.is_pending(n)) {
            v |= 1 << 22;
        }
        if self.pending[PENDSV as usize] {
            v |= 1 << 28;
        }
        if self.pending[SYSTICK as usize] {
            v |= 1 << 26;
        }
        if self.stack.len() <= 1 {
            v |= 1 << 11; // RETTOBASE
        }
        v
    }

    // write an NVIC/SCB register (`value` already merged to a full word); false if unknown
    pub fn write(&mut self, offset: u32, value: u32) -> bool {
        let mut each = |base: u32, f: &mut dyn FnMut(&mut Self, usize)| {
            let first = ((offset - base) * 8) as usize;
            for i in 0..32 {
                if value & 1 << i != 0 && first + i + 16 < COUNT {
                    f(self, first + i + 16);
                }
            }
        };
        match offset {
            0x100..=0x11C => each(0x100, &mut |s, n| s.enabled[n] = true),
            0x180..=0x19C => each(0x180, &mut |s, n| s.enabled[n] = false),
            0x200..=0x21C => each(0x200, &mut |s, n| s.pending[n] = true),
            0x280..=0x29C => each(0x280, &mut |s, n| s.pending[n] = false),
            0x400..=0x4EC => {
                let first = (offset - 0x400) as usize + 16;
                for i in 0..4 {
                    if first + i < COUNT {
                        self.priority[first + i] = (value >> (8 * i)) as u8 & PRIO_MASK;
                    }
                }
            }
            0xF00 => {
                let n = (value & 0x1FF) as usize + 16;
                if n < COUNT {
                    self.pending[n] = true;
                }
            }
            0xD04 => {
                if value & 1 << 28 != 0 {
                    self.pending[PENDSV as usize] = true;
                }
                if value & 1 << 27 != 0 {
                    self.pending[PENDSV as usize] = false;
                }
                if value & 1 << 26 != 0 {
                    self.pending[SYSTICK as usize] = true;
                }
                if value & 1 << 25 != 0 {
                    self.pending[SYSTICK as usize] = false;
                }
            }
            0xD08 => self.vtor = value & 0xFFFF_FF80,
            0xD0C => {
                if value >> 16 == 0x05FA {
                    self.aircr_prigroup = (value >> 8) & 7;
                }
            }
            0xD10 => self.scr = value & 0x16,
            0xD14 => self.ccr = value,
            0xD18..=0xD20 => {
                let first = (offset - 0xD18) as usize + 4;
                for i in 0..4 {
                    self.priority[first + i] = (value >> (8 * i)) as u8 & PRIO_MASK;
                }
            }
            _ => return false,
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basepri_masks_equal_and_lower_urgency() {
        let mut nvic = Nvic::default();
        nvic.write(0x100, 1 << 28); // enable IRQ 28
        nvic.write(0x41C, 0x20); // IRQ 28 priority 0x20
        nvic.write(0x200, 1 << 28);
        assert_eq!(nvic.preempting(0, false), Some(IRQ0 + 28));
        assert_eq!(nvic.preempting(0x20, false), None);
        assert_eq!(nvic.preempting(0x30, false), Some(IRQ0 + 28));
        assert_eq!(nvic.preempting(0, true), None);
    }
}
