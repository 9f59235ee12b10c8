//! Memory and bus timing of the STM32F103 that the instruction costs in `cost.rs` leave out:
//! flash wait states and the prefetch buffer (following FLASH_ACR), instruction fetch from SRAM
//! over the System bus, and the AHB-to-APB bridges (following RCC_CFGR's APB dividers).
//! For `cost.rs` (static, per translated block) and `bus.rs` (dynamic, per peripheral access).
//!
//! Sources and fits (bench/README.md, "Model", has the same list):
//! - RM0008 §3.3.3: flash is read in 64-bit lines, LATENCY wait states (2 at 72 MHz), a
//!   prefetch buffer of two lines that reads the next line while the current one is used.
//!   A line therefore takes `1 + LATENCY` cycles; sequential code gets 8 bytes per line time.
//! - Cortex-M3 TRM table 18-1: a taken branch costs `1 + P`, P ≥ 1 the pipeline refill. Here
//!   P = one line read for a target in flash (1 + LATENCY), plus the stalls of the target
//!   block's own line schedule (a 32-bit target straddling two lines waits for both).
//! - Measured (blaatschaap.be, "Wait a microsecond"): `subs r0,#4; bhi` from SRAM takes 4
//!   cycles per iteration on an STM32F103, so P = 2 for a branch to SRAM (the System bus
//!   fetch is registered: one cycle more than the TRM's best case).
//! - Fitted (blog.soch.cc, "Fastest GPIO read speed STM32F103"): a loop reading GPIOA->IDR
//!   takes 12.03 cycles per iteration from flash at 72 MHz, 2 wait states, prefetch on. With
//!   the flash model above this leaves 3 cycles of bridge stall on the APB2 read: modeled as
//!   `1 + 2·d` cycles for an APB with divider d (one cycle to cross the bridge, APB setup and
//!   access phases of d core cycles each). APB1 (TIM2, divider 2 at 72 MHz) is that formula
//!   extrapolated: 5 cycles; not measured.
//! - Assumed: a peripheral write is absorbed by the core's write buffer (the store costs what
//!   an SRAM store costs) but keeps the bridge busy for the same `1 + 2·d` cycles; the next
//!   peripheral access waits for it. It lands (pin edges are recorded) at the end of that.

/// First address past the code region (flash and its boot alias); SRAM code lies above.
pub const CODE_END: u32 = 0x2000_0000;
/// Flash line: the prefetch buffer's unit (RM0008 §3.3.3).
const LINE: u32 = 8;
/// Refill after a taken branch to SRAM: 1 (TRM) + 1 for the registered System bus (measured).
const SRAM_REFILL: u64 = 2;

/// Flash access configuration (FLASH_ACR).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FlashConfig {
    /// LATENCY: wait states per line read.
    pub wait_states: u64,
    /// PRFTBE: prefetch buffer enabled.
    pub prefetch: bool,
}

impl FlashConfig {
    /// Reset value of FLASH_ACR (0x30): zero wait states, prefetch on.
    pub const RESET: Self = Self::from_acr(0x30);

    // the configuration FLASH_ACR = `acr` selects
    pub const fn from_acr(acr: u32) -> Self {
        Self { wait_states: (acr & 7) as u64, prefetch: acr & 0x10 != 0 }
    }

    // cycles to read one flash line
    pub fn line_cycles(&self) -> u64 {
        1 + self.wait_states
    }

    // pipeline refill for a taken branch (or exception return) to `target`
    pub fn refill(&self, target: u32) -> u64 {
        if target < CODE_END {
            self.line_cycles()
        } else {
            SRAM_REFILL
        }
    }

    // extra cycles of a data read from the code region (literal pools, TBB/TBH tables)
    pub fn data_read_extra(&self, addr_in_code: bool) -> u64 {
        if addr_in_code {
            self.wait_states
        } else {
            0
        }
    }

    // exception entry: 12 (TRM §5.5, zero wait states) + the vector and first-line reads
    pub fn entry_cycles(&self) -> u64 {
        12 + self.wait_states
    }

    // exception return: 10 + the refill at the return address
    pub fn return_cycles(&self) -> u64 {
        10 + self.wait_states
    }

    // tail-chain: 6 + the new handler's vector and first line
    pub fn tail_chain_cycles(&self) -> u64 {
        6 + self.wait_states
    }
}

