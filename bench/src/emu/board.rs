//! `Board`: the emulated Blue Pill running an ELF, and what tests, the `sim` CLI and the sweep
//! do with it (serial lines, inputs, edges, loads, profiles). Its run loop is `board/run_loop.rs`.

use std::path::Path;

use anyhow::{bail, Context, Result};
use unicorn_engine::RegisterARM;

use super::clock::HZ;
use super::cpu::{self, Cpu, Image};
use super::gpio::PinEdge;
use super::input::{InputFlip, Port};
use super::mcu::TIM2_IRQ;
use super::nvic::IRQ0;
use super::profile::{self, FnCost};
use super::stats::{IsrRun, Stats};

mod run_loop;
mod usb_port;

/// An emulated Blue Pill with a program loaded.
pub struct Board {
    cpu: Cpu,
    image: Image,
    pub(crate) stats: Stats,
    /// Sleeping in WFI (or after an exception return with SLEEPONEXIT).
    sleeping: bool,
    /// EXC_RETURN kept while sleeping on exit (frame still stacked).
    sleep_on_exit: Option<u32>,
    split: Option<usize>,
    inputs: Vec<InputFlip>,
    fault: Option<String>,
    /// Cycles of the resets by the independent watchdog so far.
    watchdogs: Vec<u64>,
    /// Cycles of the resets the firmware requested.
    soft_resets: Vec<u64>,
    /// The firmware runs in dual-edge mode (`$580=1`): [`Board::report`] counts both edges of
    /// a step pin as steps.
    pub dual_edge: bool,
    /// The interrupt whose runs are the step path's statistics (`step_isr`, the profile's
    /// default): TIM2's, or DMA1 channel 1's in DMA burst mode (`$581=1`, the buffer fill).
    pub step_irq: u32,
}

impl Board {
    // load an ELF file
    pub fn load(elf: impl AsRef<Path>) -> Result<Self> {
        let path = elf.as_ref();
        let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        Self::from_elf_bytes(&bytes)
    }

    // load an ELF image from memory
    pub fn from_elf_bytes(elf: &[u8]) -> Result<Self> {
        let (mut cpu, image) = cpu::build(elf)?;
        cpu.reg_write(RegisterARM::PC, (image.reset & !1) as u64).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        cpu.get_data_mut().move_marks.targets = image.symbols.addresses_ending("::stepper::state::Stepper<_,_>>::finish");
        Ok(Self {
            cpu,
            image,
            stats: Stats::default(),
            sleeping: false,
            sleep_on_exit: None,
            split: None,
            inputs: Vec::new(),
            fault: None,
            watchdogs: Vec::new(),
            soft_resets: Vec::new(),
            dual_edge: false,
            step_irq: TIM2_IRQ,
        })
    }

    // modeled cycles since reset
    pub fn cycles(&self) -> u64 {
        self.cpu.get_data().now
    }

    // simulated seconds since reset
    pub fn seconds(&self) -> f64 {
        self.cycles() as f64 / HZ as f64
    }

    // instructions executed since reset
    pub fn instructions(&self) -> u64 {
        self.cpu.get_data().insns
    }

    // the CPU fault that stopped execution, if any
    pub fn fault(&self) -> Option<&str> {
        self.fault.as_deref()
    }

    // is the CPU asleep in WFI?
    pub fn is_sleeping(&self) -> bool {
        self.sleeping
    }

    // read a core register (e.g. `RegisterARM::R0`)
    pub fn reg(&self, r: RegisterARM) -> u32 {
        self.cpu.reg_read(r).unwrap_or(0) as u32
    }

    // read a 32-bit word of memory
    pub fn read_u32(&self, addr: u32) -> u32 {
        let mut b = [0u8; 4];
        let _ = self.cpu.mem_read(addr as u64, &mut b);
        u32::from_le_bytes(b)
    }

    /// Deepest stack use since reset and the room the stack has (bytes from `_stack_end` to the
    /// top of RAM), found from the power-up paint ([`cpu::STACK_PAINT`]): `used == room` means
    /// the stack reached the statics (and may have overwritten them).
    pub fn stack_peak(&self) -> Option<(u32, u32)> {
        let floor = self.image.stack_end?;
        let top = cpu::RAM_BASE + cpu::RAM_SIZE;
        let ram = self.read_mem(floor, (top - floor) as usize);
        let untouched = ram.iter().take_while(|&&b| b == cpu::STACK_PAINT).count() as u32;
        Some((top - floor - untouched, top - floor))
    }

