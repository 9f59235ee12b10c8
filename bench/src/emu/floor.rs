//! The floor of a one-axis step handler in this model: a hand-scheduled Thumb handler that does
//! only what interrupt mode's plain step must (the checks of `Stepper::tick_quick`, the step's
//! own state, the rising store first, the falling edge at the compare event, the DWT
//! self-timing that `$I` reports), run on the bench with TIM2 at a fixed rate. No compiled
//! handler of the same work beats it; each part's share shows what a faster mode would have
//! to give up. For `cargo sim -- --floor` and bench/RESULTS.md ("The step handler's floor").
//!
//! The parts that can be left out: the self-timing (`rec`), and the compare check (`fall`,
//! whose falling edge DMA could store instead: the event's interrupt is then off).

use anyhow::Result;

use super::{asm, Board, HZ};

/// The handler. `st` is the step half's state (as `Stepper`), `slot` the running move's (as
/// `Prepared`), `tm` the self-timing's counters (as `StepTime`).
const HANDLER: &str = r#"
.thumb_func
tim2:
  push {r4, r5, r6, lr}
  ldr r6, =0xE0001004        @ DWT CYCCNT
  ldr r5, [r6]               @ the entry's cycle
  ldr r4, =0x40000000        @ TIM2
  ldr r3, =st
  ldr r0, [r4, #0x10]        @ SR: which event
  lsls r0, r0, #31
  beq fall
  ldr r0, [r3, #0]           @ the precomputed word
  ldr r1, =0x40010C10        @ GPIOB BSRR
  str r0, [r1]               @ the rising edge, first
  mvn r0, #1
  str r0, [r4, #0x10]        @ clear UIF
  ldr r0, [r3, #12]          @ the shared control word
  ldr r0, [r0]
  ldr r1, [r3, #8]           @ as last seen
  cmp r0, r1
  bne slow
  ldr r12, [r3, #16]         @ the running move's slot
  ldrd r0, r1, [r12]         @ its period (1/16 tick) and trigger
  cbz r0, slow               @ held to rest
  ldr r2, [r3, #20]          @ steps left
  subs r2, #1
  cmp r2, r1
  bls slow                   @ the trigger, or the last step
  ldr r1, [r3, #24]          @ the period's fraction
  add r1, r0
  ldr r0, [r3, #28]          @ the ramp millisecond's ticks left
  subs r0, r0, r1, lsr #4
  ble slow                   @ a ramp millisecond ends
  ldr lr, [r3, #32]          @ the longest period one event holds
  cmp lr, r1, lsr #4
  blo slow
  str r2, [r3, #20]
  str r0, [r3, #28]
  and r0, r1, #15
  str r0, [r3, #24]
  ldrd r0, lr, [r12, #8]     @ the move's steps and the master's bit
  str lr, [r3, #0]           @ the next word
  subs r0, r0, r2
  ldr lr, [r3, #36]
  str r0, [lr]               @ steps done, for reports
  lsrs r1, r1, #4
  subs r1, #1
  str r1, [r4, #0x2C]        @ ARR
fall:
  ldr r0, [r4, #0x10]        @ the compare event came?
  lsls r0, r0, #30
  bpl rec
  ldr r0, [r3, #4]           @ the falling word
  ldr r1, =0x40010C10
  str r0, [r1]
  mvn r0, #2
  str r0, [r4, #0x10]        @ clear CC1IF
rec:
  ldr r0, [r6]
  subs r0, r0, r5            @ this entry's cycles
  ldr r3, =tm
  ldm r3, {r1, r2}
  adds r1, #1
  add r2, r0
  stm r3, {r1, r2}           @ entries, busy cycles
  ldr r1, [r3, #8]
  cmp r0, r1
  it hi
  strhi r0, [r3, #8]         @ max
  ldr r1, [r3, #12]
  cmp r0, r1
  it lo
  strlo r0, [r3, #12]        @ min
  pop {r4, r5, r6, pc}
slow:
  b fall                     @ (a whole tick: never taken here)
.ltorg
"#;

/// Reset: the firmware's flash timing, the cycle counter, TIM2 at `ARR` with a 0.5 µs
/// compare (`DIER` its interrupts), then sleep; the state of a long cruise at `PERIOD16`.
const SETUP: &str = r#"
.thumb_func
reset:
  ldr r0, =0x40022000        @ FLASH_ACR: 2 wait states, prefetch
  movs r1, #0x32
  str r1, [r0]
  ldr r0, =0xE000EDFC        @ DEMCR.TRCENA
  ldr r1, =(1 << 24)
  str r1, [r0]
  ldr r0, =0xE0001000        @ DWT_CTRL.CYCCNTENA
  movs r1, #1
  str r1, [r0]
  ldr r0, =0xE000E100        @ NVIC ISER0: TIM2
  ldr r1, =(1 << 28)
  str r1, [r0]
  ldr r0, =0x40000000        @ TIM2
  ldr r1, =ARR
  str r1, [r0, #0x2C]
  movs r1, #36               @ CCR1: a 0.5 us pulse
  str r1, [r0, #0x34]
  movs r1, #DIER
  str r1, [r0, #0x0C]
  movs r1, #0x81             @ CR1: ARPE, CEN
  str r1, [r0, #0x00]
idle:
  wfi
  b idle
.ltorg
.data
st:
  .word 0x200                @ the word: X's step pin, PB9
  .word 0x2000000            @ the falling word
  .word 0                    @ the control word as last seen
  .word ctl
  .word slot
  .word 0x7FFFFFFF           @ steps left
  .word 0                    @ the fraction
  .word 0x7FFFFFFF           @ the millisecond's ticks left
  .word 65536                @ the longest period
  .word done
ctl: .word 0
slot:
  .word PERIOD16             @ the period, 1/16 tick
  .word 0                    @ the trigger (fired)
  .word 0x7FFFFFFF           @ the move's steps
  .word 0x200                @ the master's bit
done: .word 0
tm: .word 0, 0, 0, 0xFFFFFFFF
"#;

/// Which parts of the handler run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Parts {
    /// The self-timing (`$I`'s step isr line).
    pub timing: bool,
    /// The compare check and falling store (else the compare interrupt is off: DMA would
    /// store the falling word).
    pub fall: bool,
}

/// The variants measured: everything interrupt mode does, then without each optional part.
pub const VARIANTS: [(&str, Parts); 4] = [
    ("interrupt mode's plain step (compare check, self-timing)", Parts { timing: true, fall: true }),
    ("without the self-timing", Parts { timing: false, fall: true }),
    ("without the compare check (DMA stores the falling edge)", Parts { timing: true, fall: false }),
    ("without either", Parts { timing: false, fall: false }),
];

/// The floor program for `parts`, the handler in SRAM or flash, TIM2 at `hz`.
pub fn program(parts: Parts, sram: bool, hz: u32) -> Result<Vec<u8>> {
    let arr = HZ as u32 / hz;
    let mut handler = HANDLER.to_string();
    let cut = |h: &mut String, from: &str, to: &str| {
        if let (Some(a), Some(b)) = (h.find(from), h.find(to)) {
            h.replace_range(a + from.len()..b, "");
        }
    };
    if !parts.timing {
        cut(&mut handler, "rec:\n", "  pop {r4, r5, r6, pc}");
    }
    if !parts.fall {
        cut(&mut handler, "fall:\n", "rec:\n");
    }
    let setup = SETUP
        .replace("=ARR", &format!("={}", arr - 1))
        .replace("PERIOD16", &(arr * 16).to_string())
        .replace("#DIER", if parts.fall { "#3" } else { "#1" });
    let body = format!("{setup}\n{}\n{handler}", if sram { ".section .data" } else { ".text" });
    asm::build("floor", &[(1, "reset"), (16 + 28, "tim2")], &body)
}

/// One variant's measure: mean modeled cycles per step (entry and return included) over
/// 10 ms at 250 kHz.
pub fn cycles(parts: Parts, sram: bool) -> Result<f64> {
    let mut b = Board::from_elf_bytes(&program(parts, sram, 250_000)?)?;
    b.run_for(HZ / 100)?;
    Ok(b.report().step_isr.mean_cycles)
}

/// Every variant, from SRAM (as the firmware's step path) and from flash: (name, SRAM cycles,
/// flash cycles).
pub fn measure() -> Result<Vec<(&'static str, f64, f64)>> {
    VARIANTS.iter().map(|&(name, parts)| Ok((name, cycles(parts, true)?, cycles(parts, false)?))).collect()
}

/// The table (Markdown): cycles and the rate the handler alone allows at 95 % CPU.
pub fn markdown(rows: &[(&str, f64, f64)]) -> String {
    let mut s = String::from("| one-axis plain step, hand-scheduled | cycles from SRAM | from flash | ≤ 95 % CPU at (SRAM) |\n|---|---:|---:|---:|\n");
    for (name, sram, flash) in rows {
        s += &format!("| {name} | {sram:.0} | {flash:.0} | {:.0} kHz |\n", HZ as f64 * 0.95 / sram / 1e3);
    }
    s
}
