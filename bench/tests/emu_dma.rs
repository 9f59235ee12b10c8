//! DMA1 driven by TIM2 requests, on a tiny hand-written program shaped like the firmware's DMA
//! step mode: update → channel 2 writes the rising BSRR word, CC1 → channel 5 the falling
//! word, CC3 (CCR3 = 1) → channel 1 the next period into ARR (preloaded), with its half- and
//! full-transfer interrupts counting in RAM. Checks landing cycles (request + latency, from
//! `emu::dma`'s constants), ARR taking effect one period later, HT/TC reaching the NVIC,
//! overruns when they are not served, and the bus cycles charged to a running CPU.

use ddastep_bench::emu::dma::{ADDRESS, AHB_ACCESS, ARBITRATION};
use ddastep_bench::emu::memory::bridge_cycles;
use ddastep_bench::emu::{asm, Board, PinEdge};

/// HT and TC counts of the DMA1_Channel1 handler.
const COUNTS: u32 = 0x2000_1000;
/// Periods the CC3 transfers program (ARR + 1), after a first period of 500.
const PERIODS: [u64; 4] = [1000, 2000, 3000, 4000];
const CCR1: u64 = 100;

// `iser`: NVIC ISER0 (bit 11 = DMA1_Channel1); `idle`: the main loop's instruction
fn program(iser: u32, idle: &str) -> String {
    r#"
.thumb_func
reset:
  ldr r0, =COUNTS
  movs r1, #0
  str r1, [r0]
  str r1, [r0, #4]
  ldr r0, =0x40021004      @ RCC_CFGR: APB1 = HCLK / 2, as the firmware runs it
  ldr r1, =0x400
  str r1, [r0]
  ldr r0, =0xE000E100      @ NVIC ISER0
  ldr r1, =ISER
  str r1, [r0]
  ldr r0, =0x40010C04      @ GPIOB CRH: PB8, PB9 push-pull outputs
  ldr r1, =0x44444433
  str r1, [r0]
  ldr r0, =0x40020000      @ DMA1
  ldr r1, =0x40010C10
  str r1, [r0, #0x24]      @ CPAR2 = GPIOB BSRR
  ldr r1, =rise
  str r1, [r0, #0x28]      @ CMAR2
  movs r1, #4
  str r1, [r0, #0x20]      @ CNDTR2
  ldr r1, =0x0AB1          @ CCR2: MSIZE 32, PSIZE 32, MINC, CIRC, DIR, EN
  str r1, [r0, #0x1C]
  ldr r1, =0x4000002C
  str r1, [r0, #0x10]      @ CPAR1 = TIM2 ARR
  ldr r1, =arrs
  str r1, [r0, #0x14]      @ CMAR1
  movs r1, #4
  str r1, [r0, #0x0C]      @ CNDTR1
  ldr r1, =0x06B7          @ CCR1: MSIZE 16, PSIZE 32, MINC, CIRC, DIR, HTIE, TCIE, EN
  str r1, [r0, #0x08]
  ldr r1, =0x40010C10
  str r1, [r0, #0x60]      @ CPAR5 = GPIOB BSRR
  ldr r1, =fall
  str r1, [r0, #0x64]      @ CMAR5
  movs r1, #1
  str r1, [r0, #0x5C]      @ CNDTR5
  ldr r1, =0x0A31          @ CCR5: MSIZE 32, PSIZE 32, CIRC, DIR, EN (no MINC)
  str r1, [r0, #0x58]
  ldr r0, =0x40000000      @ TIM2
  ldr r1, =499
  str r1, [r0, #0x2C]      @ ARR = 499: the first period is 500
  movs r1, #CCR1
  str r1, [r0, #0x34]      @ CCR1
  movs r1, #1
  str r1, [r0, #0x3C]      @ CCR3 = 1
  ldr r1, =0x0B00          @ DIER = UDE | CC1DE | CC3DE, no interrupts
  str r1, [r0, #0x0C]
  movs r1, #0x81
  str r1, [r0, #0x00]      @ CR1 = ARPE | CEN
idle:
  IDLE
  b idle

.thumb_func
dma1_ch1:
  ldr r0, =0x40020000
  ldr r1, [r0]             @ ISR
  ldr r2, =COUNTS
  tst r1, #4               @ HTIF1
  beq 1f
  ldr r3, [r2]
  adds r3, #1
  str r3, [r2]
1:
  tst r1, #2               @ TCIF1
  beq 2f
  ldr r3, [r2, #4]
  adds r3, #1
  str r3, [r2, #4]
2:
  movs r1, #1
  str r1, [r0, #4]         @ IFCR: CGIF1
  bx lr

.data
.align 2
rise: .word 1 << 9, 1 << 8, 1 << 9, 1 << 8
fall: .word (1 << 9 | 1 << 8) << 16
arrs: .hword 999, 1999, 2999, 3999
"#
    .replace("COUNTS", &format!("{COUNTS:#x}"))
    .replace("ISER", &format!("{iser:#x}"))
    .replace("IDLE", idle)
    .replace("#CCR1", &format!("#{CCR1}"))
}

fn board(iser: u32, idle: &str) -> Board {
    let elf = asm::build("dma", &[(1, "reset"), (16 + 11, "dma1_ch1")], &program(iser, idle)).expect("assemble");
    Board::from_elf_bytes(&elf).expect("load")
}

// request → GPIO write (APB2, divider 1) and → TIM2 write (APB1, divider 2)
fn latency(apb_divider: u64) -> u64 {
    ARBITRATION + ADDRESS + AHB_ACCESS + bridge_cycles(apb_divider)
}

fn pins(b: &Board) -> Vec<PinEdge> {
    b.edges().iter().copied().filter(|e| e.port == 1 && (e.pin == 8 || e.pin == 9)).collect()
}

#[test]
fn timer_requests_drive_bsrr_and_arr_with_the_modeled_latency() {
    let mut b = board(1 << 11, "wfi");
    assert_eq!(latency(1), 7);
    // The first update: its rising edge lands one GPIO latency later.
    assert!(b.run_until(10_000, |b| !pins(b).is_empty()).unwrap());
    let (updates, first_update) = b.timer_updates();
    assert_eq!(updates, 1);
    assert_eq!(pins(&b)[0], PinEdge { cycle: first_update + latency(1), port: 1, pin: 9, level: true });
    let start = first_update - 500;

    b.run_until_cycle(start + 24_000).unwrap();
    let edges = pins(&b);
    let rises: Vec<_> = edges.iter().filter(|e| e.level).collect();
    let falls: Vec<_> = edges.iter().filter(|e| !e.level).collect();
    // Period p (p >= 1) runs the ARR that CC3 wrote during period p - 1: one period late.
    let mut update = first_update;
    for (k, rise) in rises.iter().enumerate() {
        assert_eq!(rise.cycle, update + latency(1), "rise {k}: {edges:?}");
        assert_eq!(rise.pin, if k % 2 == 0 { 9 } else { 8 }, "rise {k}: the update words in turn");
        let fall = falls[k];
        assert_eq!((fall.cycle, fall.pin), (update + CCR1 + latency(1), rise.pin), "fall {k}: CC1 + latency");
        update += PERIODS[k % 4];
    }
    // Every update (PERIODS wrapped around) gave a pulse; period 0's CC1 found the pins low.
    let (updates, _) = b.timer_updates();
    assert_eq!((rises.len() as u64, falls.len() as u64), (updates, updates), "{edges:?}");
    assert!(updates >= 9, "{updates}");

    // Every request became one transfer: ch2 per update, ch1 per CC3, ch5 per CC1.
    let n = b.dma_transfers();
    assert_eq!((n[1], n[0], n[4]), (updates, updates + 1, updates + 1), "{n:?}");
    assert_eq!(n.iter().sum::<u64>(), 3 * updates + 2);
    // HT after the 2nd of every 4 ARR items, TC after the 4th; served, so no overrun.
    let (ht, tc) = (b.read_u32(COUNTS), b.read_u32(COUNTS + 4));
    assert_eq!((ht as u64, tc as u64), ((n[0] + 2) / 4, n[0] / 4), "ch1 transfers {}", n[0]);
    assert!(tc >= 1);
    assert_eq!((b.overruns(), b.dma_overruns()), (0, 0));
    assert_eq!(b.dma_channel(1).cndtr, 4 - (n[0] % 4) as u32);
    // Bus matrix: SRAM read + bridge per transfer, TIM2 on the slower APB1.
    let bus = (n[1] + n[4]) * (AHB_ACCESS + bridge_cycles(1)) + n[0] * (AHB_ACCESS + bridge_cycles(2));
    assert_eq!(b.dma_bus_cycles(), bus);
    assert!(b.dma_stolen_cycles() <= 2 * (AHB_ACCESS + bridge_cycles(2)), "the CPU sleeps: {}", b.dma_stolen_cycles());
    let r = b.report();
    assert_eq!((r.dma.transfers, r.dma.bus_cycles, r.dma.overruns), (n, bus, 0));
    assert!(r.to_string().contains("DMA1: transfers per channel 1..7"), "{r}");
}

#[test]
fn unserved_half_and_complete_flags_count_as_overruns() {
    // Same program, DMA1_Channel1 not enabled in the NVIC: nobody clears HTIF/TCIF.
    let mut b = board(0, "wfi");
    b.run_for(40_000).unwrap();
    let n = b.dma_transfers()[0];
    let (ht, tc) = ((n + 2) / 4, n / 4);
    assert!(ht >= 3 && tc >= 2, "{n}");
    assert_eq!(b.dma_overruns(), (ht - 1) + (tc - 1), "{n} transfers on channel 1");
    assert_eq!(b.overruns(), b.dma_overruns());
    assert_eq!(b.read_u32(COUNTS), 0, "handler never ran");
}

#[test]
fn a_running_cpu_loses_the_bus_cycles() {
    let mut sleeper = board(1 << 11, "wfi");
    let mut busy = board(1 << 11, "nop");
    sleeper.run_for(20_000).unwrap();
    busy.run_for(20_000).unwrap();
    assert_eq!(busy.dma_stolen_cycles(), busy.dma_bus_cycles(), "every transfer stole from the running CPU");
    assert!(busy.dma_bus_cycles() > 0);
    // The same transfers happen either way, at the same cycles.
    assert_eq!(busy.dma_transfers(), sleeper.dma_transfers());
    assert!(pins(&busy).len() >= 10);
    assert_eq!(pins(&busy), pins(&sleeper), "the edges follow the timer, not the CPU");
}

// Peripheral to memory (DIR = 0), not circular: channel 2 copies TIM2 CNT into a half-word
// array on each of the first three updates.
const CNT_COPY: &str = r#"
.thumb_func
reset:
  ldr r0, =0x40021004      @ RCC_CFGR: APB1 = HCLK / 2
  ldr r1, =0x400
  str r1, [r0]
  ldr r0, =0x40020000      @ DMA1 channel 2
  ldr r1, =0x40000024
  str r1, [r0, #0x24]      @ CPAR2 = TIM2 CNT
  ldr r1, =0x20000100
  str r1, [r0, #0x28]      @ CMAR2
  movs r1, #3
  str r1, [r0, #0x20]      @ CNDTR2 = 3
  ldr r1, =0x0681          @ CCR2: MSIZE 16, PSIZE 32, MINC, EN (DIR = 0, not circular)
  str r1, [r0, #0x1C]
  ldr r0, =0x40000000      @ TIM2
  ldr r1, =999
  str r1, [r0, #0x2C]
  ldr r1, =0x100           @ DIER = UDE
  str r1, [r0, #0x0C]
  movs r1, #1
  str r1, [r0]             @ CEN
idle:
  wfi
  b idle
"#;

#[test]
fn peripheral_to_memory_reads_at_the_landing_cycle_and_stops_when_done() {
    let elf = asm::build("dma_cnt", &[(1, "reset")], CNT_COPY).expect("assemble");
    let mut b = Board::from_elf_bytes(&elf).expect("load");
    b.run_for(6_000).unwrap();
    assert!(b.timer_updates().0 >= 5);
    assert_eq!(b.dma_transfers()[1], 3, "not circular: three items, then the channel stops");
    assert_eq!(b.dma_channel(2).cndtr, 0);
    // CNT read through the APB1 bridge: the update at r, then 1 + 1 + 5 cycles to the read
    // (the SRAM write follows it); CNT restarted at 0 at r. Truncated to 16 bits.
    let cnt = ARBITRATION + ADDRESS + bridge_cycles(2);
    let mem = b.read_mem(0x2000_0100, 8);
    assert_eq!(mem, [cnt as u8, 0, cnt as u8, 0, cnt as u8, 0, 0xA5, 0xA5], "untouched RAM keeps its paint");
}