    // read memory
    pub fn read_mem(&self, addr: u32, len: usize) -> Vec<u8> {
        self.cpu.mem_read_as_vec(addr as u64, len).unwrap_or_default()
    }

    // run for `cycles` more modeled cycles
    pub fn run_for(&mut self, cycles: u64) -> Result<()> {
        let end = self.cycles() + cycles;
        self.run_until_cycle(end)
    }

    // run for `s` simulated seconds
    pub fn run_seconds(&mut self, s: f64) -> Result<()> {
        self.run_for((s * HZ as f64) as u64)
    }

    // run until modeled cycle `end`
    pub fn run_until_cycle(&mut self, end: u64) -> Result<()> {
        while self.cycles() < end {
            self.step(end)?;
        }
        Ok(())
    }

    // run until `done(board)` holds or `max_cycles` pass; returns whether it held
    pub fn run_until(&mut self, max_cycles: u64, mut done: impl FnMut(&Board) -> bool) -> Result<bool> {
        let end = self.cycles() + max_cycles;
        while !done(self) {
            if self.cycles() >= end {
                return Ok(false);
            }
            self.step(end)?;
        }
        Ok(true)
    }

    // run until no pin has changed for `quiet` cycles (motion over) or `max_cycles` pass;
    // returns whether it went quiet
    pub fn run_until_quiet(&mut self, quiet: u64, max_cycles: u64) -> Result<bool> {
        let end = self.cycles() + max_cycles;
        loop {
            let last = self.edges().last().map_or(0, |e| e.cycle);
            if self.cycles() >= last + quiet {
                return Ok(true);
            }
            if self.cycles() >= end {
                return Ok(false);
            }
            let next = (last + quiet).min(end);
            self.run_until_cycle(next.max(self.cycles() + 1))?;
        }
    }

    // queue bytes on the host side of USART1 RX (they arrive at line pace)
    pub fn serial_send(&mut self, bytes: &[u8]) {
        let m = self.cpu.get_data_mut();
        m.usart1.rx_queue.extend(bytes);
        let now = m.now;
        m.usart1.start_rx(now);
    }

    // queue bytes ahead of everything not yet on the wire (Grbl's realtime commands from a
    // sender: they reach the receiver at the next byte slot, still at line pace)
    pub fn serial_send_urgent(&mut self, bytes: &[u8]) {
        let m = self.cpu.get_data_mut();
        for &b in bytes.iter().rev() {
            m.usart1.rx_queue.push_front(b);
        }
        let now = m.now;
        m.usart1.start_rx(now);
    }

    // host bytes queued for USART1 RX and not yet on the wire
    pub fn serial_pending(&self) -> usize {
        self.cpu.get_data().usart1.rx_queue.len()
    }

    // everything the firmware sent on USART1 TX
    pub fn serial_output(&self) -> String {
        String::from_utf8_lossy(&self.cpu.get_data().usart1.transcript).into_owned()
    }

    // raw TX bytes and the modeled cycle each one finished
    pub fn serial_bytes(&self) -> (&[u8], &[u64]) {
        let u = &self.cpu.get_data().usart1;
        (&u.transcript, &u.tx_times)
    }

    // send one line (adds '\n') and run until a reply line starts with "ok" or "error"
    pub fn send_line_wait_ok(&mut self, line: &str) -> Result<String> {
        self.send_line_wait_ok_within(line, 10 * HZ)
    }

    // like `send_line_wait_ok` with a timeout in modeled cycles
    pub fn send_line_wait_ok_within(&mut self, line: &str, max_cycles: u64) -> Result<String> {
        self.line_wait_reply(line, max_cycles, "", |b| &b.cpu.get_data().usart1.transcript, Board::serial_send)
    }

