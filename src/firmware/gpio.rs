//! GPIO: the pin modes (CRL/CRH words built per pin from `ddastep::board`), the atomic BSRR
//! outputs (enable, spindle and coolant, LED) and the inputs (limits, probe, door). GPIOB's
//! step and direction pins are set up by `boot.rs` and written by the step interrupt.

use ddastep::board;
use ddastep::grbl::spindle::SpindleOut;
use stm32f1xx_hal::pac;

/// GPIOB's registers: BSRR stores are atomic, so every context may use them.
#[inline(always)]
pub fn gpiob() -> &'static pac::gpiob::RegisterBlock {
    // SAFETY: only BSRR (write-only, atomic set/reset) is used after init.
    unsafe { &*pac::GPIOB::ptr() }
}

/// The enable pin's level that turns the drivers off (`$4`): what the panic and fault handlers
/// drive. High until `init` reads the settings (the board's enable is active low).
pub static ENABLE_OFF_HIGH: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(true);

/// Drives the shared enable pin.
pub fn set_enable(high: bool) {
    let bit = 1u32 << board::ENABLE_PIN;
    // SAFETY: BSRR takes any word (low half sets, high half resets, atomically); this one drives only EN.
    gpiob().bsrr().write(|w| unsafe { w.bits(if high { bit } else { bit << 16 }) });
}

/// The spindle and coolant pins (one atomic BSRR store).
pub fn set_tool_outputs(o: SpindleOut) {
    let pins = [
        (board::SPINDLE_ENABLE_PIN, o.enable),
        (board::SPINDLE_DIR_PIN, o.ccw),
        (board::COOLANT_FLOOD_PIN, o.flood),
        (board::COOLANT_MIST_PIN, o.mist),
    ];
    let word = pins.iter().fold(0u32, |w, &(p, on)| w | if on { 1 << p } else { 1 << (p + 16) });
    // SAFETY: BSRR stores are atomic; only `idle` drives these GPIOA pins.
    let gpioa = unsafe { &*pac::GPIOA::ptr() };
    // SAFETY: BSRR takes any word; this one drives only the four spindle and coolant pins.
    gpioa.bsrr().write(|w| unsafe { w.bits(word) });
}

/// GPIOA's input register (the limit inputs).
pub fn gpioa_idr() -> u32 {
    // SAFETY: a read of the input data register, no side effects.
    unsafe { &*pac::GPIOA::ptr() }.idr().read().bits()
}

/// GPIOC's input register (the probe and door inputs).
pub fn gpioc_idr() -> u32 {
    // SAFETY: a read of the input data register, no side effects.
    unsafe { &*pac::GPIOC::ptr() }.idr().read().bits()
}

/// The probe input (PC14) is low: in contact, unless `$6` inverts.
pub fn probe_low() -> bool {
    gpioc_idr() & 1 << board::PROBE_PIN == 0
}

/// PC13 LED (active low): on for 100 ms of every second.
pub fn heartbeat(now_ms: u32) {
    let on = now_ms % 1000 < 100;
    let bit = 1u32 << board::LED_PIN;
    // SAFETY: BSRR stores are atomic; only idle drives PC13.
    let gpioc = unsafe { &*pac::GPIOC::ptr() };
    // SAFETY: BSRR takes any word; this one drives only PC13.
    gpioc.bsrr().write(|w| unsafe { w.bits(if on { bit << 16 } else { bit }) });
}

/// A pin's mode in CRL/CRH (RM0008 §9.2.1): its CNF and MODE bits, one nibble per pin.
#[derive(Clone, Copy)]
pub enum PinMode {
    /// Input, floating (CNF 01, MODE 00): the reset state.
    InputFloating = 0b0100,
    /// Input with pull-up or pull-down, as ODR says (CNF 10, MODE 00).
    InputPull = 0b1000,
    /// Push-pull output, 2 MHz (CNF 00, MODE 10).
    Output2MHz = 0b0010,
    /// Push-pull output, 50 MHz (CNF 00, MODE 11).
    Output50MHz = 0b0011,
    /// Alternate function push-pull output, 50 MHz (CNF 10, MODE 11).
    Alternate50MHz = 0b1011,
}

