//! Builds the unicorn Cortex-M3 with the Blue Pill memory map and the hooks that feed the
//! time model: a block hook (adds cached block costs, stops before a block when an event
//! is due) and MMIO callbacks into `mcu::Mcu`. For `board.rs`.
//!
//! Memory map: flash 128 KiB at 0x0800_0000 (copied to the boot alias at 0), RAM 20 KiB at
//! 0x2000_0000, system memory (flash size, UID: [`write_chip`]) at 0x1FFF_F000, peripherals 0x4000_0000–
//! 0x4002_FFFF, their bit-band alias at 0x4200_0000, SRAM bit-band at 0x2200_0000 and the
//! private peripheral bus at 0xE000_0000.

use anyhow::{anyhow, Context, Result};
use object::{Object, ObjectSegment, ObjectSymbol};
use unicorn_engine::unicorn_const::{Arch, Mode, Prot};
use unicorn_engine::{ArmCpuModel, RegisterARM, Unicorn};

use ddastep::grbl::chip::{Chip, FLASH_SIZE_ADDR, UID_ADDR};

use super::mcu::{Mcu, Stop};
use super::profile::Symbols;

pub const FLASH_BASE: u32 = 0x0800_0000;
/// Flash mapped: 128 KiB, what the C8 die holds (ST guarantees 64 and F_SIZE reads 64).
pub const FLASH_SIZE: u32 = 128 * 1024;
pub const RAM_BASE: u32 = 0x2000_0000;
pub const RAM_SIZE: u32 = 20 * 1024;
/// Byte RAM holds at power-up in the emulator, so the deepest stack use shows as the lowest
/// byte that no longer holds it ([`Image::stack_end`] up to the top of RAM).
pub const STACK_PAINT: u8 = 0xA5;
/// System memory (read-only: the device registers the chip check reads).
const SYSTEM_BASE: u32 = 0x1FFF_F000;
/// The part the emulator is unless told otherwise: a genuine STM32F103C8 (64 KiB; the ID
/// spells `ddastep-emu!`; a Cortex-M3 r1p1).
pub const BLUE_PILL: Chip = Chip {
    flash_kib: 64,
    uid: [u32::from_le_bytes(*b"ddas"), u32::from_le_bytes(*b"tep-"), u32::from_le_bytes(*b"emu!")],
    cpuid: super::mcu::CPUID_M3_R1P1,
};

/// The loaded program: entry state and symbols the bench uses.
pub struct Image {
    pub initial_sp: u32,
    pub reset: u32,
    pub rtt: Option<u32>,
    /// Lowest address the stack may use (cortex-m-rt's `_stack_end`: the end of the statics).
    pub stack_end: Option<u32>,
    pub symbols: Symbols,
}

pub type Cpu = Unicorn<'static, Mcu>;

// map memory, install hooks and load `elf` into a new CPU
pub fn build(elf: &[u8]) -> Result<(Cpu, Image)> {
    let e = |err| anyhow!("unicorn: {err:?}");
    let mut uc = Unicorn::new_with_data(Arch::ARM, Mode::THUMB | Mode::MCLASS, Mcu::new()).map_err(e)?;
    uc.ctl_set_cpu_model(ArmCpuModel::CORTEX_M3 as i32).map_err(e)?;
    uc.mem_map(0, FLASH_SIZE as u64, Prot::READ | Prot::EXEC).map_err(e)?;
    uc.mem_map(FLASH_BASE as u64, FLASH_SIZE as u64, Prot::ALL).map_err(e)?;
    uc.mem_map(RAM_BASE as u64, RAM_SIZE as u64, Prot::ALL).map_err(e)?;
    uc.mem_write(RAM_BASE as u64, &[STACK_PAINT; RAM_SIZE as usize]).map_err(e)?;
    uc.mem_map(SYSTEM_BASE as u64, 0x1000, Prot::READ).map_err(e)?;
    write_chip(&mut uc, &BLUE_PILL)?;
    map_mmio(&mut uc, 0x4000_0000, 0x3_0000, 0).map_err(e)?;
    map_mmio(&mut uc, 0xE000_0000, 0x10_0000, 0).map_err(e)?;
    map_bitband(&mut uc, 0x4200_0000, 0x4000_0000, 0x3_0000).map_err(e)?;
    map_bitband(&mut uc, 0x2200_0000, RAM_BASE, RAM_SIZE).map_err(e)?;
    uc.add_block_hook(1, 0, on_block).map_err(e)?;
    let image = load_elf(&mut uc, elf)?;
    uc.reg_write(RegisterARM::SP, image.initial_sp as u64).map_err(e)?;
    Ok((uc, image))
}

