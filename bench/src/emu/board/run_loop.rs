//! The board's run loop: interleaves unicorn execution, peripheral events, exceptions and
//! sleep.
//!
//! Each loop turn: apply scheduled input flips, bring peripherals to `now`, take a pending
//! exception that may preempt (or tail-chain), fast-forward through WFI sleep, else run the
//! CPU until the next event. The block hook stops before a block when an event is due; when
//! the event falls inside a block, the CPU is restarted with an instruction count so it stops
//! at the first instruction boundary at or after the event (exact in modeled cycles).

use anyhow::{bail, Result};
use unicorn_engine::RegisterARM;

use super::Board;
use crate::emu::dma_run;
use crate::emu::exception;
use crate::emu::mcu::Stop;
use crate::emu::nvic::IRQ0;
use crate::emu::profile;
use crate::emu::stats::IsrEntry;

/// Instruction budget per unicorn run when no split is needed.
const UNLIMITED: usize = 1 << 40;

impl Board {
    // one turn of the run loop, never past cycle `end`
    pub(super) fn step(&mut self, end: u64) -> Result<()> {
        if let Some(f) = &self.fault {
            bail!("CPU stopped: {f}");
        }
        let now = self.cycles();
        if !self.cpu.get_data().plant_flips.is_empty() {
            let flips = std::mem::take(&mut self.cpu.get_data_mut().plant_flips);
            self.inputs.extend(flips);
            self.inputs.sort_by_key(|f| std::cmp::Reverse(f.cycle));
        }
        while self.inputs.last().is_some_and(|f| f.cycle <= now) {
            let f = self.inputs.pop().unwrap();
            self.set_input(f.port, f.pin, f.level);
        }
        self.cpu.get_data_mut().sync(now);
        // DMA requests up to `now`: served here (the CPU loses bus cycles unless asleep);
        // transfers already due land at once.
        if dma_run::service(&mut self.cpu, !self.sleeping) {
            self.cpu.get_data_mut().sync(now);
        }
        if let Some(flag) = self.cpu.get_data().reset_due {
            self.system_reset(flag);
            return Ok(());
        }
        let basepri = self.reg(RegisterARM::BASEPRI);
        let primask = self.reg(RegisterARM::PRIMASK) != 0;
        let next_input = self.inputs.last().map_or(u64::MAX, |f| f.cycle);
        let deadline = self.cpu.get_data().next_event().min(next_input).min(end);
        if self.sleeping {
            let m = self.cpu.get_data();
            let wake = m.pending && m.nvic.preempting(basepri, false).is_some();
            if !wake {
                let until = deadline.max(now);
                self.stats.sleep(now, until);
                self.cpu.get_data_mut().now = until;
                return Ok(());
            }
            self.sleeping = false;
            if let Some(ret) = self.sleep_on_exit.take() {
                let n = self.cpu.get_data().nvic.preempting(basepri, primask).unwrap_or(0);
                let tail = self.cpu.get_data().exception_cycles().2;
                self.take(n, ret, tail);
                return Ok(());
            }
        }
        if self.split.is_none() && self.cpu.get_data().pending {
            if let Some(n) = self.cpu.get_data().nvic.preempting(basepri, primask) {
                let ret = exception::stack_frame(&mut self.cpu);
                let entry = self.cpu.get_data().exception_cycles().0;
                self.take(n, ret, entry);
                return Ok(());
            }
        }
        self.run_cpu(deadline)
    }

    // run unicorn until the block hook, a count limit, WFI, an exception return or a fault
    fn run_cpu(&mut self, deadline: u64) -> Result<()> {
        let pc = self.reg(RegisterARM::PC);
        let count = self.split.take().unwrap_or(UNLIMITED);
        {
            let m = self.cpu.get_data_mut();
            m.deadline = deadline;
            m.stop = Stop::None;
            m.cur = None;
            if count != UNLIMITED {
                m.armed = Some((pc, m.now));
            }
        }
        let result = self.cpu.emu_start((pc | 1) as u64, 0, 0, count);
        let start_pc = pc;
        let mut pc = self.reg(RegisterARM::PC);
        if let Some(store) = self.cpu.get_data_mut().mmio_stop.take() {
            let next = self.cpu.get_data().block().and_then(|b| {
                let i = b.index_of(store)?;
                Some(b.insns.get(i + 1).map_or(b.end, |n| n.addr))
            });
            if let (true, Some(next)) = (pc == store, next) {
                pc = next;
                let _ = self.cpu.reg_write(RegisterARM::PC, pc as u64);
            }
        }
        static TRACE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        if *TRACE.get_or_init(|| std::env::var_os("EMU_TRACE").is_some()) {
            let m = self.cpu.get_data();
            eprintln!("run {start_pc:#x} count {count} -> {pc:#x} {result:?} stop {:?} cur {:x?} now {} deadline {deadline}", m.stop, m.cur, m.now);
        }
        let m = self.cpu.get_data_mut();
        m.armed = None;
        let mut wfi = false;
        if let Some(b) = m.block() {
            let (cycles, n) = match b.index_of(pc) {
                Some(i) => (b.prefix[i], i),
                None => (if pc >= 0xFFFF_FFF0 { b.prefix[b.insns.len()] } else { b.cost_to(pc) }, b.insns.len()),
            };
            wfi = pc == b.end && b.insns.last().is_some_and(|i| i.wfi);
            let start = b.start;
            m.account(start, cycles, n as u64);
        }
        m.cur = None;
        if let Stop::Split(k) = m.stop {
            self.split = Some(k);
        }
        if pc >= 0xFFFF_FFF0 {
            self.exception_return(pc | 1);
        } else if wfi {
            self.sleeping = true;
        } else if let Err(e) = result {
            self.fault = Some(format!("{e:?} at pc {pc:#010x} after {} modeled cycles", self.cycles()));
            bail!("CPU stopped: {}", self.fault.as_ref().unwrap());
        }
        Ok(())
    }

