//! The MMIO dispatch: unicorn's read and write callbacks routed to the peripheral models at
//! the access's cycle (bridge stalls included), GPIO stores traced as pin edges, input edges
//! into EXTI and the encoder timer, and plain registers for everything without a model.
//!
//! Registers with no model keep what was written (so read-modify-write works), read 0 until
//! then, and are logged once with address and PC.

use super::address::*;
use super::{Mcu, TIM2_IRQ};
use crate::emu::exti;
use crate::emu::gpio::PinEdge;
use crate::emu::iwdg;
use crate::emu::memory::FlashConfig;
use crate::emu::nvic::IRQ0;

/// GPIOA pins of TIM3's encoder inputs TI1, TI2.
const ENCODER_PINS: [u8; 2] = ddastep::board::ENCODER_PINS;
/// DWT_CTRL.NUMCOMP of a Cortex-M3 (4 comparators), read-only.
const DWT_NUMCOMP_4: u32 = 4 << 28;

impl Mcu {
    // MMIO read of `size` bytes at `addr`
    pub fn read(&mut self, addr: u32, size: usize) -> u32 {
        let issued = self.access_cycle();
        // A read through a bridge stalls the core until the data is back.
        let t = match self.bridge(addr, issued) {
            Some((_, end)) => {
                self.stall += end - issued;
                end
            }
            None => issued,
        };
        self.sync(t);
        let word = addr & !3;
        let shift = (addr & 3) * 8;
        let v = self.read_reg(word, t);
        self.sync(t);
        let mask = if size >= 4 { u32::MAX } else { (1u32 << (8 * size)) - 1 };
        (v >> shift) & mask
    }

    // the register (word) at `word` read at cycle `t`, by the CPU or the DMA
    pub(in crate::emu) fn read_reg(&mut self, word: u32, t: u64) -> u32 {
        match word {
            TIM2..=0x4000_03FF => self.tim2.read(word - TIM2, t),
            DMA1..=0x4002_03FF => self.dma.read(word - DMA1),
            TIM1..=0x4001_2FFF => self.tim1.read(word - TIM1),
            TIM3..=0x4000_07FF => self.tim3.read(word - TIM3, t),
            USART1..=0x4001_3BFF => self.usart1.read(word - USART1, t),
            USB..=0x4000_5FFF => self.usb.read(word - USB),
            USB_PMA..=0x4000_63FF => self.usb.pma_read(word - USB_PMA),
            IWDG..=0x4000_33FF => self.iwdg.read(word - IWDG),
            EXTI..=0x4001_07FF => self.exti.read(word - EXTI),
            GPIOA..=0x4001_1BFF => {
                let p = ((word - GPIOA) / 0x400) as usize;
                self.ports[p].read((word - GPIOA) % 0x400)
            }
            0xE000_E010..=0xE000_E01F => self.systick.read(word - 0xE000_E010, t),
            DWT_CTRL => self.dwt.ctrl | DWT_NUMCOMP_4,
            DWT_CYCCNT => self.dwt.cyccnt(t),
            CPUID => self.cpuid,
            SCS..=0xE000_EFFF if self.nvic.read(word - SCS).is_some() => self.nvic.read(word - SCS).unwrap(),
            _ => self.plain_read(word),
        }
    }

    // MMIO write of `size` bytes at `addr`
    pub fn write(&mut self, addr: u32, size: usize, value: u32) {
        let issued = self.access_cycle();
        // A write waits only for a bridge still busy; the write buffer takes it, it lands later.
        let (t, lands) = match self.bridge(addr, issued) {
            Some((start, end)) => {
                self.stall += start - issued;
                (start, end)
            }
            None => (issued, issued),
        };
        self.sync(t);
        let word = addr & !3;
        let shift = (addr & 3) * 8;
        let mask = if size >= 4 { u32::MAX } else { ((1u32 << (8 * size)) - 1) << shift };
        let v = (value << shift) & mask;
        self.write_reg(word, v, mask, t, lands);
        self.sync(t);
    }

