//! USART1 RX -> TX echo round trip through the RXNE interrupt, with byte times at 115200
//! baud, and priority preemption / BASEPRI masking with software-pended IRQs.

use ddastep_bench::emu::{asm, Board, RegisterARM, HZ};

const ECHO: &str = r#"
.thumb_func
reset:
  ldr r0, =0x40013800      @ USART1
  ldr r1, =625             @ BRR = 72 MHz / 115200
  str r1, [r0, #0x08]
  ldr r1, =0x202C          @ UE | RXNEIE | TE | RE
  str r1, [r0, #0x0C]
  ldr r0, =0xE000E104      @ ISER1: IRQ 37
  movs r1, #(1 << 5)
  str r1, [r0]
idle:
  wfi
  b idle
.thumb_func
usart1:
  ldr r0, =0x40013800
  ldr r1, [r0, #0x04]      @ DR (clears RXNE)
  adds r1, #1              @ echo the next character
  str r1, [r0, #0x04]
  bx lr
"#;

#[test]
fn rx_to_tx_echo_takes_byte_times() {
    let elf = asm::build("echo", &[(1, "reset"), (16 + 37, "usart1")], ECHO).unwrap();
    let mut b = Board::from_elf_bytes(&elf).unwrap();
    b.run_for(1000).unwrap();
    let t0 = b.cycles();
    b.serial_send(b"HAL");
    b.run_for(HZ / 100).unwrap();
    assert_eq!(b.serial_output(), "IBM");
    let (_, times) = b.serial_bytes();
    // First byte: 10 bits in (6250 cycles), ISR, 10 bits out.
    let first = times[0] - t0;
    assert!(first > 12_500 && first < 12_600, "{first}");
    assert_eq!(times[1] - times[0], 6250);
}

const PREEMPT: &str = r#"
.thumb_func
reset:
  ldr r0, =0xE000E100
  ldr r1, =0x3               @ enable IRQ 0 and 1
  str r1, [r0]
  ldr r0, =0xE000E400
  ldr r1, =0x00004080        @ IRQ0 prio 0x80, IRQ1 prio 0x40
  str r1, [r0]
  movs r4, #0
  movs r5, #0
  movs r1, #0x40
  msr basepri, r1            @ mask priority >= 0x40
  ldr r0, =0xE000E200
  movs r1, #1
  str r1, [r0]               @ pend IRQ 0 (masked by BASEPRI)
  nop
  nop
  mov r6, r4                 @ r6 = r4 while masked (0)
  movs r1, #0
  msr basepri, r1            @ unmask: IRQ 0 runs now
  mov r7, r4                 @ r7 = r4 after
idle:
  wfi
  b idle
.thumb_func
irq0:
  ldr r0, =0xE000E200
  movs r1, #2
  str r1, [r0]               @ pend IRQ 1: higher priority, preempts now
  nop
  nop
  lsls r4, r4, #4
  adds r4, #1                @ r4 = (r4 << 4) + 1
  bx lr
.thumb_func
irq1:
  lsls r4, r4, #4
  adds r4, #2
  bx lr
"#;

#[test]
fn basepri_masks_then_higher_priority_preempts() {
    let elf = asm::build("preempt", &[(1, "reset"), (16, "irq0"), (17, "irq1")], PREEMPT).unwrap();
    let mut b = Board::from_elf_bytes(&elf).unwrap();
    b.run_for(2000).unwrap();
    assert_eq!(b.reg(RegisterARM::R6), 0, "IRQ 0 must wait while BASEPRI masks it");
    // IRQ 1 ran inside IRQ 0 (preemption), then IRQ 0 finished: r4 = ((0<<4)+2)<<4 + 1.
    assert_eq!(b.reg(RegisterARM::R7), 0x21);
    assert!(b.is_sleeping());
    assert_eq!(b.reg(RegisterARM::SP), 0x2000_5000, "stack balanced after nested exceptions");
}