/// Makes the emulated part `c`: its flash size and unique ID in system memory, its CPUID (the
/// firmware reads them at boot: set before the first run).
pub fn write_chip(uc: &mut Cpu, c: &Chip) -> Result<()> {
    let e = |err| anyhow!("unicorn: {err:?}");
    uc.mem_write(FLASH_SIZE_ADDR as u64, &c.flash_kib.to_le_bytes()).map_err(e)?;
    let uid: Vec<u8> = c.uid.iter().flat_map(|w| w.to_le_bytes()).collect();
    uc.mem_write(UID_ADDR as u64, &uid).map_err(e)?;
    uc.get_data_mut().cpuid = c.cpuid;
    Ok(())
}

fn map_mmio(uc: &mut Cpu, base: u64, size: u64, _: u32) -> Result<(), unicorn_engine::unicorn_const::uc_error> {
    uc.mmio_map(
        base,
        size,
        Some(move |uc: &mut Unicorn<Mcu>, off: u64, len: usize| {
            let pc = uc.reg_read(RegisterARM::PC).unwrap_or(0) as u32;
            let m = uc.get_data_mut();
            m.pc = pc;
            m.read((base + off) as u32, len) as u64
        }),
        Some(move |uc: &mut Unicorn<Mcu>, off: u64, len: usize, value: u64| {
            let pc = uc.reg_read(RegisterARM::PC).unwrap_or(0) as u32;
            let m = uc.get_data_mut();
            m.pc = pc;
            m.write((base + off) as u32, len, value as u32);
            if let Some(page) = m.flash_erase.take() {
                let page = page & !0x3FF;
                if (FLASH_BASE..FLASH_BASE + FLASH_SIZE).contains(&page) {
                    let _ = uc.mem_write(page as u64, &[0xFF; 1024]);
                }
            }
            // A write may pend an interrupt or move the next event: the block hook re-checks at
            // the next block. (Stopping here would make unicorn replay the store.)
            let m = uc.get_data_mut();
            m.deadline = m.deadline.min(m.next_event());
            // A store to the SCS that pends an exception (NVIC ISPR/STIR, ICSR) preempts right
            // after the store. Unicorn then reports the store's own PC; `board.rs` steps past it.
            if base == 0xE000_0000 && m.pending {
                m.mmio_stop = Some(pc);
                let _ = uc.emu_stop();
            }
        }),
    )
}

// bit-band alias: word n of the alias is bit n%32 of word n/32 of the target region
fn map_bitband(uc: &mut Cpu, alias: u64, target: u32, size: u32) -> Result<(), unicorn_engine::unicorn_const::uc_error> {
    let locate = move |off: u64| ((target + (off / 32) as u32) & !3, ((off / 32) % 4 * 8 + (off % 32) / 4) as u32);
    let is_ram = target == RAM_BASE;
    uc.mmio_map(
        alias,
        size as u64 * 32,
        Some(move |uc: &mut Unicorn<Mcu>, off: u64, _len: usize| {
            let (word, bit) = locate(off);
            let v = if is_ram {
                let mut b = [0u8; 4];
                let _ = uc.mem_read(word as u64, &mut b);
                u32::from_le_bytes(b)
            } else {
                let pc = uc.reg_read(RegisterARM::PC).unwrap_or(0) as u32;
                uc.get_data_mut().pc = pc;
                uc.get_data_mut().read(word, 4)
            };
            ((v >> bit) & 1) as u64
        }),
        Some(move |uc: &mut Unicorn<Mcu>, off: u64, _len: usize, value: u64| {
            let (word, bit) = locate(off);
            if is_ram {
                let mut b = [0u8; 4];
                let _ = uc.mem_read(word as u64, &mut b);
                let v = u32::from_le_bytes(b) & !(1 << bit) | ((value as u32 & 1) << bit);
                let _ = uc.mem_write(word as u64, &v.to_le_bytes());
            } else {
                let pc = uc.reg_read(RegisterARM::PC).unwrap_or(0) as u32;
                let m = uc.get_data_mut();
                m.pc = pc;
                let v = m.read(word, 4) & !(1 << bit) | ((value as u32 & 1) << bit);
                m.write(word, 4, v);
                m.deadline = m.deadline.min(m.next_event());
            }
        }),
    )
}

// copy the ELF's loadable segments into flash/RAM and find the vector table and RTT block
fn load_elf(uc: &mut Cpu, elf: &[u8]) -> Result<Image> {
    let file = object::File::parse(elf).context("parsing ELF")?;
    for seg in file.segments() {
        let data = seg.data()?;
        if data.is_empty() {
            continue;
        }
        let (addr, _) = seg.file_range();
        let _ = addr;
        let paddr = segment_paddr(elf, seg.address()).unwrap_or(seg.address());
        uc.mem_write(paddr, data).map_err(|err| anyhow!("loading segment at {paddr:#x}: {err:?}"))?;
        if (FLASH_BASE as u64..(FLASH_BASE + FLASH_SIZE) as u64).contains(&paddr) {
            uc.mem_write(paddr - FLASH_BASE as u64, data).map_err(|err| anyhow!("boot alias: {err:?}"))?;
        }
    }
    let mut vt = [0u8; 8];
    uc.mem_read(FLASH_BASE as u64, &mut vt).map_err(|err| anyhow!("{err:?}"))?;
    let rtt = file.symbols().find(|s| s.name() == Ok("_SEGGER_RTT")).map(|s| s.address() as u32);
    let stack_end = file.symbols().find(|s| s.name() == Ok("_stack_end")).map(|s| s.address() as u32);
    Ok(Image {
        initial_sp: u32::from_le_bytes(vt[0..4].try_into().unwrap()),
        reset: u32::from_le_bytes(vt[4..8].try_into().unwrap()),
        rtt,
        stack_end,
        symbols: Symbols::from_elf(elf),
    })
}