    // enter exception `n` with `exc_return` in LR, charging `cost` modeled cycles
    fn take(&mut self, n: u32, exc_return: u32, cost: u64) {
        let start = self.cycles();
        self.stats.handler_enter(start);
        exception::enter(&mut self.cpu, n, exc_return);
        let m = self.cpu.get_data_mut();
        m.account(profile::ENTRY, cost, 0);
        if n == IRQ0 + self.step_irq {
            m.first_bsrr = None;
            if let Some(b) = &mut m.isr_blocks {
                b.clear();
            }
            let update = (m.tim2.sr & 1 != 0).then_some(m.tim2.last_update);
            self.stats.isr = Some(IsrEntry { start, insns: m.insns, update, overruns: m.tim2.overruns });
        }
    }

    // a branch to EXC_RETURN: deactivate, then tail-chain, sleep on exit, or unstack
    fn exception_return(&mut self, exc_return: u32) {
        let n = self.cpu.get_data_mut().nvic.deactivate();
        let now = self.cycles();
        self.cpu.get_data_mut().sync(now);
        let basepri = self.reg(RegisterARM::BASEPRI);
        let primask = self.reg(RegisterARM::PRIMASK) != 0;
        let next = self.cpu.get_data().nvic.preempting(basepri, primask);
        // A tail-chain replaces the return: its cost is charged to the next handler's entry.
        let (_, return_cycles, tail) = self.cpu.get_data().exception_cycles();
        let ret = if next.is_some() { 0 } else { return_cycles };
        if n == IRQ0 + self.step_irq {
            let m = self.cpu.get_data_mut();
            let blocks = m.isr_blocks.as_mut().map(std::mem::take).unwrap_or_default();
            let (insns, bsrr) = (m.insns, m.first_bsrr);
            self.stats.isr_done(now + ret, insns, bsrr, blocks);
        }
        if let Some(next) = next {
            self.take(next, exc_return, tail);
            return;
        }
        self.profile_return(n, return_cycles);
        let to_thread = exc_return & 8 != 0;
        if to_thread {
            self.stats.handler_leave(now + return_cycles);
        }
        if to_thread && self.cpu.get_data().nvic.scr & 2 != 0 {
            self.sleeping = true;
            self.sleep_on_exit = Some(exc_return);
            self.cpu.get_data_mut().now += return_cycles;
            return;
        }
        exception::unstack(&mut self.cpu, exc_return);
        self.cpu.get_data_mut().now += return_cycles;
    }

    // the IWDG expired or the firmware asked (AIRCR): peripherals to reset (RCC_CSR `flag`
    // set), the core restarts at the reset vector with the initial SP; RAM keeps its contents
    // (the firmware's startup code zeroes .bss and copies .data, as after any reset)
    fn system_reset(&mut self, flag: u32) {
        self.cpu.get_data_mut().system_reset(flag);
        if flag == crate::emu::iwdg::CSR_IWDGRSTF {
            self.watchdogs.push(self.cycles());
        } else {
            self.soft_resets.push(self.cycles());
        }
        let regs = [
            (RegisterARM::PRIMASK, 0),
            (RegisterARM::BASEPRI, 0),
            (RegisterARM::CONTROL, 0),
            (RegisterARM::MSP, self.image.initial_sp as u64),
            (RegisterARM::SP, self.image.initial_sp as u64),
            (RegisterARM::APSR_NZCVQ, 0),
            (RegisterARM::EPSR, 1 << 24),
            (RegisterARM::LR, 0xFFFF_FFFF),
            (RegisterARM::PC, (self.image.reset & !1) as u64),
        ];
        for (r, v) in regs {
            let _ = self.cpu.reg_write(r, v);
        }
        self.sleeping = false;
        self.sleep_on_exit = None;
        self.split = None;
        self.stats.isr = None;
        self.stats.handler_leave(self.cycles());
    }

    // charge an exception return of exception `n` to the profile (the clock is charged apart)
    fn profile_return(&mut self, n: u32, cycles: u64) {
        if let Some(h) = &mut self.cpu.get_data_mut().profile {
            h.add(n, profile::RETURN, cycles, 0);
        }
    }
}
