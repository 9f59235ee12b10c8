//! Interrupts near IT blocks: the handler must start with no IT state (its first instructions
//! are unconditional) and the return must restore the rest of an interrupted block; a store
//! that pends an exception preempts right after itself.
//!
//! Observed with unicorn 2.1.5: an exact-stop split or a pending store never stops *inside*
//! an IT block (unicorn runs on to the end of its translated block, so such an exception is
//! taken up to a few instructions late); the bench still clears the IT bits on entry and
//! restores them from the frame on return, and these tests pin both behaviours.

use ddastep_bench::emu::{asm, Board, RegisterARM};

const PROGRAM: &str = r#"
.thumb_func
reset:
  ldr r0, =0xE000E100      @ NVIC ISER0: TIM2
  ldr r1, =(1 << 28)
  str r1, [r0]
  ldr r0, =0x40000000      @ TIM2
  movs r1, #96
  str r1, [r0, #0x2C]      @ ARR = 96: an update every 97 cycles
  movs r1, #1
  str r1, [r0, #0x0C]      @ DIER = UIE
  str r1, [r0, #0x00]      @ CR1 = CEN
  movs r4, #0              @ passes of the loop
  movs r5, #0              @ "else" slots executed (must stay 0)
  movs r6, #0              @ "then" slots executed (2 per pass)
loop:
  cmp r4, r4               @ Z = 1
  ittet eq
  addeq r4, r4, #1
  addeq r6, r6, #1
  addne r5, r5, #1
  addeq r6, r6, #1
  b loop

.thumb_func
tim2:
  ldr r0, =count
  ldr r1, [r0]
  add r1, r1, #1           @ skipped if the interrupted IT state leaked into the handler
  str r1, [r0]
  ldr r0, =0x40000010      @ TIM2 SR: clear UIF
  movs r1, #0
  str r1, [r0]
  bx lr

.data
count: .word 0
"#;

#[test]
fn it_state_is_cleared_on_entry_and_restored_on_return() {
    let elf = asm::build("it_state", &[(1, "reset"), (16 + 28, "tim2")], PROGRAM).expect("assemble");
    let mut b = Board::from_elf_bytes(&elf).expect("load");
    b.run_for(200_000).unwrap();
    let (passes, elses, thens) = (b.reg(RegisterARM::R4), b.reg(RegisterARM::R5), b.reg(RegisterARM::R6));
    assert!(passes > 1000, "{passes}");
    assert_eq!(elses, 0, "the else slot ran: IT state lost across an exception return");
    assert!(thens.abs_diff(2 * passes) <= 1, "then slots {thens} for {passes} passes");
    let entries = b.report().step_isr.entries;
    let counted = b.read_u32(0x2000_0000);
    assert!(entries > 1000, "{entries}");
    assert!(counted.abs_diff(entries as u32) <= 1, "handler counted {counted} of {entries} entries: IT state leaked into it");
}

// A store to NVIC STIR inside an IT block preempts right after the store, mid-block.
const PEND_IN_IT: &str = r#"
.thumb_func
reset:
  ldr r0, =0xE000E100      @ NVIC ISER0: IRQ 28
  ldr r1, =(1 << 28)
  str r1, [r0]
  ldr r0, =0xE000EF00      @ STIR
  movs r1, #28
  movs r4, #0
  movs r5, #0
  movs r6, #0
loop:
  cmp r4, r4               @ Z = 1
  ittet eq
  streq r1, [r0]           @ pend IRQ 28: taken after this store
  addeq r6, r6, #1
  addne r5, r5, #1
  addeq r4, r4, #1
  b loop

.thumb_func
irq:
  ldr r2, =count
  ldr r3, [r2]
  add r3, r3, #1
  str r3, [r2]
  bx lr

.data
count: .word 0
"#;

#[test]
fn software_pend_inside_an_it_block_resumes_the_block() {
    let elf = asm::build("pend_in_it", &[(1, "reset"), (16 + 28, "irq")], PEND_IN_IT).expect("assemble");
    let mut b = Board::from_elf_bytes(&elf).expect("load");
    b.run_for(100_000).unwrap();
    let (passes, elses, thens) = (b.reg(RegisterARM::R4), b.reg(RegisterARM::R5), b.reg(RegisterARM::R6));
    let counted = b.read_u32(0x2000_0000);
    assert!(passes > 1000, "{passes}");
    assert_eq!(elses, 0, "the else slot ran after the handler returned");
    assert!(thens.abs_diff(passes) <= 1, "then slots {thens} for {passes} passes");
    assert!(counted.abs_diff(passes) <= 1, "handler ran its increment {counted} times for {passes} pends");
}

// The same pend outside an IT block, followed by more straight-line code in the same block.
const PEND_MID_BLOCK: &str = r#"
.thumb_func
reset:
  ldr r0, =0xE000E100      @ NVIC ISER0: IRQ 28
  ldr r1, =(1 << 28)
  str r1, [r0]
  ldr r0, =0xE000EF00      @ STIR
  movs r1, #28
  movs r6, #0
  str r1, [r0]             @ pend IRQ 28: taken after this store
  adds r6, r6, #1
  adds r6, r6, #1
idle:
  b idle

.thumb_func
irq:
  ldr r2, =seen
  str r6, [r2]             @ r6 as the handler found it
  bx lr

.data
seen: .word 0xFFFF
"#;

#[test]
fn software_pend_preempts_right_after_the_store() {
    let elf = asm::build("pend_mid_block", &[(1, "reset"), (16 + 28, "irq")], PEND_MID_BLOCK).expect("assemble");
    let mut b = Board::from_elf_bytes(&elf).expect("load");
    b.run_for(1_000).unwrap();
    assert_eq!(b.reg(RegisterARM::R6), 2);
    assert_eq!(b.read_u32(0x2000_0000), 0, "the handler ran after instructions that follow the pending store");
}