    // write `v` (already in its lanes, `mask`) to the register at `word` at cycle `t`, by the
    // CPU or the DMA; a GPIO write changes the pins at `lands`
    pub(in crate::emu) fn write_reg(&mut self, word: u32, v: u32, mask: u32, t: u64, lands: u64) {
        match word {
            DMA1..=0x4002_03FF => {
                let merged = (self.dma.read(word - DMA1) & !mask) | v;
                self.dma.write(word - DMA1, merged, t)
            }
            TIM2..=0x4000_03FF => {
                let v = if word == TIM2 + 0x10 { v | !mask } else { v };
                self.tim2.write(word - TIM2, v, t);
                if word == TIM2 + 0x0C {
                    self.dma_requests_enabled();
                }
            }
            TIM1..=0x4001_2FFF => {
                let merged = (self.tim1.read(word - TIM1) & !mask) | v;
                self.tim1.write(word - TIM1, merged, t)
            }
            TIM3..=0x4000_07FF => {
                let off = word - TIM3;
                let merged = if off == 0x24 { v } else { (self.tim3.read(off, t) & !mask) | v };
                self.tim3.write(off, merged)
            }
            USART1..=0x4001_3BFF => self.usart1.write(word - USART1, v, t),
            USB..=0x4000_5FFF => self.usb.write(word - USB, v, mask),
            USB_PMA..=0x4000_63FF => self.usb.pma_write(word - USB_PMA, v, mask),
            IWDG..=0x4000_33FF => self.iwdg.write(word - IWDG, v, t),
            EXTI..=0x4001_07FF => {
                let merged = if word - EXTI == 0x14 { v } else { (self.exti.read(word - EXTI) & !mask) | v };
                self.exti.write(word - EXTI, merged)
            }
            GPIOA..=0x4001_1BFF => self.gpio_write(word, v, mask, lands),
            0xE000_E010..=0xE000_E01F => self.systick.write(word - 0xE000_E010, v, t),
            DWT_CTRL => {
                let demcr = self.regs.get(&DEMCR).copied().unwrap_or(0);
                self.dwt.set(t, (self.dwt.ctrl & !mask) | v, demcr, None);
            }
            DWT_CYCCNT => {
                let demcr = self.regs.get(&DEMCR).copied().unwrap_or(0);
                self.dwt.set(t, self.dwt.ctrl, demcr, Some(v));
            }
            DEMCR => {
                let demcr = (self.regs.get(&DEMCR).copied().unwrap_or(0) & !mask) | v;
                self.regs.insert(DEMCR, demcr);
                self.dwt.set(t, self.dwt.ctrl, demcr, None);
            }
            SCS..=0xE000_EFFF if self.nvic.read(word - SCS).is_some() || word == SCS + 0xF00 => {
                let merged = match word - SCS {
                    0x400..=0x4EF | 0xD18..=0xD23 => (self.nvic.read(word - SCS).unwrap() & !mask) | v,
                    _ => v,
                };
                self.nvic.write(word - SCS, merged);
                // AIRCR.SYSRESETREQ (with the key): a system reset.
                if word == SCS + 0xD0C && v >> 16 == 0x05FA && v & 4 != 0 {
                    self.reset_due = Some(iwdg::CSR_SFTRSTF);
                    self.deadline = 0; // stop at the next block
                }
            }
            _ => self.plain_write(word, v, mask),
        }
    }

    // an external level change of input `pin` on port `port` (index): EXTI edge detection
    pub fn input_edge(&mut self, port: usize, pin: u8, before: bool) {
        let after = self.ports[port].idr() & 1 << pin != 0;
        if let (0, Some(ch)) = (port, ENCODER_PINS.iter().position(|&p| p == pin)) {
            if before != after {
                let other = self.ports[0].idr() & 1 << ENCODER_PINS[1 - ch] != 0;
                self.tim3.input(ch, after, other);
            }
        }
        if pin as u32 >= exti::LINES || before == after {
            return;
        }
        let cr = self.regs.get(&(AFIO_EXTICR1 + 4 * (pin as u32 / 4))).copied().unwrap_or(0);
        if (cr >> (4 * (pin as u32 % 4))) & 0xF == port as u32 {
            self.exti.edge(pin as u32, after);
            let now = self.now;
            self.sync(now);
        }
    }

