//! Hardware setup: clocks, pins, TIM2 as the step timer, TIM1 as the spindle PWM, USART1,
//! SysTick.

use cortex_m::peripheral::syst::SystClkSource;
use ddastep::board;
use ddastep::motion::engine::IDLE_TICKS;
use ddastep::grbl::settings::Settings;
use ddastep::grbl::spindle::{PwmTiming, SpindleOut};
use ddastep::grbl::store::{Stored, IMAGE_LEN, PAGE_LEN};
use stm32f1xx_hal::flash;
use stm32f1xx_hal::pac;
use stm32f1xx_hal::prelude::*;
use stm32f1xx_hal::rcc::Config;
use stm32f1xx_hal::serial::{self, Rx, Tx};

/// TIM2 status: update interrupt flag.
pub const SR_UIF: u32 = 1 << 0;
/// TIM2 status: capture/compare 1 interrupt flag.
pub const SR_CC1IF: u32 = 1 << 1;

/// TIM2's registers (owned by the step interrupt after `init`).
#[inline(always)]
pub fn tim2() -> &'static pac::tim2::RegisterBlock {
    // SAFETY: after init only the step interrupt writes TIM2's SR/ARR; settings code writes
    // CCR1 only while the engine is parked.
    unsafe { &*pac::TIM2::ptr() }
}

/// GPIOB's registers: BSRR stores are atomic, so every context may use them.
#[inline(always)]
pub fn gpiob() -> &'static pac::gpiob::RegisterBlock {
    // SAFETY: only BSRR (write-only, atomic set/reset) is used after init.
    unsafe { &*pac::GPIOB::ptr() }
}

/// Starts the DWT cycle counter (DEMCR.TRCENA, DWT_CTRL.CYCCNTENA) for the step path's
/// self-measurement.
pub fn start_cycle_counter(dcb: &mut cortex_m::peripheral::DCB, dwt: &mut cortex_m::peripheral::DWT) {
    dcb.enable_trace();
    dwt.enable_cycle_counter();
}

/// DWT_CYCCNT: core cycles, wrapping (one load from the private peripheral bus).
#[inline(always)]
pub fn cycles() -> u32 {
    cortex_m::peripheral::DWT::cycle_count()
}

/// What `init` hands to the tasks.
pub struct Board {
    pub tx: Tx<pac::USART1>,
    pub rx: Rx<pac::USART1>,
    pub flash: flash::Parts,
}

/// The persistent image lives in the last two 1 KiB flash pages, A/B (`ddastep::grbl::store`):
/// memory.x keeps the program out of them.
const STORE_OFFSETS: [u32; 2] = [62 * 1024, 63 * 1024];

/// Page `i` of the store, as mapped flash.
fn store_page(i: usize) -> &'static [u8] {
    // SAFETY: the store pages are mapped flash, read-only here; written only by `save`, which
    // runs in the same (idle) context.
    unsafe { core::slice::from_raw_parts((0x0800_0000 + STORE_OFFSETS[i]) as *const u8, PAGE_LEN) }
}

/// The newest valid image of the two pages (defaults when both are blank or torn).
pub fn load_store() -> Stored {
    Stored::load([store_page(0), store_page(1)]).0
}

