//! Modeled Cortex-M3 cycle costs: decodes a translated block once and caches per-instruction
//! costs, so the block hook only adds a prefix sum. For the run loop in `board.rs`.
//!
//! Costs follow the Cortex-M3 TRM (r1p1, table 18-1 "Cortex-M3 instruction set summary"),
//! with the STM32F103's memory timing from `memory.rs` added: flash wait states as FLASH_ACR
//! sets them (W; 2 at 72 MHz), the line schedule of the prefetch buffer (stalls when code
//! outruns 8 bytes per line read), and the refill after a taken branch (a line read in flash,
//! 2 cycles in SRAM). Peripheral bridge stalls are dynamic: `mcu.rs` adds them per access.
//!
//! | class                                   | modeled cycles                    |
//! |-----------------------------------------|-----------------------------------|
//! | ALU, MOV, shifts, extend, MUL, IT, hints | 1                                 |
//! | MLA, MLS                                | 2                                 |
//! | UMULL/SMULL, UMLAL/SMLAL                | 4, 5 (TRM: 3–5, 4–7)              |
//! | UDIV/SDIV                               | 7 (TRM: 2–12, data dependent)     |
//! | LDR/STR single                          | 2, or 1 right after a load/store  |
//! | LDR literal (from flash)                | 2 + W                             |
//! | LDRD/STRD, LDM/STM/PUSH/POP             | 1 + N                             |
//! | taken branch, write to PC               | 1 + P, P = 1 + W in flash, 2 in SRAM |
//! | TBB/TBH                                 | 2 + W (table read) + P            |
//! | ISB                                     | 1 + P                             |
//! | not-taken conditional branch            | 1                                 |
//! | any instruction in flash                | + fetch stall of the line schedule |

use std::collections::HashMap;

use super::memory::{fetch_stalls, FlashConfig, CODE_END};

/// How an instruction ends a block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Falls through to the next instruction.
    Next,
    /// Always branches (B, BL, BX, POP {pc}, LDR pc, ...).
    Branch,
    /// Branches only if a condition holds (B<c>, CBZ, CBNZ, or inside an IT block).
    CondBranch,
}

/// One decoded instruction.
#[derive(Clone, Copy, Debug)]
pub struct Insn {
    pub addr: u32,
    /// Modeled cycles when it does not branch.
    pub cost: u64,
    pub flow: Flow,
    pub wfi: bool,
}

/// A decoded block: instructions and prefix sums of their costs.
#[derive(Clone, Debug)]
pub struct Block {
    pub start: u32,
    /// Flash configuration the costs were computed for.
    pub flash: FlashConfig,
    pub end: u32,
    pub insns: Vec<Insn>,
    /// `prefix[k]` = cycles of the first `k` instructions (no branch penalty).
    pub prefix: Vec<u64>,
}

impl Block {
    // cycles of the whole block, adding the refill when the last instruction branched to `next`
    pub fn cost_to(&self, next: u32) -> u64 {
        let base = self.prefix[self.insns.len()];
        match self.insns.last() {
            Some(last) if last.flow == Flow::Branch || (last.flow == Flow::CondBranch && next != self.end) => {
                base + self.flash.refill(next)
            }
            _ => base,
        }
    }

    // index of the instruction at `pc`, or `None` outside this block
    pub fn index_of(&self, pc: u32) -> Option<usize> {
        if pc == self.end {
            return Some(self.insns.len());
        }
        self.insns.iter().position(|i| i.addr == pc)
    }

    // number of leading instructions whose end lies before `cycles` after the block start
    pub fn insns_before(&self, cycles: u64) -> usize {
        self.prefix.iter().position(|&p| p >= cycles).unwrap_or(self.insns.len())
    }
}

/// Hashes a block's start address with one multiply: the block hook looks blocks up three
/// times per block, and SipHash took a quarter of a USB stream test's host time.
#[derive(Default)]
struct AddrHasher(u64);

impl std::hash::Hasher for AddrHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u32(b as u32 ^ (self.0 as u32).rotate_left(8));
        }
    }

    fn write_u32(&mut self, n: u32) {
        self.0 = (n as u64 ^ self.0).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }

    fn finish(&self) -> u64 {
        self.0 ^ self.0 >> 29
    }
}

/// Decoded blocks by start address, for one flash configuration.
pub struct BlockCache {
    blocks: HashMap<u32, Block, std::hash::BuildHasherDefault<AddrHasher>>,
    flash: FlashConfig,
}

impl Default for BlockCache {
    fn default() -> Self {
        Self { blocks: HashMap::default(), flash: FlashConfig::RESET }
    }
}

impl BlockCache {
    // the flash configuration blocks are costed for
    pub fn flash(&self) -> FlashConfig {
        self.flash
    }

    // cost blocks for `flash` from now on (drops the blocks costed for another configuration)
    pub fn set_flash(&mut self, flash: FlashConfig) {
        if flash != self.flash {
            self.flash = flash;
            self.blocks.clear();
        }
    }