    // the port's half of `send_line_wait_ok`: `line` (plus '\n') goes out through `send`, and
    // the board runs until a complete line of `received` (what the port got back since) starts
    // with "ok" or "error"; that text if "ok"
    pub(super) fn line_wait_reply(
        &mut self,
        line: &str,
        max_cycles: u64,
        port: &str,
        received: fn(&Board) -> &[u8],
        send: fn(&mut Board, &[u8]),
    ) -> Result<String> {
        let mark = received(self).len();
        send(self, format!("{}\n", line.trim_end()).as_bytes());
        let reply = |b: &Board| {
            let text = String::from_utf8_lossy(&received(b)[mark..]).into_owned();
            let complete = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
            let last = complete.lines().find(|l| l.starts_with("ok") || l.starts_with("error"));
            last.map(|l| (text.clone(), l.starts_with("ok")))
        };
        let got = self.run_until(max_cycles, |b| reply(b).is_some())?;
        match reply(self) {
            Some((text, true)) if got => Ok(text),
            Some((text, _)) => bail!("{line:?} -> {}", text.trim_end()),
            None => bail!(
                "no ok/error for {line:?}{port} within {:.3} s (simulated); got {:?}",
                max_cycles as f64 / HZ as f64,
                String::from_utf8_lossy(&received(self)[mark..])
            ),
        }
    }

    // drive an input pin now (port A limit inputs, ...)
    pub fn set_input(&mut self, port: Port, pin: u8, level: bool) {
        let m = self.cpu.get_data_mut();
        let before = m.ports[port as usize].idr() & 1 << pin != 0;
        let p = &mut m.ports[port as usize];
        p.ext_driven |= 1 << pin;
        if level {
            p.ext_level |= 1 << pin;
        } else {
            p.ext_level &= !(1 << pin);
        }
        m.input_edge(port as usize, pin, before);
    }

    // wire a machine model to the pins (replaces any previous one); its power-on input levels
    // apply at once
    pub fn attach_plant(&mut self, mut plant: Box<dyn super::plant::Plant>) {
        let mut flips = Vec::new();
        plant.initial(&mut flips);
        for f in flips {
            self.schedule_input(f);
        }
        self.cpu.get_data_mut().plant = Some(plant);
    }

    // the machine model wired to the pins
    pub fn plant(&self) -> Option<&dyn super::plant::Plant> {
        self.cpu.get_data().plant.as_deref()
    }

    // schedule an input change at a modeled cycle
    pub fn schedule_input(&mut self, flip: InputFlip) {
        self.inputs.push(flip);
        self.inputs.sort_by_key(|f| std::cmp::Reverse(f.cycle));
    }

    // output latch level of a pin
    pub fn output(&self, port: Port, pin: u8) -> bool {
        self.cpu.get_data().ports[port as usize].odr & 1 << pin != 0
    }

    // every change of TIM1's PWM output (spindle/laser on PA8) so far
    pub fn pwm_changes(&self) -> &[super::pwm::PwmChange] {
        &self.cpu.get_data().tim1.changes
    }

    // TIM3, the quadrature encoder counter (count, filter setting, how often it was read)
    pub fn encoder_timer(&self) -> &super::qenc::EncoderTimer {
        &self.cpu.get_data().tim3
    }

    // every output latch change so far
    pub fn edges(&self) -> &[PinEdge] {
        &self.cpu.get_data().edges
    }

    // hand over the pin edges recorded so far and forget them (long runs that only count)
    pub fn take_edges(&mut self) -> Vec<PinEdge> {
        std::mem::take(&mut self.cpu.get_data_mut().edges)
    }

    // where the engine's moves ended so far: the cycle its step half's `finish` ran (a move's
    // last step), and whether the step interrupt ran it (not DMA's fill, which runs ahead of
    // the pins); recorded while edges are
    pub fn move_ends(&self) -> &[(u64, bool)] {
        &self.cpu.get_data().move_marks.hits
    }

    // hand over the move ends recorded so far and forget them (with `take_edges`)
    pub fn take_move_ends(&mut self) -> Vec<(u64, bool)> {
        std::mem::take(&mut self.cpu.get_data_mut().move_marks.hits)
    }

    // keep (default) or drop the pin edge history (long sweeps)
    pub fn record_edges(&mut self, on: bool) {
        self.cpu.get_data_mut().record_edges = on;
    }

    // RX bytes lost because the firmware had not read the previous one
    pub fn usart_rx_overruns(&self) -> u64 {
        self.cpu.get_data().usart1.rx_overruns
    }

    /// Holds IRQ `irq` back (it stays pending, not taken) until called again with `false`:
    /// for tests of an interrupt that comes late (the firmware's own NVIC settings unchanged).
    pub fn hold_irq(&mut self, irq: u32, held: bool) {
        self.cpu.get_data_mut().nvic.held[(IRQ0 + irq) as usize] = held;
    }

    // TIM2 events that found their flag still set, plus the DMA's overruns (`dma_overruns`)
    pub fn overruns(&self) -> u64 {
        let m = self.cpu.get_data();
        m.tim2.overruns + m.dma.overruns()
    }