/// Fetch stalls of straight-line code: the cycles each instruction waits for its bytes.
///
/// The block's first line is taken as available when the block starts (a taken branch paid
/// for it in `refill`); with prefetch on, each further line is read as soon as the previous
/// one has arrived and a buffer is free (two lines), otherwise when the core starts on the
/// previous line. `insns` are (address, size in bytes, execution cycles, data transfers on
/// the bus). SRAM code: see [`sram_fetch_stalls`].
pub fn fetch_stalls(cfg: &FlashConfig, insns: &[(u32, u32, u64, u64)]) -> Vec<u64> {
    let Some(&(start, _, _, _)) = insns.first() else { return Vec::new() };
    if start >= CODE_END {
        return sram_fetch_stalls(insns);
    }
    let first = start / LINE;
    let l = cfg.line_cycles();
    // arrive[k], first_issue[k], last_issue[k] for line first + k
    let mut arrive: Vec<u64> = vec![0];
    let mut first_issue: Vec<Option<u64>> = vec![None];
    let mut last_issue: Vec<Option<u64>> = vec![None];
    let mut t = 0u64;
    let mut stalls = Vec::with_capacity(insns.len());
    for &(addr, size, cost, _) in insns {
        let need = ((addr + size - 1) / LINE - first) as usize;
        while arrive.len() <= need {
            let k = arrive.len();
            let request = if cfg.prefetch {
                // The buffer holds two lines: line k waits until the core starts on line k-2.
                let freed = if k >= 2 { first_issue[k - 2].unwrap_or(arrive[k - 2]) } else { 0 };
                arrive[k - 1].max(freed)
            } else {
                // On demand: the core's fetch unit asks for line k when it takes the last
                // instruction that starts in line k-1 (it fetches one word ahead).
                last_issue[k - 1].unwrap_or(arrive[k - 1])
            };
            arrive.push(request + l);
            first_issue.push(None);
            last_issue.push(None);
        }
        let issue = t.max(arrive[need]);
        let own = ((addr / LINE) - first) as usize;
        first_issue[own].get_or_insert(issue);
        last_issue[own] = Some(issue);
        stalls.push(issue - t);
        t = issue + cost;
    }
    stalls
}

/// Words the core's fetch unit may hold ahead of the instruction it executes (Cortex-M3 TRM
/// §1.2: a three-word prefetch buffer).
const FETCH_AHEAD: u64 = 3;

/// Fetch stalls of straight-line code in SRAM. Instructions come over the System bus, 32 bits
/// per bus cycle, and so does every data transfer (SRAM and peripherals): one bus, data first.
/// A cycle-by-cycle schedule: the block's first word is there when it starts (the refill paid
/// for it); each cycle the bus is not moving data, the fetch unit reads the next word if it is
/// fewer than [`FETCH_AHEAD`] words ahead of the instruction executing (or waiting); an
/// instruction's data transfers take the bus in its last cycles (one per word: a single
/// load/store 1, LDRD/STRD 2, LDM/STM/PUSH/POP one per register); an instruction issues once
/// its last halfword has arrived. Assumed from the TRM's bus description, not checked against
/// silicon (the one silicon figure for SRAM code, a loop without data, has no contention).
pub fn sram_fetch_stalls(insns: &[(u32, u32, u64, u64)]) -> Vec<u64> {
    let Some(&(start, _, _, _)) = insns.first() else { return Vec::new() };
    let base = start / 4;
    let word = |addr: u32| (addr / 4 - base) as u64;
    let mut fetched = 1u64; // words 0..fetched are in the buffer
    let mut c = 0u64; // the current cycle
    let mut free_at = 0u64; // the cycle the previous instruction's execution ends
    let mut stalls = Vec::with_capacity(insns.len());
    // Runs cycle `c`: a fetch unless `data` holds the bus, while the fetch unit is fewer than
    // FETCH_AHEAD words past `at` (the first word of the instruction executing or waiting).
    let cycle = |c: &mut u64, fetched: &mut u64, data: bool, at: u64| {
        if !data && *fetched < at + FETCH_AHEAD {
            *fetched += 1;
        }
        *c += 1;
    };
    for &(addr, size, cost, data) in insns {
        let (first, last) = (word(addr), word(addr + size - 1));
        // Wait for the instruction's bytes.
        while fetched <= last {
            cycle(&mut c, &mut fetched, false, first);
        }
        stalls.push(c - free_at);
        // Execute: the data transfers in the last cycles.
        let data = data.min(cost);
        for k in 0..cost {
            cycle(&mut c, &mut fetched, k >= cost - data, first);
        }
        free_at = c;
    }
    stalls
}

/// Which bus a data address is on, for the bridge model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bus {
    /// APB1 (0x4000_0000..0x4001_0000): TIM2-7, USART2/3, I2C, SPI2, ...
    Apb1,
    /// APB2 (0x4001_0000..0x4001_8000): GPIO, AFIO, USART1, TIM1, SPI1, ADC
    Apb2,
    /// Everything else (AHB peripherals, the core's private bus, memory): no bridge.
    Other,
}

// the bus `addr` is on (bit-band aliases resolve to their target before this)
pub fn bus_of(addr: u32) -> Bus {
    match addr {
        0x4000_0000..=0x4000_FFFF => Bus::Apb1,
        0x4001_0000..=0x4001_7FFF => Bus::Apb2,
        _ => Bus::Other,
    }
}