    // is the block at `start` of `size` bytes decoded?
    pub fn contains(&self, start: u32, size: u32) -> bool {
        self.blocks.get(&start).is_some_and(|b| b.end == start + size)
    }

    // decode and keep the block at `start` whose bytes are `code`
    pub fn insert(&mut self, start: u32, code: &[u8]) {
        self.blocks.insert(start, decode_block(start, code, self.flash));
    }

    // the cached block at `start`
    pub fn at(&self, start: u32) -> Option<&Block> {
        self.blocks.get(&start)
    }
}

// decode the Thumb-2 instructions in `code` (which starts at `start`), costed for `flash`
pub fn decode_block(start: u32, code: &[u8], flash: FlashConfig) -> Block {
    let mut insns = Vec::new();
    let mut sizes = Vec::new();
    let mut off = 0usize;
    let w = flash.data_read_extra(start < CODE_END);
    let mut prev_mem = false;
    let mut it_left = 0u32;
    while off + 2 <= code.len() {
        let hw1 = u16::from_le_bytes([code[off], code[off + 1]]);
        let wide = hw1 >> 11 >= 0b11101;
        let hw2 = if wide && off + 4 <= code.len() { u16::from_le_bytes([code[off + 2], code[off + 3]]) } else { 0 };
        let addr = start + off as u32;
        let mut d = if wide { decode32(hw1, hw2, addr, &flash, w) } else { decode16(hw1, w) };
        if it_left > 0 {
            it_left -= 1;
            if d.flow == Flow::Branch {
                d.flow = Flow::CondBranch;
            }
        }
        if hw1 & 0xFF00 == 0xBF00 && hw1 & 0x000F != 0 {
            it_left = 4 - (hw1 & 0xF).trailing_zeros();
        }
        // Neighbouring single loads/stores pipeline (TRM §18.3): the second costs 1.
        let cost = if d.single_mem && prev_mem { d.cost - 1 } else { d.cost };
        prev_mem = d.single_mem;
        insns.push(Insn { addr, cost, flow: d.flow, wfi: hw1 == 0xBF30 });
        let size = if wide { 4 } else { 2 };
        sizes.push((addr, size, cost, d.data));
        off += size as usize;
    }
    // Fetch stalls count as part of the instruction that waited.
    let stalls = fetch_stalls(&flash, &sizes);
    let mut prefix = vec![0];
    for (i, s) in insns.iter_mut().zip(stalls) {
        i.cost += s;
        prefix.push(prefix.last().unwrap() + i.cost);
    }
    Block { start, flash, end: start + off as u32, insns, prefix }
}

struct Decoded {
    cost: u64,
    flow: Flow,
    single_mem: bool,
    /// Data transfers on the bus (words): what SRAM code's fetches share the System bus with.
    data: u64,
}

fn alu() -> Decoded {
    Decoded { cost: 1, flow: Flow::Next, single_mem: false, data: 0 }
}

fn mem(cost: u64) -> Decoded {
    Decoded { cost, flow: Flow::Next, single_mem: true, data: 1 }
}

fn branch(cost: u64, flow: Flow) -> Decoded {
    Decoded { cost, flow, single_mem: false, data: 0 }
}

// a transfer of `words` words (LDM/STM/PUSH/POP, LDRD/STRD): 1 + `words` cycles
fn multi(words: u64, flow: Flow) -> Decoded {
    Decoded { cost: 1 + words, flow, single_mem: false, data: words }
}

// 16-bit Thumb instruction
fn decode16(hw: u16, w: u64) -> Decoded {
    match hw >> 10 {
        0b010001 => {
            // ADD/CMP/MOV high registers, BX/BLX.
            let op = (hw >> 8) & 3;
            let rd = ((hw >> 4) & 8) | (hw & 7);
            if op == 3 || (op != 1 && rd == 15) {
                branch(1, Flow::Branch)
            } else {
                alu()
            }
        }
        0b010010 | 0b010011 => mem(2 + w), // LDR literal
        _ => match hw >> 12 {
            0b0101..=0b1001 => mem(2),
            0b1011 => misc16(hw),
            0b1100 => multi((hw & 0xFF).count_ones() as u64, Flow::Next), // LDM/STM
            0b1101 => match (hw >> 8) & 0xF {
                0xE | 0xF => alu(), // UDF, SVC
                _ => branch(1, Flow::CondBranch),
            },
            0b1110 => branch(1, Flow::Branch), // B
            _ => alu(),
        },
    }
}

// 16-bit miscellaneous (1011 xxxx)
fn misc16(hw: u16) -> Decoded {
    let regs = (hw & 0xFF).count_ones() as u64;
    match (hw >> 8) & 0xF {
        0x1 | 0x3 | 0x9 | 0xB => branch(1, Flow::CondBranch), // CBZ/CBNZ
        0x4 | 0x5 => multi(regs + ((hw >> 8) & 1) as u64, Flow::Next), // PUSH
        0xC | 0xD if hw & 0x100 != 0 => multi(regs + 1, Flow::Branch), // POP {.., pc}
        0xC | 0xD => multi(regs, Flow::Next), // POP
        _ => alu(),
    }
}