/// The CRL (`high` false: pins 0–7) or CRH (pins 8–15) bits of `pins`: (the mask of their
/// nibbles, their modes).
pub const fn config_word(pins: &[(u8, PinMode)], high: bool) -> (u32, u32) {
    let (mut mask, mut word) = (0, 0);
    let mut i = 0;
    while i < pins.len() {
        let (pin, mode) = pins[i];
        if (pin >= 8) == high {
            let at = (pin % 8) * 4;
            mask |= 0xF << at;
            word |= (mode as u32) << at;
        }
        i += 1;
    }
    (mask, word)
}

/// GPIOA: limits X, Y, Z pulled up; mist, flood, spindle direction outputs (low); encoder A/B
/// (TIM3) pulled up (open-collector encoders; not 5 V tolerant); the spindle PWM (TIM1_CH1);
/// spindle enable (output, low). PA9/PA10 stay as the HAL left them (USART1), PA11..PA14
/// untouched (USB, SWD).
const GPIOA_PINS: [(u8, PinMode); 10] = [
    (board::LIMIT_PINS[0], PinMode::InputPull),
    (board::LIMIT_PINS[1], PinMode::InputPull),
    (board::LIMIT_PINS[2], PinMode::InputPull),
    (board::COOLANT_MIST_PIN, PinMode::Output2MHz),
    (board::COOLANT_FLOOD_PIN, PinMode::Output2MHz),
    (board::SPINDLE_DIR_PIN, PinMode::Output2MHz),
    (board::ENCODER_PINS[0], PinMode::InputPull),
    (board::ENCODER_PINS[1], PinMode::InputPull),
    (board::SPINDLE_PWM_PIN, PinMode::Alternate50MHz),
    (board::SPINDLE_ENABLE_PIN, PinMode::Output2MHz),
];
const GPIOA_CRL: (u32, u32) = config_word(&GPIOA_PINS, false);
const GPIOA_CRH: (u32, u32) = config_word(&GPIOA_PINS, true);
// CRL is written whole: every pin of it has a mode above.
const _: () = assert!(GPIOA_CRL.0 == u32::MAX);

/// GPIOC: the LED (active low, output), the probe and door inputs pulled up.
const GPIOC_PINS: [(u8, PinMode); 3] =
    [(board::LED_PIN, PinMode::Output2MHz), (board::PROBE_PIN, PinMode::InputPull), (board::DOOR_PIN, PinMode::InputPull)];
const GPIOC_CRH: (u32, u32) = config_word(&GPIOC_PINS, true);

/// Limit inputs, spindle and coolant outputs and the LED (GPIOB is set up by `boot.rs`),
/// written as whole CRL/CRH words. The HAL's per-pin calls cost ~1 KiB of flash for the same
/// result.
pub fn setup() {
    // SAFETY: init owns the GPIO ports; the HAL configured only PA9/PA10 (USART1).
    let (a, c) = unsafe { (&*pac::GPIOA::ptr(), &*pac::GPIOC::ptr()) };
    let tool = 1 << board::SPINDLE_ENABLE_PIN | 1 << board::SPINDLE_DIR_PIN | 1 << board::COOLANT_FLOOD_PIN | 1 << board::COOLANT_MIST_PIN;
    // SAFETY: BSRR: pull-ups on the limit and encoder inputs (ODR high) and the tool outputs low, before CRL/CRH make them inputs and outputs.
    a.bsrr().write(|w| unsafe { w.bits(board::LIMIT_INPUTS | board::ENCODER_INPUTS | tool << 16) });
    // SAFETY: CRL: a defined mode nibble for every pin (`GPIOA_PINS`); init owns GPIOA.
    a.crl().write(|w| unsafe { w.bits(GPIOA_CRL.1) });
    // SAFETY: CRH: defined modes for the `GPIOA_PINS` nibbles only; the others keep theirs.
    a.crh().modify(|r, w| unsafe { w.bits((r.bits() & !GPIOA_CRH.0) | GPIOA_CRH.1) });
    // SAFETY: BSRR: LED off (high), pull-ups on the probe and door inputs.
    c.bsrr().write(|w| unsafe { w.bits(1 << board::LED_PIN | 1 << board::PROBE_PIN | 1 << board::DOOR_PIN) });
    // SAFETY: CRH: defined modes for the `GPIOC_PINS` nibbles only; the others keep theirs.
    c.crh().modify(|r, w| unsafe { w.bits((r.bits() & !GPIOC_CRH.0) | GPIOC_CRH.1) });
}