    fn gpio_write(&mut self, word: u32, v: u32, mask: u32, t: u64) {
        let p = ((word - GPIOA) / 0x400) as usize;
        let off = (word - GPIOA) % 0x400;
        let old = self.ports[p].odr;
        let v = if matches!(off, 0x00 | 0x04 | 0x0C) { (self.ports[p].read(off) & !mask) | v } else { v };
        if let Some(new) = self.ports[p].write(off, v) {
            if p == 1 && matches!(off, 0x10 | 0x14) && self.nvic.ipsr() == IRQ0 + TIM2_IRQ && self.first_bsrr.is_none() {
                self.first_bsrr = Some(t);
            }
            let changed = old ^ new;
            if let (Some(plant), true) = (&mut self.plant, changed != 0) {
                plant.outputs(t, p as u8, old, new, &mut self.plant_flips);
                // Stop the CPU in time for the earliest input change.
                if let Some(first) = self.plant_flips.iter().map(|f| f.cycle).min() {
                    self.deadline = self.deadline.min(first);
                }
            }
            if self.record_edges && changed != 0 {
                // In cycle order: a DMA write can land before a CPU store already recorded.
                let mut at = self.edges.partition_point(|e| e.cycle <= t);
                for pin in 0..16 {
                    if changed & 1 << pin != 0 {
                        self.edges.insert(at, PinEdge { cycle: t, port: p as u8, pin, level: new & 1 << pin != 0 });
                        at += 1;
                    }
                }
            }
        }
    }

    fn plain_read(&mut self, word: u32) -> u32 {
        let v = self.regs.get(&word).copied().unwrap_or(0);
        match word {
            RCC => {
                // Ready bits follow their enables: HSI, HSE, PLL.
                let mut v = v & !((1 << 1) | (1 << 17) | (1 << 25));
                v |= (v & 1) << 1 | (v & (1 << 16)) << 1 | (v & (1 << 24)) << 1;
                v
            }
            0x4002_1004 => (v & !0xC) | (v & 3) << 2, // CFGR.SWS = SW
            0x4002_200C => 0,                          // FLASH_SR: never busy
            RCC_CSR => v | (v & 1) << 1,               // LSIRDY = LSION
            FLASH_IF => (v & !0x20) | (v & 0x10) << 1, // ACR.PRFTBS = PRFTBE
            _ => {
                self.log_unmodeled(word);
                v
            }
        }
    }

    fn plain_write(&mut self, word: u32, v: u32, mask: u32) {
        let old = self.regs.get(&word).copied().unwrap_or(0);
        self.regs.insert(word, (old & !mask) | v);
        if word == RCC_CSR && v & iwdg::CSR_RMVF != 0 {
            // RMVF clears every reset flag (and reads back 0).
            self.regs.insert(word, old & !mask & 0x00FF_FFFF | v & 0x00FF_FFFF & !iwdg::CSR_RMVF);
        }
        if word == FLASH_IF {
            self.flash_pending = Some(FlashConfig::from_acr((old & !mask) | v));
        }
        if word == 0x4002_2010 && v & (1 << 6) != 0 && v & (1 << 1) != 0 {
            self.flash_erase = self.regs.get(&0x4002_2014).copied(); // CR.STRT with PER: AR page
            // The erase completes at once here, and hardware clears STRT when BSY falls
            // (RM0008 §3.3.1): a stale STRT would make the next erase's "set PER" (written
            // before its AR) erase the previous page again.
            if let Some(cr) = self.regs.get_mut(&0x4002_2010) {
                *cr &= !(1 << 6);
            }
        }
        // FLASH_KEYR: the second key of the unlock sequence clears CR.LOCK (RM0008 §3.3.1),
        // so a program/erase after the HAL re-locked the controller works as on silicon.
        if word == 0x4002_2004 && v == 0xCDEF_89AB {
            if let Some(cr) = self.regs.get_mut(&0x4002_2010) {
                *cr &= !(1 << 7);
            }
        }
        self.log_unmodeled(word);
    }

    fn log_unmodeled(&mut self, word: u32) {
        let known = matches!(word, RCC..=0x4002_13FF | FLASH_IF..=0x4002_23FF | 0x4001_0000..=0x4001_03FF)
            || word == 0xE000_EDFC;
        if !known && self.logged.insert(word) {
            self.unmodeled.insert(word, self.pc);
            eprintln!("emu: unmodeled peripheral register {word:#010x} (first access at pc {:#010x})", self.pc);
        }
    }
}
