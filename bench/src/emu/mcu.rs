//! `Mcu`: the emulated STM32F103's state (time, peripherals, NVIC, traces) and the MMIO dispatch
//! from unicorn's callbacks to the peripheral models. For `board.rs`, which owns a
//! `Unicorn<Mcu>`.
//!
//! Time is modeled cycles. During a block, `now` is the cycle the block began and an access
//! happens at the end of its instruction: `now + stall + prefix[i] + cost[i]`, where `stall`
//! holds the bridge stalls of this block's earlier peripheral accesses (`memory.rs`): they
//! are added to the clock with the block.
//! Registers with no model keep what was written (so read-modify-write works), read 0 until
//! then, and are logged once with address and PC.

use std::collections::{BTreeMap, HashMap, HashSet};

use super::cost::{Block, BlockCache};
use super::dma::{self, Dma};
use super::gpio::{GpioPort, PinEdge};
use super::exti::{self, Exti};
use super::iwdg::{self, Iwdg};
use super::memory::{apb_divider, bridge_cycles, bus_of, Bus, FlashConfig};
use super::nvic::{Nvic, IRQ0};
use super::profile::Histogram;
use super::pwm::Pwm;
use super::qenc::EncoderTimer;
use super::systick::SysTick;
use super::timer::Timer;
use super::usart::Usart;

/// TIM2 global interrupt (IRQ 28).
pub const TIM2_IRQ: u32 = 28;
/// USART1 global interrupt (IRQ 37).
pub const USART1_IRQ: u32 = 37;

const TIM2: u32 = 0x4000_0000;
const TIM1: u32 = 0x4001_2C00;
const TIM3: u32 = 0x4000_0400;
/// GPIOA pins of TIM3's encoder inputs TI1, TI2.
const ENCODER_PINS: [u8; 2] = [6, 7];
const USART1: u32 = 0x4001_3800;
const GPIOA: u32 = 0x4001_0800;
const RCC: u32 = 0x4002_1000;
const DMA1: u32 = 0x4002_0000;
const IWDG: u32 = 0x4000_3000;
const EXTI: u32 = 0x4001_0400;
const AFIO_EXTICR1: u32 = 0x4001_0008;
const RCC_CSR: u32 = 0x4002_1024;
const FLASH_IF: u32 = 0x4002_2000;
const RCC_CFGR: u32 = 0x4002_1004;
const SCS: u32 = 0xE000_E000;
const DWT_CTRL: u32 = 0xE000_1000;
const DWT_CYCCNT: u32 = 0xE000_1004;
const DEMCR: u32 = 0xE000_EDFC;
/// DWT_CTRL.NUMCOMP of a Cortex-M3 (4 comparators), read-only.
const DWT_NUMCOMP_4: u32 = 4 << 28;

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
    fn set(&mut self, t: u64, ctrl: u32, demcr: u32, cyccnt: Option<u32>) {
        let value = cyccnt.unwrap_or_else(|| self.cyccnt(t));
        self.ctrl = ctrl;
        self.running = ctrl & 1 != 0 && demcr & 1 << 24 != 0;
        self.held = value;
        self.base = t.wrapping_sub(value as u64);
    }
}

/// Why the block hook stopped the CPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    None,
    /// An exception may preempt, or the deadline has passed.
    Event,
    /// The deadline falls after the first `k` instructions of the block.
    Split(usize),
}

/// Everything the emulator callbacks can see.
pub struct Mcu {
    /// Cycle at the start of `cur` (or the current PC when stopped).
    pub now: u64,
    pub insns: u64,
    pub cur: Option<u32>,
    /// The cycle before which the CPU must stop (next peripheral event or run limit).
    pub deadline: u64,
    /// Block allowed to run `k` instructions at (addr, cycle) after an exact-stop restart.
    pub armed: Option<(u32, u64)>,
    pub stop: Stop,
    /// Some exception is pending and enabled (cheap check for the block hook).
    pub pending: bool,
    pub blocks: BlockCache,
    pub nvic: Nvic,
    pub tim2: Timer,
    /// TIM1: the spindle/laser PWM.
    pub tim1: Pwm,
    /// TIM3: the quadrature encoder counter on PA6/PA7.
    pub tim3: EncoderTimer,
    /// DMA1 (`dma.rs`, `dma_run.rs`).
    pub dma: Dma,
    pub usart1: Usart,
    pub systick: SysTick,
    pub ports: Vec<GpioPort>,
    pub edges: Vec<PinEdge>,
    pub record_edges: bool,
    /// Plain registers (RCC, AFIO, FLASH, unknown).
    pub regs: HashMap<u32, u32>,
    pub unmodeled: BTreeMap<u32, u32>,
    logged: HashSet<u32>,
    pub dwt: Dwt,
    /// Current PC as synced by unicorn's per-instruction counter hook.
    pub pc: u32,
    /// First GPIOB BSRR/BRR store cycle since the last TIM2 entry.
    pub first_bsrr: Option<u64>,
    pub flash_erase: Option<u32>,
    /// PC of a store after which the write callback stopped the CPU.
    pub mmio_stop: Option<u32>,
    /// Per-block cycle histogram while profiling is on.
    pub profile: Option<Histogram>,
    /// Cycles of blocks run in thread mode so far.
    pub thread_cycles: u64,
    /// Inclusive timing of chosen functions, while on.
    pub fn_timer: Option<super::profile::FnTimer>,
    /// Block starts of the running TIM2 handler, while the per-entry log is on.
    pub isr_blocks: Option<Vec<u32>>,
    /// Bridge stall cycles of the current block so far (added to the clock with the block).
    pub stall: u64,
    /// Cycle at which the AHB-to-APB bridges finish the last transfer (buffered writes).
    pub bridge_free: u64,
    /// FLASH_ACR was written: blocks are re-costed for this from the next block on.
    pub flash_pending: Option<FlashConfig>,
    /// Independent watchdog; `reset_due` is set when it expires (the board resets the MCU).
    pub iwdg: Iwdg,
    /// A reset is due, with the RCC_CSR flag it leaves (IWDGRSTF, SFTRSTF).
    pub reset_due: Option<u32>,
    pub exti: Exti,
    /// The machine wired to the pins, and the input changes it scheduled (board applies them).
    pub plant: Option<Box<dyn super::plant::Plant>>,
    pub plant_flips: Vec<super::input::InputFlip>,
}

