//! TIM2 update/compare timing with ARR preload, GPIO BSRR edges, exception entry/exit and
//! WFI fast-forward, on a tiny hand-written program.

use ddastep_bench::emu::{asm, Board, HZ};

// TIM2 at 72 MHz, ARR = 999 (1000-cycle period), CCR1 = 100; update ISR sets PB9 via BSRR,
// CC1 ISR resets it via BRR. Idle loop is WFI.
const PROGRAM: &str = r#"
.thumb_func
reset:
  ldr r0, =0xE000E100      @ NVIC ISER0
  ldr r1, =(1 << 28)
  str r1, [r0]
  ldr r0, =0x40010C04      @ GPIOB CRH: PB9 push-pull output 50 MHz
  ldr r1, =0x44444434
  str r1, [r0]
  ldr r0, =0x40000000      @ TIM2
  movs r1, #0
  str r1, [r0, #0x28]      @ PSC = 0
  ldr r1, =999
  str r1, [r0, #0x2C]      @ ARR = 999
  movs r1, #100
  str r1, [r0, #0x34]      @ CCR1 = 100
  movs r1, #3
  str r1, [r0, #0x0C]      @ DIER = UIE | CC1IE
  movs r1, #0x81
  str r1, [r0, #0x00]      @ CR1 = ARPE | CEN
idle:
  wfi
  b idle

.thumb_func
tim2:
  ldr r0, =0x40000000
  ldr r1, [r0, #0x10]      @ SR
  tst r1, #1
  beq cc1
  ldr r2, =0x40010C10      @ GPIOB BSRR
  ldr r3, =(1 << 9)
  str r3, [r2]             @ rising edge
  mvn r1, #1
  str r1, [r0, #0x10]      @ clear UIF
  ldr r1, =1999
  str r1, [r0, #0x2C]      @ ARR preload: applies at the next update
  bx lr
cc1:
  ldr r2, =0x40010C14      @ GPIOB BRR
  ldr r3, =(1 << 9)
  str r3, [r2]             @ falling edge
  mvn r1, #2
  str r1, [r0, #0x10]      @ clear CC1IF
  bx lr
"#;

fn board() -> Board {
    let elf = asm::build("timer", &[(1, "reset"), (16 + 28, "tim2")], PROGRAM).expect("assemble");
    Board::from_elf_bytes(&elf).expect("load")
}

#[test]
fn update_and_compare_edges_are_exact_in_modeled_cycles() {
    let mut b = board();
    b.run_for(10_000).unwrap();
    let edges: Vec<_> = b.edges().iter().filter(|e| e.port == 1 && e.pin == 9).map(|e| (e.cycle, e.level)).collect();
    assert!(edges.len() >= 5, "{edges:?}");
    // Rising edges follow update events; with ARR preload the first period is 1000 cycles,
    // then 2000 (the ISR's ARR write waits for the next update).
    let rises: Vec<u64> = edges.iter().filter(|e| e.1).map(|e| e.0).collect();
    assert_eq!(rises[1] - rises[0], 1000, "{edges:?}");
    assert_eq!(rises[2] - rises[1], 2000, "{edges:?}");
    assert_eq!(rises[3] - rises[2], 2000, "{edges:?}");
    // Falling edges follow the compare at CNT = 100: 100 cycles after the update event,
    // offset the same way as the rising edge (same handler path length up to the store).
    let falls: Vec<u64> = edges.iter().filter(|e| !e.1).map(|e| e.0).collect();
    let fall_after_rise = falls[1] - rises[1];
    assert_eq!(falls[2] - rises[2], fall_after_rise);
    assert!(fall_after_rise > 80 && fall_after_rise < 120, "{fall_after_rise}");
    let r = b.report();
    assert_eq!(r.overruns, 0);
    assert!(r.step_isr.entries >= 8, "{}", r.step_isr.entries);
    let (lo, hi) = (r.step_isr.bsrr_offset_min_cycles.unwrap(), r.step_isr.bsrr_offset_max_cycles.unwrap());
    assert_eq!(lo, hi, "every update handler reaches its BSRR store after the same modeled delay");
    assert!(lo > 14 && lo < 40, "{lo}");
}

#[test]
fn wfi_fast_forwards_and_load_is_low() {
    let mut b = board();
    let t = std::time::Instant::now();
    b.run_for(HZ / 10).unwrap(); // 100 ms simulated
    assert!(b.is_sleeping());
    // 36 kHz of interrupts (update + compare), each well under 100 modeled cycles.
    let r = b.report();
    assert!(r.cpu_load_peak > 0.02 && r.cpu_load_peak < 0.2, "{}", r.cpu_load_peak);
    assert_eq!(r.axes.0[0].1.rising_edges, b.edges().iter().filter(|e| e.pin == 9 && e.level).count() as u64);
    eprintln!("100 ms simulated in {:?}", t.elapsed());
}
