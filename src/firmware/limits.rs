//! Hard limits (`$21`): EXTI lines 0–2 on the X, Y, Z limit inputs (PA0–PA2), both edges, at
//! RTIC's top priority, just below the step interrupt (so it runs right after a step interrupt
//! in progress, never in the middle of its BSRR store; a step interrupt already pending when it
//! stops the timer may still run once, before the step pins are driven low). When an edge leaves a limit pin active that was not
//! active at the last poll (`$5` applied; as Grbl's `HARD_LIMIT_FORCE_STATE_CHECK`, and so
//! neither a switch's release nor its bounce trips), the handler
//! stops TIM2 and its interrupt, drives every step pin low and sets [`HALTED`]; the idle loop
//! then reports ALARM:1. The engine is not touched: its move is cut where the timer stopped,
//! and the Ctrl-X that follows rebuilds the step output in place (`output::rebuild`: the
//! engine takes the stop, keeping its position) and leaves the controller in the alarm state
//! (as Grbl, which keeps its position across the reset but wants `$H` or `$X`, the position
//! being suspect).

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering::Relaxed};

use ddastep::board;
use stm32f1xx_hal::pac;

use super::gpio;
use super::tim2::tim2;

/// The limit interrupt stopped the step output (cleared by the Ctrl-X's rebuild).
pub static HALTED: AtomicBool = AtomicBool::new(false);
/// Bit 0: `$21` on; bit 1: `$5` (pins inverted); bits 8–10: pins already active at the last
/// poll (a carriage resting on or leaving its switch: the release bounce must not trip);
/// bits 16–18: homing's watched axes (their switch closing stops the engine, no alarm).
/// Written by `idle`, read by the handler.
static ARMED: AtomicU32 = AtomicU32::new(0);
/// EXTI lines 0, 1, 2 (PA0, PA1, PA2: AFIO_EXTICR1 selects port A at reset).
const LINES: u32 = 0b111;
/// EXTI line 14: the probe input, PC14 (AFIO_EXTICR4 selects port C). Always unmasked: its
/// handler acts only while the controller has a probe cycle armed.
const PROBE_LINE: u32 = 1 << board::PROBE_PIN;
/// `$6` (probe input inverted), written by `idle`.
pub static PROBE_INVERT: AtomicBool = AtomicBool::new(false);
fn exti() -> &'static pac::exti::RegisterBlock {
    // SAFETY: `setup` runs in init; afterwards `arm` writes IMR (idle) and the handler writes
    // PR (rc_w1: clearing its own lines); the two registers are independent.
    unsafe { &*pac::EXTI::ptr() }
}

/// Both edges of the three lines; masked until [`arm`].
pub fn setup() {
    let e = exti();
    // SAFETY: IMR: the probe line only, a line EXTI has (init, interrupts off).
    e.imr().write(|w| unsafe { w.bits(PROBE_LINE) });
    // SAFETY: RTSR: rising edges on lines 0-2 and 14, lines EXTI has.
    e.rtsr().write(|w| unsafe { w.bits(LINES | PROBE_LINE) });
    // SAFETY: FTSR: falling edges on the same lines.
    e.ftsr().write(|w| unsafe { w.bits(LINES | PROBE_LINE) });
    // SAFETY: PR is write-1-to-clear: clears the pending flags of those lines only.
    e.pr().write(|w| unsafe { w.bits(LINES | PROBE_LINE) });
    // SAFETY: init only; AFIO's clock is on (the JTAG remap).
    let afio = unsafe { &*pac::AFIO::ptr() };
    // EXTI14 from port C (the register's other lines port A, as at reset).
    afio.exticr4().write(|w| w.exti14().pc());
}

/// The EXTI15_10 handler body: the probe input changed; a probe cycle's edge stops the engine
/// at its next tick (see `Shared::probe_input`).
pub fn on_probe_edge<const N: usize>(shared: &ddastep::motion::shared::Shared<N>) {
    // SAFETY: PR is write-1-to-clear: clears only the probe line's flag, this handler's own.
    exti().pr().write(|w| unsafe { w.bits(PROBE_LINE) });
    shared.probe_input(gpio::probe_low() != PROBE_INVERT.load(Relaxed));
}

/// Follows `$21` and `$5`, the pins active now, and homing (`watch`: `Some(axes)` while a
/// cycle runs; hard limits are off then, as in Grbl) (every poll: two stores).
pub fn arm(on: bool, invert: bool, active: u8, watch: Option<u8>) {
    let on = on && watch.is_none();
    let watch = watch.unwrap_or(0) as u32;
    ARMED.store(on as u32 | (invert as u32) << 1 | (active as u32) << 8 | watch << 16, Relaxed);
    // SAFETY: IMR: lines 0-2 and 14 or line 14 alone; only `idle` writes IMR.
    exti().imr().write(|w| unsafe { w.bits(if on || watch != 0 { LINES | PROBE_LINE } else { PROBE_LINE }) });
}

/// The EXTI0/1/2 handler body: homing's stop for a watched switch, else (hard limits) stop
/// all step output if a limit pin went active.
pub fn on_edge<const N: usize>(shared: &ddastep::motion::shared::Shared<N>) {
    // SAFETY: PR is write-1-to-clear: clears only lines 0-2, this handler's own.
    exti().pr().write(|w| unsafe { w.bits(LINES) });
    let armed = ARMED.load(Relaxed);
    let active = ddastep::grbl::limits::active_pins(gpio::gpioa_idr(), armed & 2 != 0) as u32;
    if active & armed >> 16 != 0 {
        // Homing: the engine ends its move at its next tick, the position exact.
        shared.stop_now();
        return;
    }
    if armed & 1 == 0 || HALTED.load(Relaxed) || active & !(armed >> 8) & 7 == 0 {
        return;
    }
    // TIM2 off (counter, interrupt enables, flags, NVIC pending), then the step pins low.
    let t = tim2();
    t.cr1().modify(|_, w| w.cen().disabled());
    t.dier().reset();
    t.sr().reset();
    cortex_m::peripheral::NVIC::unpend(pac::Interrupt::TIM2);
    let low = board::STEP_PINS.iter().fold(0u32, |w, &p| w | 1 << (p + 16));
    // SAFETY: BSRR takes any word; this one resets only the step pins.
    gpio::gpiob().bsrr().write(|w| unsafe { w.bits(low) });
    HALTED.store(true, Relaxed);
}
