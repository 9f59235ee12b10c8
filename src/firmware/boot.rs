//! The first instructions after any reset (a watchdog one included): cortex-m-rt's
//! `__pre_init`, which runs before RAM is initialised, so it is assembly (Rust code may not
//! run before .bss/.data exist). It drives the step and direction pins low and the drivers off
//! (EN high, active low) as outputs on the reset clock; `init` and the first poll then set the
//! enable level `$4` asks for.

use ddastep::board::{DIR_PINS, ENABLE_PIN, STEP_PINS};

use super::gpio::{config_word, PinMode};

/// GPIOB BSRR word: every pin low except EN, which goes high.
const SAFE_BSRR: u32 = (0xFFFF & !(1 << ENABLE_PIN)) << 16 | 1 << ENABLE_PIN;

/// PB2 is BOOT1 (strapped on the board): it stays a floating input.
const BOOT1_PIN: u8 = 2;

/// Axes with a step and a direction pin on GPIOB.
const N: usize = STEP_PINS.len();

/// GPIOB's 16 pins: step, direction and EN push-pull outputs at 50 MHz, BOOT1 an input.
const fn gpiob_pins() -> [(u8, PinMode); 2 * N + 2] {
    let mut pins = [(BOOT1_PIN, PinMode::InputFloating); 2 * N + 2];
    let mut i = 0;
    while i < N {
        pins[i] = (STEP_PINS[i], PinMode::Output50MHz);
        pins[N + i] = (DIR_PINS[i], PinMode::Output50MHz);
        i += 1;
    }
    pins[2 * N] = (ENABLE_PIN, PinMode::Output50MHz);
    pins
}
const GPIOB_CRL: (u32, u32) = config_word(&gpiob_pins(), false);
const GPIOB_CRH: (u32, u32) = config_word(&gpiob_pins(), true);
// Both words are written whole: every pin has a mode.
const _: () = assert!(GPIOB_CRL.0 == u32::MAX && GPIOB_CRH.0 == u32::MAX);

/// RCC_APB2ENR and its GPIOB clock enable (IOPBEN); GPIOB's registers (RM0008 §7.3.7, §9.2).
const RCC_APB2ENR: u32 = 0x4002_1018;
const APB2ENR_IOPBEN: u32 = 1 << 3;
const GPIOB: u32 = 0x4001_0C00;
const GPIO_CRL: u32 = 0x00;
const GPIO_CRH: u32 = 0x04;
const GPIO_BSRR: u32 = 0x10;

// RCC_APB2ENR.IOPBEN (GPIOB clock), then GPIOB BSRR (levels first), CRL and CRH.
core::arch::global_asm!(
    ".section .text.__pre_init, \"ax\"",
    ".global __pre_init",
    ".type __pre_init, %function",
    ".thumb_func",
    "__pre_init:",
    "ldr r0, ={apb2enr}",
    "ldr r1, [r0]",
    "orr r1, r1, #{iopben}",
    "str r1, [r0]",
    "ldr r0, ={gpiob}",
    "ldr r1, ={bsrr}",
    "str r1, [r0, #{bsrr_at}]",
    "ldr r1, ={crl}",
    "str r1, [r0, #{crl_at}]",
    "ldr r1, ={crh}",
    "str r1, [r0, #{crh_at}]",
    "bx lr",
    ".ltorg",
    apb2enr = const RCC_APB2ENR,
    iopben = const APB2ENR_IOPBEN,
    gpiob = const GPIOB,
    bsrr = const SAFE_BSRR,
    bsrr_at = const GPIO_BSRR,
    crl = const GPIOB_CRL.1,
    crl_at = const GPIO_CRL,
    crh = const GPIOB_CRH.1,
    crh_at = const GPIO_CRH,
);