impl Mcu {
    // power-on state
    pub fn new() -> Self {
        let mut regs = HashMap::new();
        regs.insert(RCC, 0x0000_0083);
        regs.insert(FLASH_IF, 0x30);
        regs.insert(RCC_CSR, iwdg::CSR_PORRSTF | iwdg::CSR_PINRSTF);
        Self {
            now: 0,
            insns: 0,
            cur: None,
            deadline: u64::MAX,
            armed: None,
            stop: Stop::None,
            pending: false,
            blocks: BlockCache::default(),
            nvic: Nvic::default(),
            tim2: Timer::new(),
            tim1: Pwm::default(),
            tim3: EncoderTimer::default(),
            dma: Dma::default(),
            usart1: Usart::default(),
            systick: SysTick::default(),
            ports: vec![GpioPort::new(); 5],
            edges: Vec::new(),
            record_edges: true,
            regs,
            unmodeled: BTreeMap::new(),
            logged: HashSet::new(),
            dwt: Dwt::default(),
            pc: 0,
            first_bsrr: None,
            flash_erase: None,
            mmio_stop: None,
            profile: None,
            thread_cycles: 0,
            fn_timer: None,
            isr_blocks: None,
            stall: 0,
            bridge_free: 0,
            flash_pending: None,
            iwdg: Iwdg::default(),
            reset_due: None,
            exti: Exti::default(),
            plant: None,
            plant_flips: Vec::new(),
        }
    }

    // a system reset (watchdog): peripherals, NVIC and clocks to their reset state, RCC_CSR
    // flags `csr` added; time, traces, the serial transcript and external inputs are kept
    pub fn system_reset(&mut self, csr: u32) {
        let mut fresh = Mcu::new();
        std::mem::swap(self, &mut fresh);
        let old = fresh;
        self.now = old.now;
        self.insns = old.insns;
        self.blocks = old.blocks;
        self.flash_pending = Some(FlashConfig::RESET);
        self.edges = old.edges;
        self.record_edges = old.record_edges;
        self.unmodeled = old.unmodeled;
        self.logged = old.logged;
        self.profile = old.profile;
        self.isr_blocks = old.isr_blocks.map(|_| Vec::new());
        self.bridge_free = old.now;
        self.tim1.changes = old.tim1.changes;
        self.plant = old.plant;
        self.plant_flips = old.plant_flips;
        let u = old.usart1;
        self.usart1.transcript = u.transcript;
        self.usart1.tx_times = u.tx_times;
        self.usart1.rx_queue = u.rx_queue;
        self.usart1.rx_overruns = u.rx_overruns;
        for (p, o) in self.ports.iter_mut().zip(&old.ports) {
            p.ext_level = o.ext_level;
            p.ext_driven = o.ext_driven;
        }
        let flags = old.regs.get(&RCC_CSR).copied().unwrap_or(0) & 0xFE00_0000;
        self.regs.insert(RCC_CSR, flags | csr);
    }

    // the block being executed
    pub fn block(&self) -> Option<&Block> {
        self.cur.and_then(|a| self.blocks.at(a))
    }

    // charge `cycles` and `insns` of block `start` to the clock (and the profile, if on)
    pub fn account(&mut self, start: u32, cycles: u64, insns: u64) {
        let cycles = cycles + std::mem::take(&mut self.stall);
        self.now += cycles;
        self.insns += insns;
        if let Some(h) = &mut self.profile {
            h.add(self.nvic.ipsr(), start, cycles, insns);
        }
        if self.nvic.ipsr() == 0 {
            self.thread_cycles += cycles;
        }
        if let Some(b) = &mut self.isr_blocks {
            if self.nvic.ipsr() == super::nvic::IRQ0 + TIM2_IRQ {
                b.push(start);
            }
        }
    }

