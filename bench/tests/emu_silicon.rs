//! The cycle model against published measurements on a genuine STM32F103 (bench/README.md,
//! "Model"): each program times itself with the DWT cycle counter, as the measurements did,
//! and the bench's figure must be within ±5 % of silicon's.
//!
//! - blaatschaap.be, "Wait a microsecond": `subs r0,#4; bhi` running from SRAM takes 4 cycles
//!   per iteration.
//! - blog.soch.cc, "Fastest GPIO read speed STM32F103": 128 reads of GPIOA->IDR into an SRAM
//!   buffer from flash at 72 MHz (2 wait states, prefetch on), loop at an 8-byte aligned
//!   address, take 1540 cycles between the two CYCCNT reads (12.03 per iteration).

use ddastep_bench::emu::{asm, Board};

/// Where the programs leave their results.
const RESULT: u32 = 0x2000_1000;
const TOLERANCE: f64 = 0.05;

// common start: clocks as the firmware sets them (FLASH_ACR, APB1 = HCLK/2), DWT on
const PRELUDE: &str = r#"
.thumb_func
reset:
  ldr r0, =0x40022000      @ FLASH_ACR
  ldr r1, =ACR
  str r1, [r0]
  ldr r0, =0x40021004      @ RCC_CFGR: PPRE1 = /2, PPRE2 = /1
  ldr r1, =0x00000400
  str r1, [r0]
  ldr r0, =0xE000EDFC      @ DEMCR.TRCENA
  ldr r1, =0x01000000
  str r1, [r0]
  ldr r5, =0xE0001000      @ DWT: CTRL.CYCCNTENA
  movs r1, #1
  str r1, [r5]
"#;

// run `program` until it has written its results, then read `n` result words
fn run(name: &str, acr: u32, program: &str, n: usize) -> Vec<u32> {
    let src = format!(".equ ACR, {acr:#x}\n{PRELUDE}{program}");
    let elf = asm::build(name, &[(1, "reset")], &src).expect("assemble");
    let mut b = Board::from_elf_bytes(&elf).expect("load");
    b.run_for(200_000).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(b.read_u32(RESULT + 4 * n as u32), 0xD0E, "{name}: program did not finish");
    (0..n).map(|i| b.read_u32(RESULT + 4 * i as u32)).collect()
}

fn within(modeled: f64, silicon: f64) -> bool {
    (modeled - silicon).abs() <= TOLERANCE * silicon
}

// `subs; bhi` from SRAM, timed for 100 and 200 iterations
const SRAM_LOOP: &str = r#"
  ldr r7, =0x20001000
  ldr r6, =delay_ram + 1   @ (no Thumb bit from the linker for a symbol in .data)
  ldr r0, =400
  ldr r2, [r5, #4]
  blx r6
  ldr r3, [r5, #4]
  subs r3, r3, r2
  str r3, [r7]
  ldr r0, =800
  ldr r2, [r5, #4]
  blx r6
  ldr r3, [r5, #4]
  subs r3, r3, r2
  str r3, [r7, #4]
  ldr r3, =0xD0E
  str r3, [r7, #8]
done:
  b done

.data
.balign 4
.thumb_func
delay_ram:
  subs r0, #4
  bhi delay_ram
  bx lr
"#;

#[test]
fn sram_subs_bhi_loop_takes_four_cycles_per_iteration() {
    let r = run("sram_loop", 0x12, SRAM_LOOP, 2);
    let per_iteration = (r[1] - r[0]) as f64 / 100.0;
    println!("subs/bhi from SRAM: {per_iteration} modeled cycles per iteration (silicon 4)");
    assert!(within(per_iteration, 4.0), "{per_iteration} (totals {r:?})");
}

// blog.soch.cc's loop as gcc -Os compiled it, between the same two CYCCNT reads
const GPIO_READ_LOOP: &str = r#"
  ldr r3, =0x20000100      @ dest[128]
  movs r4, #0
  mov r1, r4
  ldr r2, [r5, #4]         @ t0
  add.w r4, r4, #1073741824
  add.w r4, r4, #67584     @ GPIOA
  .balign 8
loop:
  ldr r0, [r4, #8]         @ GPIOA->IDR (APB2)
  str.w r0, [r3, r1, lsl #2]
  adds r1, #1
  cmp r1, #128
  bne.n loop
  ldr r3, [r5, #4]         @ t1
  subs r3, r3, r2
  ldr r7, =0x20001000
  str r3, [r7]
  ldr r3, =0xD0E
  str r3, [r7, #4]
done:
  b done
"#;

#[test]
fn gpio_read_loop_from_flash_matches_silicon() {
    let r = run("gpio_read", 0x12, GPIO_READ_LOOP, 1);
    println!("128 GPIOA->IDR reads from flash: {} modeled cycles (silicon 1540)", r[0]);
    assert!(within(r[0] as f64, 1540.0), "{}", r[0]);
}

#[test]
fn wait_states_follow_flash_acr() {
    // The same loop at LATENCY 0 (as below 24 MHz) and with the prefetch buffer off.
    let ws0 = run("gpio_read_ws0", 0x10, GPIO_READ_LOOP, 1)[0];
    let ws2 = run("gpio_read_ws2", 0x12, GPIO_READ_LOOP, 1)[0];
    let ws2_no_prefetch = run("gpio_read_noprefetch", 0x02, GPIO_READ_LOOP, 1)[0];
    println!("LATENCY 0: {ws0}, LATENCY 2: {ws2}, LATENCY 2 without prefetch: {ws2_no_prefetch}");
    // Each taken branch refills one line: 2 more cycles per iteration at 2 wait states.
    let per_iteration = (ws2 - ws0) as f64 / 128.0;
    assert!((1.9..=2.1).contains(&per_iteration), "{ws0} {ws2}");
    assert!(ws2_no_prefetch > ws2, "{ws2_no_prefetch} {ws2}");
}