// physical (load) address of the program header whose virtual address is `vaddr`
fn segment_paddr(elf: &[u8], vaddr: u64) -> Option<u64> {
    use object::read::elf::{FileHeader, ProgramHeader};
    let header = object::elf::FileHeader32::<object::Endianness>::parse(elf).ok()?;
    let endian = header.endian().ok()?;
    header
        .program_headers(endian, elf)
        .ok()?
        .iter()
        .find(|ph| ph.p_type(endian) == object::elf::PT_LOAD && ph.p_vaddr(endian) as u64 == vaddr)
        .map(|ph| ph.p_paddr(endian) as u64)
}

// block hook: account the previous block, then stop before this one if an event is due
fn on_block(uc: &mut Unicorn<Mcu>, addr: u64, size: u32) {
    let addr = addr as u32;
    let m = uc.get_data_mut();
    if let Some(prev) = m.cur.take() {
        let b = m.blocks.at(prev).expect("current block is cached");
        let (cycles, n) = (b.cost_to(addr), b.insns.len() as u64);
        m.account(prev, cycles, n);
    }
    m.apply_flash_config();
    // DMA requests raised by this run's peripheral accesses: served at this block boundary.
    super::dma_run::service(uc, true);
    let m = uc.get_data_mut();
    if m.fn_timer.is_some() && m.nvic.ipsr() == 0 {
        time_calls(uc, addr);
    }
    if !uc.get_data().blocks.contains(addr, size) {
        let mut code = vec![0u8; size as usize];
        let _ = uc.mem_read(addr as u64, &mut code);
        uc.get_data_mut().blocks.insert(addr, &code);
    }
    let (basepri, primask) = if uc.get_data().pending {
        (uc.reg_read(RegisterARM::BASEPRI).unwrap_or(0) as u32, uc.reg_read(RegisterARM::PRIMASK).unwrap_or(0) != 0)
    } else {
        (0, false)
    };
    let m = uc.get_data_mut();
    m.cur = Some(addr);
    if m.armed == Some((addr, m.now)) {
        m.armed = None;
        mark_move_end(m, addr);
        return;
    }
    let block = m.blocks.at(addr).expect("just cached");
    let n = block.insns.len();
    let k = block.insns_before(m.deadline.saturating_sub(m.now));
    let preempt = m.pending && m.nvic.preempting(basepri, primask).is_some();
    if preempt || m.now >= m.deadline || (k > 0 && k < n) {
        m.stop = if preempt || m.now >= m.deadline { Stop::Event } else { Stop::Split(k) };
        let _ = uc.emu_stop();
    } else {
        mark_move_end(m, addr);
    }
}

// a block that runs now at `addr`: a move end if it is `finish`'s entry (only blocks that run:
// a block stopped before it runs is entered again, and would count the end twice)
fn mark_move_end(m: &mut Mcu, addr: u32) {
    if m.record_edges && m.move_marks.targets.contains(&addr) {
        let tim2 = m.nvic.ipsr() == super::nvic::IRQ0 + super::mcu::TIM2_IRQ;
        m.move_marks.hits.push((m.now, tim2));
    }
}

// the function timer (`profile::FnTimer`): a thread-mode block starting at `addr` opens a call
// of a timed function or closes the innermost open one
fn time_calls(uc: &mut Unicorn<Mcu>, addr: u32) {
    let sp = uc.reg_read(RegisterARM::SP).unwrap_or(0) as u32;
    let lr = uc.reg_read(RegisterARM::LR).unwrap_or(0) as u32;
    let m = uc.get_data_mut();
    let (now, thread) = (m.now, m.thread_cycles);
    let Some(t) = m.fn_timer.as_mut() else { return };
    // a tail call returns to its caller's return address: every call that ends here closes
    let mut closed = false;
    while let Some(&(ret, at_sp, k, start)) = t.open.last() {
        if ret != addr || sp < at_sp {
            break;
        }
        t.open.pop();
        t.done.push((k, thread - start, now));
        let site = t.sites.entry((k, ret)).or_default();
        site.0 += 1;
        site.1 += thread - start;
        closed = true;
    }
    if closed {
        return;
    }
    if let Some(&(_, k)) = t.targets.iter().find(|(a, _)| *a == addr) {
        t.open.push((lr & !1, sp, k, thread));
    }
}