    // modeled cycle at which the instruction at `self.pc` completes its access
    pub fn access_cycle(&self) -> u64 {
        match self.block().and_then(|b| b.index_of(self.pc).map(|i| (b, i))) {
            Some((b, i)) if i < b.insns.len() => self.now + self.stall + b.prefix[i + 1],
            _ => self.now + self.stall,
        }
    }

    // apply a FLASH_ACR change between blocks
    pub fn apply_flash_config(&mut self) {
        if let Some(f) = self.flash_pending.take() {
            self.blocks.set_flash(f);
        }
    }

    // exception entry, return and tail-chain cycles for the current flash configuration
    pub fn exception_cycles(&self) -> (u64, u64, u64) {
        let f = self.blocks.flash();
        (f.entry_cycles(), f.return_cycles(), f.tail_chain_cycles())
    }

    // APB divider of the bridge in front of `addr` (RCC_CFGR PPRE1/PPRE2), `None` off the APBs
    fn apb(&self, addr: u32) -> Option<u64> {
        let cfgr = self.regs.get(&RCC_CFGR).copied().unwrap_or(0);
        match bus_of(addr) {
            Bus::Apb1 => Some(apb_divider(cfgr >> 8 & 7)),
            Bus::Apb2 => Some(apb_divider(cfgr >> 11 & 7)),
            Bus::Other => None,
        }
    }

    // a peripheral transfer issued at cycle `t`: waits for the bridge, returns (start, end)
    pub(super) fn bridge(&mut self, addr: u32, t: u64) -> Option<(u64, u64)> {
        let d = self.apb(addr)?;
        let start = t.max(self.bridge_free);
        self.bridge_free = start + bridge_cycles(d);
        Some((start, self.bridge_free))
    }

    // bring peripherals to cycle `t` and refresh the NVIC's interrupt lines
    pub fn sync(&mut self, t: u64) {
        self.dma_land(t);
        self.tim2.advance(t);
        self.dma_collect();
        self.tim1.advance(t);
        self.usart1.advance(t);
        let wraps = self.systick.advance(t);
        if wraps > 0 {
            self.nvic.pending[super::nvic::SYSTICK as usize] = true;
        }
        if self.iwdg.expires_at(super::clock::HZ).is_some_and(|e| e <= t) {
            self.reset_due = Some(iwdg::CSR_IWDGRSTF);
        }
        self.nvic.level[(IRQ0 + TIM2_IRQ) as usize] = self.tim2.irq();
        for irq in [6, 7, 8, 9, 10, 23, 40] {
            self.nvic.level[(IRQ0 + irq) as usize] = false;
        }
        for line in 0..exti::LINES {
            self.nvic.level[(IRQ0 + exti::irq_of(line)) as usize] |= self.exti.irq(line);
        }
        self.nvic.level[(IRQ0 + USART1_IRQ) as usize] = self.usart1.irq();
        for x in 0..dma::CHANNELS {
            self.nvic.level[(IRQ0 + dma::IRQ_CHANNEL1) as usize + x] = self.dma.irq(x);
        }
        self.pending = self.nvic.any_pending();
    }

    // the next cycle at which a peripheral changes state
    pub fn next_event(&self) -> u64 {
        [
            self.tim2.next_event(),
            self.usart1.next_event(),
            self.systick.next_event(),
            self.iwdg.expires_at(super::clock::HZ),
            self.dma.next_event(),
        ]
            .into_iter()
            .flatten()
            .min()
            .unwrap_or(u64::MAX)
    }

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
    pub(super) fn read_reg(&mut self, word: u32, t: u64) -> u32 {
        match word {
            TIM2..=0x4000_03FF => self.tim2.read(word - TIM2, t),
            DMA1..=0x4002_03FF => self.dma.read(word - DMA1),
            TIM1..=0x4001_2FFF => self.tim1.read(word - TIM1),
            TIM3..=0x4000_07FF => self.tim3.read(word - TIM3, t),
            USART1..=0x4001_3BFF => self.usart1.read(word - USART1, t),
            IWDG..=0x4000_33FF => self.iwdg.read(word - IWDG),
            EXTI..=0x4001_07FF => self.exti.read(word - EXTI),
            GPIOA..=0x4001_1BFF => {
                let p = ((word - GPIOA) / 0x400) as usize;
                self.ports[p].read((word - GPIOA) % 0x400)
            }
            0xE000_E010..=0xE000_E01F => self.systick.read(word - 0xE000_E010, t),
            DWT_CTRL => self.dwt.ctrl | DWT_NUMCOMP_4,
            DWT_CYCCNT => self.dwt.cyccnt(t),
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
    pub(super) fn write_reg(&mut self, word: u32, v: u32, mask: u32, t: u64, lands: u64) {
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