// 32-bit Thumb-2 instruction
fn decode32(hw1: u16, hw2: u16, addr: u32, flash: &FlashConfig, w: u64) -> Decoded {
    match hw1 >> 11 {
        0b11101 if hw1 & 0x0600 == 0 => {
            if hw1 & 0x0040 == 0 {
                // LDM/STM: 1 + N; a load of PC branches.
                let regs = hw2.count_ones() as u64;
                let load = hw1 & 0x0010 != 0;
                let flow = if load && hw2 & 0x8000 != 0 { Flow::Branch } else { Flow::Next };
                multi(regs, flow)
            } else if hw1 & 0xFFF0 == 0xE8D0 && hw2 & 0xFFE0 == 0xF000 {
                Decoded { data: 1, ..branch(2 + w, Flow::Branch) } // TBB/TBH
            } else if hw1 & 0x0120 != 0 || hw1 & 0x0080 != 0 {
                multi(2, Flow::Next) // LDRD/STRD
            } else {
                mem(2) // LDREX/STREX
            }
        }
        0b11110 if hw2 & 0x8000 != 0 => {
            if hw2 & 0x5000 != 0 {
                branch(1, Flow::Branch) // B.W, BL
            } else if (hw1 >> 6) & 0xE != 0xE {
                branch(1, Flow::CondBranch) // B<c>.W
            } else if hw1 == 0xF3BF && hw2 & 0xFFF0 == 0x8F60 {
                // ISB: 1 + B, B at least a pipeline refill (TRM table 18-1).
                Decoded { cost: 1 + flash.refill(addr + 4), ..alu() }
            } else {
                alu() // MSR, MRS, hints, DSB/DMB (1 + B, B ≥ 0)
            }
        }
        0b11111 => match (hw1 >> 8) & 0x7 {
            0 | 1 => {
                let rn = hw1 & 0xF;
                let rt = hw2 >> 12;
                let load = hw1 & 0x0010 != 0;
                if load && rt == 15 {
                    Decoded { data: 1, ..branch(2, Flow::Branch) }
                } else if rn == 15 {
                    mem(2 + w)
                } else {
                    mem(2)
                }
            }
            3 => match (hw1 >> 4) & 0xF {
                0x0 if hw2 & 0xF0F0 == 0xF000 => alu(), // MUL
                0x0 | 0x1 => Decoded { cost: 2, ..alu() }, // MLA/MLS
                0x8 | 0xA => Decoded { cost: 4, ..alu() }, // SMULL/UMULL
                0x9 | 0xB => Decoded { cost: 7, ..alu() }, // SDIV/UDIV
                0xC | 0xE => Decoded { cost: 5, ..alu() }, // SMLAL/UMLAL
                _ => alu(),
            },
            _ => alu(),
        },
        _ => alu(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WS2: FlashConfig = FlashConfig::from_acr(0x12);

    #[test]
    fn costs_of_a_small_block() {
        // movs r0,#1; ldr r3,[pc,#8]; str r0,[r3]; str r0,[r3,#4]; bx lr
        let code = [0x01, 0x20, 0x02, 0x4b, 0x18, 0x60, 0x58, 0x60, 0x70, 0x47];
        let b = decode_block(0x0800_0000, &code, WS2);
        let costs: Vec<u64> = b.insns.iter().map(|i| i.cost).collect();
        assert_eq!(costs, vec![1, 4, 1, 1, 1]);
        assert_eq!(b.insns[4].flow, Flow::Branch);
        assert_eq!(b.cost_to(0x0800_0100), 8 + 3);
    }

    #[test]
    fn isb_refills_the_pipeline() {
        // isb sy; nop
        let b = decode_block(0x0800_0000, &[0xBF, 0xF3, 0x6F, 0x8F, 0x00, 0xBF], WS2);
        assert_eq!(b.insns.iter().map(|i| i.cost).collect::<Vec<_>>(), vec![4, 1]);
    }

    #[test]
    fn branch_refill_follows_flash_latency_and_sram() {
        // subs r0,#4; bhi .-2
        let code = [0x04, 0x38, 0xFD, 0xD8];
        let ram = decode_block(0x2000_0000, &code, WS2);
        assert_eq!(ram.cost_to(0x2000_0000), 4, "SRAM: 1 + (1 + P = 2)");
        let flash = decode_block(0x0800_0000, &code, WS2);
        assert_eq!(flash.cost_to(0x0800_0000), 5, "flash, 2 wait states: 1 + (1 + 3)");
        let fast = decode_block(0x0800_0000, &code, FlashConfig::RESET);
        assert_eq!(fast.cost_to(0x0800_0000), 3, "flash, 0 wait states: 1 + (1 + 1)");
        assert_eq!(fast.cost_to(0x0800_0004), 2, "not taken");
    }
}