    // TIM2 update events (counter wraps) so far and the cycle of the last one
    pub fn timer_updates(&self) -> (u64, u64) {
        let t = &self.cpu.get_data().tim2;
        (t.updates, t.last_update)
    }

    // DMA1 overruns: HTIF/TCIF set again while set with their interrupt enabled (a half not
    // refilled in time), plus requests lost because the previous one of the same channel was
    // not yet acknowledged (included in `overruns`)
    pub fn dma_overruns(&self) -> u64 {
        self.cpu.get_data().dma.overruns()
    }

    // DMA1 data items moved so far, per channel (index 0 = channel 1)
    pub fn dma_transfers(&self) -> [u64; super::dma::CHANNELS] {
        self.cpu.get_data().dma.transfers
    }

    // bus-matrix cycles of all DMA transfers so far (`dma.rs`: SRAM access + bridge transfer)
    pub fn dma_bus_cycles(&self) -> u64 {
        self.cpu.get_data().dma.bus_cycles
    }

    // the part of `dma_bus_cycles` charged to the CPU (transfers while it was not asleep)
    pub fn dma_stolen_cycles(&self) -> u64 {
        self.cpu.get_data().dma.stolen
    }

    // DMA1 channel `x` (1..=7): CCR, CNDTR, CPAR, CMAR
    pub fn dma_channel(&self, x: usize) -> super::dma::Channel {
        self.cpu.get_data().dma.ch[x - 1]
    }

    // peripheral registers without a model that the program touched (address -> first PC)
    pub fn unmodeled(&self) -> Vec<(u32, u32)> {
        self.cpu.get_data().unmodeled.iter().map(|(a, p)| (*a, *p)).collect()
    }

    // raw bytes in RTT up-buffer 0 (defmt frames, not decoded)
    pub fn rtt_up(&self) -> Vec<u8> {
        let Some(cb) = self.image.rtt else { return Vec::new() };
        // SEGGER_RTT_CB: id[16], max_up, max_down, then up buffers {name, buf, size, wr, rd, flags}.
        let buf = self.read_u32(cb + 24 + 4);
        let size = self.read_u32(cb + 24 + 8) as usize;
        let wr = self.read_u32(cb + 24 + 12) as usize;
        if buf == 0 || size == 0 || size > 64 * 1024 {
            return Vec::new();
        }
        self.read_mem(buf, wr.min(size))
    }

    // CPU load (not sleeping) averaged over the 1 ms windows between two cycles
    pub fn cpu_load(&self, from: u64, to: u64) -> f64 {
        self.stats.cpu_load_between(from, to)
    }

    // forget the step-ISR figures so far (entries, cycles, BSRR offsets): measure one stretch
    pub fn reset_step_isr_stats(&mut self) {
        self.stats.step_isr = Default::default();
    }

    // make the emulated part `c` (flash size, unique ID, CPUID; default `cpu::BLUE_PILL`):
    // before the first run, as the firmware reads them at boot
    pub fn set_chip(&mut self, c: &ddastep::grbl::chip::Chip) -> Result<()> {
        cpu::write_chip(&mut self.cpu, c)
    }

    // write memory (e.g. a flash page before boot, as a reset keeps flash)
    pub fn write_mem(&mut self, addr: u32, bytes: &[u8]) -> Result<()> {
        self.cpu.mem_write(addr as u64, bytes).map_err(|e| anyhow::anyhow!("writing {addr:#x}: {e:?}"))?;
        if (cpu::FLASH_BASE..cpu::FLASH_BASE + cpu::FLASH_SIZE).contains(&addr) {
            self.cpu.mem_write((addr - cpu::FLASH_BASE) as u64, bytes).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        }
        Ok(())
    }

    // busy fraction of each 1 ms window [k·72 000, (k+1)·72 000) cycles for k in `windows`
    pub fn window_loads(&self, windows: std::ops::Range<u64>) -> Vec<f64> {
        windows.map(|w| self.stats.window_load(w as usize)).collect()
    }

    // fraction of each 1 ms window spent in handler mode (every exception, entry to return)
    pub fn window_interrupt_loads(&self, windows: std::ops::Range<u64>) -> Vec<f64> {
        windows.map(|w| self.stats.window_interrupt_load(w as usize)).collect()
    }

