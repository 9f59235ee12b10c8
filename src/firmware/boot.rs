//! The first instructions after any reset (a watchdog one included): cortex-m-rt's
//! `__pre_init`, which runs before RAM is initialised, so it is assembly (Rust code may not
//! run before .bss/.data exist). It drives the step and direction pins low and the drivers off
//! (EN high, active low) as outputs on the reset clock; `init` and the first poll then set the
//! enable level `$4` asks for.

use ddastep::board::ENABLE_PIN;

/// GPIOB BSRR word: every pin low except EN, which goes high.
const SAFE_BSRR: u32 = (0xFFFF & !(1 << ENABLE_PIN)) << 16 | 1 << ENABLE_PIN;

// RCC_APB2ENR.IOPBEN (GPIOB clock), then GPIOB BSRR (levels first), CRL and CRH: PB0,1,3..7
// dir outputs (PB2 = BOOT1 stays an input), PB8 EN, PB9..15 step outputs (push-pull 50 MHz).
core::arch::global_asm!(
    ".section .text.__pre_init, \"ax\"",
    ".global __pre_init",
    ".type __pre_init, %function",
    ".thumb_func",
    "__pre_init:",
    "ldr r0, =0x40021018",
    "ldr r1, [r0]",
    "orr r1, r1, #8",
    "str r1, [r0]",
    "ldr r0, =0x40010C00",
    "ldr r1, ={bsrr}",
    "str r1, [r0, #0x10]",
    "ldr r1, =0x33333433",
    "str r1, [r0]",
    "ldr r1, =0x33333333",
    "str r1, [r0, #4]",
    "bx lr",
    ".ltorg",
    bsrr = const SAFE_BSRR,
);