/// Writes the image into the page not holding the newest valid one, then reads it back (the
/// CPU stalls while flash is busy: only when idle). A power cut leaves the other page intact.
pub fn save_store(parts: &mut flash::Parts, image: &[u8; IMAGE_LEN]) {
    let target = Stored::newest([store_page(0), store_page(1)]).map_or(0, |i| 1 - i);
    let at = STORE_OFFSETS[target];
    let mut w = parts.writer(flash::SectorSize::Sz1K, flash::FlashSize::Sz64K);
    // The read-back below compares the whole image: the HAL's own per-halfword and erase checks
    // would only repeat it (and cost flash).
    w.change_verification(false);
    let ok = w.erase(at, 1024).is_ok() && w.write(at, image).is_ok();
    if !ok || store_page(target).get(..IMAGE_LEN) != Some(&image[..]) {
        defmt::warn!("store: flash write failed; the previous image stays in force");
    }
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

/// New step pulse width: CCR1 is preloaded, so it takes effect at the next update event.
/// Nothing in dual-edge mode ([`no_falling_edge`]: the compare interrupt is off). `false` when
/// DMA burst mode's buffers cannot hold the pulse (their layout follows it: a restart).
pub fn set_pulse_ticks(ticks: u32) -> bool {
    let dier = tim2().dier().read();
    let ccr = if super::burst::active() {
        if dier.cc1de().bit_is_clear() {
            return true;
        }
        let Some(fall) = super::burst::fall_ticks(ticks) else { return false };
        fall
    } else {
        if dier.cc1ie().bit_is_clear() {
            return true;
        }
        ticks + ddastep::motion::timing::STORE_LATENCY_TICKS
    };
    // (Preloaded: the step interrupt's period sees it from the next update.)
    tim2().ccr1().write(|w| w.ccr().set(ccr.min(0xFFFF) as u16));
    true
}

/// DMA mode: compare 3 (the period store) one tick after the update.
const PERIOD_STORE_TICK: u16 = 1;

/// TIM2 DIER: DMA requests on update, compare 1, compare 3.
const DIER_UDE: u32 = 1 << 8;
const DIER_CC1DE: u32 = 1 << 9;
const DIER_CC3DE: u32 = 1 << 11;

/// DMA1's registers (the fill interrupt owns channel 1's flags after `init`).
#[inline(always)]
pub fn dma1() -> &'static pac::dma1::RegisterBlock {
    // SAFETY: after init only the fill interrupt touches DMA1 (ISR read, IFCR write).
    unsafe { &*pac::DMA1::ptr() }
}

/// DMA burst mode (`ddastep::motion::burst`): TIM2 without interrupts, its update event storing
/// `words[k]` into GPIOB's BSRR (channel 2), its compare 3 event storing `periods[k]` into ARR
/// (channel 1, with the fill interrupt at each half), and with full pulses its compare 1
/// event, `fall` ticks after the update, storing `*off` into BSRR (channel 5). `n` entries,
/// circular; the first period is `first` ticks.
pub fn setup_dma(words: u32, periods: u32, off: u32, n: u32, first: u32, fall: u32, dual: bool) {
    // SAFETY: one bit of the clock enables (DMA1EN), set once in init, interrupts off.
    unsafe { (*pac::RCC::ptr()).ahbenr().modify(|_, w| w.dma1en().set_bit()) };
    let t = tim2();
    // Every TIM2 interrupt and DMA request off (DIER's reset value).
    t.dier().reset();
    // SAFETY: ARR: `first` is the layout's longest entry, which fits the 16-bit counter.
    t.arr().write(|w| unsafe { w.bits(first - 1) });
    // Compare 3 frozen, not preloaded (CCMR2's reset value), one tick after the update: the
    // period store.
    t.ccmr2_output().reset();
    t.ccr3().write(|w| w.ccr().set(PERIOD_STORE_TICK));
    // SAFETY: CCR1: the falling edge's compare value, inside the 16-bit period.
    t.ccr1().write(|w| unsafe { w.bits(fall) });
    t.egr().write(|w| w.ug().set_bit());
    // Counting starts past compare 3, so the first period store follows the first update.
    t.cnt().write(|w| w.cnt().set(PERIOD_STORE_TICK + 1));
    // Every flag cleared (SR's reset value).
    t.sr().reset();
    // CCR: memory to peripheral (DIR), circular, memory increment, very high priority, on.
    const DIR: u32 = 1 << 4;
    const CIRC: u32 = 1 << 5;
    const MINC: u32 = 1 << 7;
    const P32: u32 = 0b10 << 8;
    const M16: u32 = 0b01 << 10;
    const M32: u32 = 0b10 << 10;
    const VERY_HIGH: u32 = 0b11 << 12;
    const HTIE: u32 = 1 << 2;
    const TCIE: u32 = 1 << 1;
    const EN: u32 = 1;
    let gpiob_bsrr = gpiob().bsrr().as_ptr() as u32;
    let dma = dma1();
    let channel = |ch: &pac::dma1::CH, par: u32, mar: u32, n: u32, cr: u32| {
        // Channel off first (CR's reset value): PAR, MAR and NDTR are writable only while EN is 0.
        ch.cr().reset();
        // SAFETY: PAR: a 32-bit peripheral register (GPIOB_BSRR or TIM2_ARR) that DMA may store into.
        ch.par().write(|w| unsafe { w.bits(par) });
        // SAFETY: MAR: a static buffer of `burst` (never freed) that DMA only reads.
        ch.mar().write(|w| unsafe { w.bits(mar) });
        // SAFETY: NDTR: the entry count, at most 2 · HALF_MAX, within its 16 bits.
        ch.ndtr().write(|w| unsafe { w.bits(n) });
        // SAFETY: CR: the named mode bits above (defined fields only) plus EN, which starts the channel.
        ch.cr().write(|w| unsafe { w.bits(cr | EN) });
    };
    channel(dma.ch2(), gpiob_bsrr, words, n, DIR | CIRC | MINC | P32 | M32 | VERY_HIGH);
    channel(dma.ch1(), t.arr().as_ptr() as u32, periods, n, DIR | CIRC | MINC | P32 | M16 | VERY_HIGH | HTIE | TCIE);
    let mut dier = DIER_UDE | DIER_CC3DE;
    if !dual {
        channel(dma.ch5(), gpiob_bsrr, off, 1, DIR | CIRC | P32 | M32 | VERY_HIGH);
        dier |= DIER_CC1DE;
    }
    // SAFETY: DIER: the DMA request enables named above, no interrupt enable.
    t.dier().write(|w| unsafe { w.bits(dier) });
}