    // fraction of each 1 ms window spent in the step interrupt (TIM2), entry and return included
    pub fn window_isr_loads(&self, windows: std::ops::Range<u64>) -> Vec<f64> {
        windows.map(|w| self.stats.window_isr_load(w as usize)).collect()
    }

    // start (clearing) or stop the log of every step-interrupt run (cycles, update event,
    // BSRR store, blocks run): where the long ticks are
    pub fn set_isr_log(&mut self, on: bool) {
        self.cpu.get_data_mut().isr_blocks = on.then(Vec::new);
        self.stats.isr_log = on.then(Vec::new);
    }

    // the step-interrupt runs logged since `set_isr_log(true)`
    pub fn isr_log(&self) -> &[IsrRun] {
        self.stats.isr_log.as_deref().unwrap_or(&[])
    }

    // start (clearing) or stop the per-block cycle histogram
    pub fn set_profile(&mut self, on: bool) {
        self.cpu.get_data_mut().profile = on.then(Default::default);
    }

    // cycles per function spent in exception `exc` (e.g. `16 + TIM2_IRQ`; 0 = thread mode)
    pub fn profile(&self, exc: u32) -> Vec<FnCost> {
        self.cpu.get_data().profile.as_ref().map_or_else(Vec::new, |h| profile::by_function(h, &self.image.symbols, exc))
    }

    // cycles per translated block spent in exception `exc`, named `address function+offset`
    pub fn profile_blocks(&self, exc: u32) -> Vec<(String, profile::Count)> {
        self.cpu.get_data().profile.as_ref().map_or_else(Vec::new, |h| profile::by_block(h, &self.image.symbols, exc))
    }

    // start timing every call of the functions named in `names` (demangled, generics as
    // `<_>`): inclusive thread-mode cycles per call, read with `timed_calls`
    pub fn time_functions(&mut self, names: &[&str]) -> Result<()> {
        let mut targets = Vec::new();
        for (k, n) in names.iter().enumerate() {
            let a = self.image.symbols.addresses(n);
            anyhow::ensure!(!a.is_empty(), "no function {n} in the firmware (inlined?)");
            targets.extend(a.into_iter().map(|a| (a, k)));
        }
        self.cpu.get_data_mut().fn_timer = Some(profile::FnTimer { targets, ..Default::default() });
        Ok(())
    }

    // cycles per function (exclusive) of the thread-mode blocks run inside the timed calls so far
    pub fn timed_profile(&self) -> Vec<FnCost> {
        self.cpu.get_data().fn_timer.as_ref().map_or_else(Vec::new, |t| profile::by_function(&t.inside, &self.image.symbols, 0))
    }

    // the timed calls so far by call site: (index into the names, `function+offset` of the
    // return address, calls, inclusive cycles), most cycles first
    pub fn timed_callers(&self) -> Vec<(usize, String, u64, u64)> {
        let Some(t) = self.cpu.get_data().fn_timer.as_ref() else { return Vec::new() };
        let mut m: std::collections::HashMap<(usize, String), (u64, u64)> = Default::default();
        for (&(k, ret), &(n, c)) in &t.sites {
            let name = self.image.symbols.lookup(ret).map_or_else(|| format!("{ret:#010x}"), |(f, o)| format!("{f}+{o:#x}"));
            let e = m.entry((k, name)).or_default();
            e.0 += n;
            e.1 += c;
        }
        let mut v: Vec<_> = m.into_iter().map(|((k, f), (n, c))| (k, f, n, c)).collect();
        v.sort_by(|a, b| b.3.cmp(&a.3).then(a.1.cmp(&b.1)));
        v
    }

    // the timed calls so far: (index into the names, inclusive thread-mode cycles, machine
    // cycle at return); timing stops
    pub fn timed_calls(&mut self) -> Vec<(usize, u64, u64)> {
        self.cpu.get_data_mut().fn_timer.take().map(|t| t.done).unwrap_or_default()
    }

    // the function symbol containing `addr` and the offset into it
    pub fn symbol(&self, addr: u32) -> Option<(&str, u32)> {
        self.image.symbols.lookup(addr)
    }

    pub(crate) fn stats(&self) -> &Stats {
        &self.stats
    }

    // modeled cycles at which the firmware reset the MCU (AIRCR.SYSRESETREQ)
    pub fn system_resets(&self) -> &[u64] {
        &self.soft_resets
    }

    // modeled cycles at which the independent watchdog reset the MCU
    pub fn watchdog_resets(&self) -> &[u64] {
        &self.watchdogs
    }
}
