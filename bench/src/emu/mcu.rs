//! `Mcu`: the emulated STM32F103's state (time, peripherals, NVIC, traces); its MMIO dispatch
//! from unicorn's callbacks to the peripheral models is `mcu/mmio.rs`, the addresses it routes
//! `mcu/address.rs`. For `board.rs`, which owns a `Unicorn<Mcu>`.
//!
//! Time is modeled cycles. During a block, `now` is the cycle the block began and an access
//! happens at the end of its instruction: `now + stall + prefix[i] + cost[i]`, where `stall`
//! holds the bridge stalls of this block's earlier peripheral accesses (`memory.rs`): they
//! are added to the clock with the block.

use std::collections::{BTreeMap, HashMap, HashSet};

use super::cost::{Block, BlockCache};
use super::dma::{self, Dma};
use super::gpio::{GpioPort, PinEdge};
use super::exti::{self, Exti};
use super::iwdg::{self, Iwdg};
use super::memory::{apb_divider, bridge_cycles, bus_of, Bus, FlashConfig};
use super::dwt::Dwt;
use super::nvic::{Nvic, IRQ0};
use super::profile::Histogram;
use super::pwm::Pwm;
use super::qenc::EncoderTimer;
use super::systick::SysTick;
use super::timer::Timer;
use super::usart::Usart;
use super::usb::UsbPeripheral;
use super::usb_host::UsbHost;
use address::{FLASH_IF, RCC, RCC_CFGR, RCC_CSR};

mod address;
mod mmio;

/// TIM2 global interrupt (IRQ 28).
pub const TIM2_IRQ: u32 = 28;
/// USART1 global interrupt (IRQ 37).
pub const USART1_IRQ: u32 = 37;
/// CPUID of the STM32F103's core, a Cortex-M3 r1p1 (the default part's).
pub const CPUID_M3_R1P1: u32 = 0x411F_C231;

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
    /// The USB device peripheral and the host on the cable (unplugged unless a run asks).
    pub usb: UsbPeripheral,
    pub usb_host: UsbHost,
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
    /// Where the engine's moves end (entries of the step half's `finish`).
    pub move_marks: super::profile::MoveMarks,
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
    /// SCB CPUID as the part reads it (`Board::set_chip`; a reset keeps it).
    pub cpuid: u32,
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
            usb: UsbPeripheral::default(),
            usb_host: UsbHost::default(),
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
            move_marks: Default::default(),
            isr_blocks: None,
            stall: 0,
            bridge_free: 0,
            flash_pending: None,
            iwdg: Iwdg::default(),
            reset_due: None,
            exti: Exti::default(),
            plant: None,
            plant_flips: Vec::new(),
            cpuid: CPUID_M3_R1P1,
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
        self.move_marks = old.move_marks;
        self.unmodeled = old.unmodeled;
        self.logged = old.logged;
        self.profile = old.profile;
        self.isr_blocks = old.isr_blocks.map(|_| Vec::new());
        self.bridge_free = old.now;
        self.tim1.changes = old.tim1.changes;
        self.plant = old.plant;
        self.plant_flips = old.plant_flips;
        self.cpuid = old.cpuid;
        let u = old.usart1;
        self.usart1.transcript = u.transcript;
        self.usart1.tx_times = u.tx_times;
        self.usart1.rx_queue = u.rx_queue;
        self.usart1.rx_overruns = u.rx_overruns;
        // The host stays on the cable; the peripheral starts over (the D+ pulse detaches it).
        self.usb_host = old.usb_host;
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
            if let Some(t) = self.fn_timer.as_mut().filter(|t| !t.open.is_empty()) {
                t.inside.add(0, start, cycles, insns);
            }
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
        let dp = self.usb_dp_high();
        self.usb_host.advance(&mut self.usb, t, dp);
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
        self.nvic.level[(IRQ0 + super::usb::IRQ_LP) as usize] = self.usb.irq_lp();
        self.nvic.level[(IRQ0 + super::usb::IRQ_HP) as usize] = self.usb.irq_hp();
        for x in 0..dma::CHANNELS {
            self.nvic.level[(IRQ0 + dma::IRQ_CHANNEL1) as usize + x] = self.dma.irq(x);
        }
        self.pending = self.nvic.any_pending();
    }

    // the Blue Pill's D+ (PA12, pulled up by R10) is high unless the firmware drives it low
    pub fn usb_dp_high(&self) -> bool {
        let a = &self.ports[0];
        let output = a.crh >> 16 & 3 != 0;
        !(output && a.odr & 1 << 12 == 0)
    }

    // the next cycle at which a peripheral changes state
    pub fn next_event(&self) -> u64 {
        [
            self.tim2.next_event(),
            self.usart1.next_event(),
            self.systick.next_event(),
            self.iwdg.expires_at(super::clock::HZ),
            self.dma.next_event(),
            self.usb_host.next_event(&self.usb, self.now, self.usb_dp_high()),
        ]
            .into_iter()
            .flatten()
            .min()
            .unwrap_or(u64::MAX)
    }
}