/// Dual-edge mode: no compare event (interrupt off, CCR1 past every period the engine sets).
pub fn no_falling_edge() {
    tim2().dier().write(|w| w.uie().set_bit());
    tim2().ccr1().write(|w| w.ccr().set(u16::MAX));
}

/// TIM1's registers (written only by `idle` after init).
#[inline(always)]
fn tim1() -> &'static pac::tim1::RegisterBlock {
    // SAFETY: only `idle` (one context) writes TIM1 after init; no interrupt uses it.
    unsafe { &*pac::TIM1::ptr() }
}

/// New spindle PWM frequency: prescaler and period, taken at the next update event.
pub fn set_pwm_timing(t: PwmTiming) {
    tim1().psc().write(|w| w.psc().set(t.psc));
    // (Preloaded, ARPE: a period is never cut.)
    tim1().arr().write(|w| w.arr().set(t.arr));
}

/// Spindle PWM compare value (preloaded: one whole period at a time) and the spindle and
/// coolant pins (one atomic BSRR store).
pub fn set_spindle(o: SpindleOut) {
    tim1().ccr1().write(|w| w.ccr().set(o.ccr));
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

impl Board {
    /// Clocks 72 MHz from the 8 MHz crystal, pins, USART1 at 115200 8N1, TIM2 running idle.
    #[inline(never)]
    pub fn setup(dp: pac::Peripherals, mut syst: cortex_m::peripheral::SYST) -> Board {
        let mut flash = dp.FLASH.constrain();
        let mut rcc = dp.RCC.freeze(
            Config::hse(8.MHz()).sysclk(72.MHz()).pclk1(36.MHz()).pclk2(72.MHz()),
            &mut flash.acr,
        );
        let mut afio = dp.AFIO.constrain(&mut rcc);
        let mut gpioa = dp.GPIOA.split(&mut rcc);
        // SAFETY: `boot.rs` already drives GPIOB; a reset here would float the step and
        // enable pins. Of its HAL pins only PB3/PB4 are used, by `disable_jtag` (AFIO only).
        let gpiob = unsafe { dp.GPIOB.split_without_reset(&mut rcc) };
        let _gpioc = dp.GPIOC.split(&mut rcc);
        let _ = afio.mapr.disable_jtag(gpioa.pa15, gpiob.pb3, gpiob.pb4);
        setup_pins();

        // USART1 on PA9/PA10.
        let tx_pin = gpioa.pa9.into_alternate_push_pull(&mut gpioa.crh);
        let rx_pin = gpioa.pa10;
        let serial = dp.USART1.serial(
            (tx_pin, rx_pin),
            serial::Config::default().baudrate(115_200.bps()),
            &mut rcc,
        );
        let (tx, mut rx) = serial.split();
        rx.listen();

        setup_tim2(&mut rcc);
        setup_tim1(&mut rcc);
        super::encoder::setup(&mut rcc);

        // SysTick at 1 kHz from the 72 MHz core clock.
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(72_000 - 1);
        syst.clear_current();
        syst.enable_counter();
        syst.enable_interrupt();
        core::mem::forget(syst);

        Board { tx, rx, flash }
    }
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
fn setup_pins() {
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

/// The idle period (ARR) and the default pulse's falling edge (CCR1) TIM2 starts with.
const IDLE_ARR: u16 = (IDLE_TICKS - 1) as u16;
const DEFAULT_CCR1: u16 = (ddastep::motion::timing::Timing::DEFAULT.pulse_ticks + ddastep::motion::timing::STORE_LATENCY_TICKS) as u16;
const _: () = assert!(IDLE_TICKS - 1 <= 0xFFFF && DEFAULT_CCR1 as u32 == ddastep::motion::timing::Timing::DEFAULT.pulse_ticks + ddastep::motion::timing::STORE_LATENCY_TICKS);

/// TIM2 as the step timer: 72 MHz, no prescaler, buffered ARR, update and compare-1 interrupts.
fn setup_tim2(rcc: &mut stm32f1xx_hal::rcc::Rcc) {
    use stm32f1xx_hal::rcc::{Enable, Reset};
    pac::TIM2::enable(rcc);
    pac::TIM2::reset(rcc);
    let t = tim2();
    t.psc().write(|w| w.psc().set(0));
    t.arr().write(|w| w.arr().set(IDLE_ARR));
    // Compare 1 "frozen" (no pin), CCR1 preloaded so a new pulse width starts at an update.
    t.ccmr1_output().write(|w| w.oc1pe().enabled());
    t.ccr1().write(|w| w.ccr().set(DEFAULT_CCR1));
    t.egr().write(|w| w.ug().set_bit());
    t.sr().reset();
    t.dier().write(|w| w.uie().enabled().cc1ie().enabled());
    // Counting starts in `start_step_timer`.
    t.cr1().write(|w| w.arpe().enabled().urs().counter_only());
}

/// TIM1 as the spindle PWM on PA8: PWM mode 1 on channel 1 with CCR1 preloaded, main output
/// on, duty 0, at the default frequency (the first poll sets `$33`'s).
fn setup_tim1(rcc: &mut stm32f1xx_hal::rcc::Rcc) {
    use stm32f1xx_hal::rcc::{Enable, Reset};
    pac::TIM1::enable(rcc);
    pac::TIM1::reset(rcc);
    set_pwm_timing(PwmTiming::new(Settings::DEFAULT.spindle_pwm_hz));
    let t = tim1();
    t.ccr1().write(|w| w.ccr().set(0));
    t.ccmr1_output().write(|w| w.oc1m().pwm_mode1().oc1pe().enabled());
    // Channel 1 output on, active high.
    t.ccer().write(|w| w.cc1e().set_bit());
    // Main output on: an advanced timer's outputs stay off without it.
    t.bdtr().write(|w| w.moe().set_bit());
    t.egr().write(|w| w.ug().set_bit());
    t.cr1().write(|w| w.arpe().enabled().cen().enabled());
}

/// Starts TIM2 counting: the last thing `init` does, so the first update event does not wait
/// behind the rest of init (which runs with interrupts off).
pub fn start_step_timer() {
    tim2().cr1().modify(|_, w| w.cen().enabled());
}