// APB divider from RCC_CFGR's PPREx field (3 bits: 0xx = 1, 100 = 2, ... 111 = 16)
pub fn apb_divider(ppre: u32) -> u64 {
    if ppre & 4 == 0 {
        1
    } else {
        2 << (ppre & 3)
    }
}

// cycles one bridge transfer takes on an APB with divider `d` (see the module notes)
pub fn bridge_cycles(d: u64) -> u64 {
    1 + 2 * d
}

#[cfg(test)]
mod tests {
    use super::*;

    const WS2: FlashConfig = FlashConfig::from_acr(0x12);

    #[test]
    fn sixteen_bit_code_keeps_up_with_the_prefetch_buffer() {
        // eight 1-cycle 16-bit instructions: 4 per line, a line every 3 cycles
        let insns: Vec<_> = (0..8).map(|i| (0x0800_0000 + 2 * i, 2, 1, 0)).collect();
        assert_eq!(fetch_stalls(&WS2, &insns), vec![0; 8]);
    }

    #[test]
    fn thirty_two_bit_code_is_fetch_bound_at_two_wait_states() {
        // 1-cycle 32-bit instructions: 2 per line, a line every 3 cycles
        let insns: Vec<_> = (0..6).map(|i| (0x0800_0000 + 4 * i, 4, 1, 0)).collect();
        let stalls = fetch_stalls(&WS2, &insns);
        let total: u64 = stalls.iter().sum::<u64>() + 6;
        assert_eq!(total, 2 * 3 + 2, "{stalls:?}"); // lines at 0, 3, 6; last insn ends at 8
        // zero wait states: a line per cycle, no stall
        assert_eq!(fetch_stalls(&FlashConfig::RESET, &insns), vec![0; 6]);
    }

    #[test]
    fn prefetch_off_fetches_on_demand() {
        // 16-bit code that keeps up with the prefetch buffer stalls without it
        let insns: Vec<_> = (0..8).map(|i| (0x0800_0000 + 2 * i, 2, 1, 0)).collect();
        let off = FlashConfig::from_acr(0x02);
        assert_eq!(fetch_stalls(&off, &insns).iter().sum::<u64>(), 2, "line 1 asked for at cycle 3");
    }

    #[test]
    fn sram_code_shares_the_system_bus_with_data() {
        // 16-bit ALU code: a word (two instructions) per bus cycle keeps up
        let alu: Vec<_> = (0..8).map(|i| (0x2000_0000 + 2 * i, 2, 1, 0)).collect();
        assert_eq!(sram_fetch_stalls(&alu), vec![0; 8]);
        // 32-bit ALU code: one word per instruction, one bus cycle each: keeps up
        let wide: Vec<_> = (0..6).map(|i| (0x2000_0000 + 4 * i, 4, 1, 0)).collect();
        assert_eq!(sram_fetch_stalls(&wide), vec![0; 6]);
        // 32-bit loads (2 cycles, the second moving data) back to back: the fetch gets every
        // other cycle, enough for one word per instruction
        let loads: Vec<_> = (0..6).map(|i| (0x2000_0000 + 4 * i, 4, 2, 1)).collect();
        assert_eq!(sram_fetch_stalls(&loads), vec![0; 6]);
        // 32-bit pipelined stores (1 cycle, moving data): the bus never fetches, a stall each
        let stores: Vec<_> = (0..4).map(|i| (0x2000_0000 + 4 * i, 4, 1, 1)).collect();
        let s = sram_fetch_stalls(&stores);
        assert_eq!(s[0], 0);
        assert!(s[1..].iter().all(|&x| x == 1), "{s:?}");
        // a push of five registers holds the bus five cycles; the fetch unit was already three
        // words ahead, so the 16-bit code after it runs on
        let mut push = vec![(0x2000_0000, 2, 6, 5)];
        push.extend((1..7).map(|i| (0x2000_0000 + 2 * i, 2, 1, 0)));
        assert_eq!(sram_fetch_stalls(&push).iter().sum::<u64>(), 0);
        // the same in flash: no bus shared (instructions on I-Code)
        let flash: Vec<_> = stores.iter().map(|&(a, s, c, d)| (a - 0x2000_0000 + 0x0800_0000, s, c, d)).collect();
        assert_eq!(fetch_stalls(&FlashConfig::RESET, &flash), vec![0; 4]);
    }

    #[test]
    fn dividers_and_buses() {
        assert_eq!((apb_divider(0), apb_divider(4), apb_divider(5), apb_divider(7)), (1, 2, 4, 16));
        assert_eq!(bus_of(0x4000_0010), Bus::Apb1);
        assert_eq!(bus_of(0x4001_0C10), Bus::Apb2);
        assert_eq!(bus_of(0x4002_1000), Bus::Other);
        assert_eq!(bridge_cycles(1), 3);
    }
}
