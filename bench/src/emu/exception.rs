//! Exception entry, return and tail-chaining done by the bench (unicorn has no NVIC):
//! stacks the 8-word frame (with the 8-byte alignment bit), loads the vector from VTOR and
//! sets LR to EXC_RETURN and clears the IT state; on a branch to 0xFFFFFFF1/F9/FD it unstacks
//! (flags and IT state from the stacked xPSR). Unicorn itself stays in
//! "thread mode" (IPSR 0) all the time; the bench keeps IPSR in `Nvic::stack`. For `board.rs`.
//!
//! Modeled costs (Cortex-M3 TRM §5.5, zero wait states, plus the flash wait states W of
//! FLASH_ACR for the vector/first-instruction or return-address fetch; `memory.rs`):
//! entry 12 + W, return 10 + W, tail-chain 6 + W (W = 2 at 72 MHz).

use unicorn_engine::RegisterARM;

use super::cpu::Cpu;

/// xPSR Thumb bit and IT/ICI bits (ARMv7-M ARM B1.4.2).
const EPSR_T: u32 = 1 << 24;
const EPSR_IT: u32 = 0x0600_FC00;

const FRAME: [RegisterARM; 7] =
    [RegisterARM::R0, RegisterARM::R1, RegisterARM::R2, RegisterARM::R3, RegisterARM::R12, RegisterARM::LR, RegisterARM::PC];

// read a little-endian word
fn read32(uc: &Cpu, addr: u32) -> u32 {
    let mut b = [0u8; 4];
    let _ = uc.mem_read(addr as u64, &mut b);
    u32::from_le_bytes(b)
}

// push the frame of the interrupted context; returns the EXC_RETURN value for it
pub fn stack_frame(uc: &mut Cpu) -> u32 {
    let handler = uc.get_data().nvic.ipsr();
    let control = uc.reg_read(RegisterARM::CONTROL).unwrap_or(0) as u32;
    let psp = handler == 0 && control & 2 != 0;
    let sp = uc.reg_read(RegisterARM::SP).unwrap_or(0) as u32;
    let mut frame = sp.wrapping_sub(32);
    let realign = frame & 4 != 0;
    if realign {
        frame -= 4;
    }
    let mut words = [0u32; 8];
    for (w, r) in words.iter_mut().zip(FRAME) {
        *w = uc.reg_read(r).unwrap_or(0) as u32;
    }
    let xpsr = uc.reg_read(RegisterARM::XPSR).unwrap_or(0) as u32;
    words[7] = (xpsr & !0x3FF) | 1 << 24 | handler | (realign as u32) << 9;
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let _ = uc.mem_write(frame as u64, &bytes);
    if psp {
        let _ = uc.reg_write(RegisterARM::PSP, frame as u64);
        let _ = uc.reg_write(RegisterARM::CONTROL, (control & !2) as u64);
    } else {
        let _ = uc.reg_write(RegisterARM::SP, frame as u64);
    }
    match (handler != 0, psp) {
        (true, _) => 0xFFFF_FFF1,
        (false, true) => 0xFFFF_FFFD,
        (false, false) => 0xFFFF_FFF9,
    }
}

// start exception `n`: activate it, set LR and jump to its vector; returns the handler address
pub fn enter(uc: &mut Cpu, n: u32, exc_return: u32) -> u32 {
    let m = uc.get_data_mut();
    m.nvic.activate(n);
    let vtor = m.nvic.vtor;
    let vector = read32(uc, vtor + 4 * n);
    let _ = uc.reg_write(RegisterARM::LR, exc_return as u64);
    // The handler starts outside any IT block (the interrupted one's state is in the frame).
    let _ = uc.reg_write(RegisterARM::EPSR, EPSR_T as u64);
    let _ = uc.reg_write(RegisterARM::PC, (vector & !1) as u64);
    vector & !1
}

// pop the frame selected by `exc_return` and restore the interrupted context
pub fn unstack(uc: &mut Cpu, exc_return: u32) {
    let psp = exc_return & 4 != 0;
    let sp = if psp { uc.reg_read(RegisterARM::PSP) } else { uc.reg_read(RegisterARM::MSP) }.unwrap_or(0) as u32;
    let words: Vec<u32> = (0..8).map(|i| read32(uc, sp + 4 * i)).collect();
    for (w, r) in words.iter().zip(FRAME) {
        let _ = uc.reg_write(r, *w as u64);
    }
    let xpsr = words[7];
    let _ = uc.reg_write(RegisterARM::APSR_NZCVQ, (xpsr & 0xF800_0000) as u64);
    // Resume an interrupted IT block where it stopped.
    let _ = uc.reg_write(RegisterARM::EPSR, (xpsr & EPSR_IT | EPSR_T) as u64);
    let new_sp = sp + 32 + if xpsr & 1 << 9 != 0 { 4 } else { 0 };
    if psp {
        let control = uc.reg_read(RegisterARM::CONTROL).unwrap_or(0);
        let _ = uc.reg_write(RegisterARM::CONTROL, control | 2);
        let _ = uc.reg_write(RegisterARM::PSP, new_sp as u64);
    } else {
        let _ = uc.reg_write(RegisterARM::MSP, new_sp as u64);
        let _ = uc.reg_write(RegisterARM::SP, new_sp as u64);
    }
}
