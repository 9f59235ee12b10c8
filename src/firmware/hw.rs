//! Hardware setup: clocks, pins, TIM2 as the step timer, USART1, SysTick.

use cortex_m::peripheral::syst::SystClkSource;
use ddastep::board;
use ddastep::engine::IDLE_TICKS;
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

/// What `init` hands to the tasks.
pub struct Board {
    pub tx: Tx<pac::USART1>,
    pub rx: Rx<pac::USART1>,
}

impl Board {
    /// Clocks 72 MHz from the 8 MHz crystal, pins, USART1 at 115200 8N1, TIM2 running idle.
    pub fn setup(dp: pac::Peripherals, mut syst: cortex_m::peripheral::SYST) -> Board {
        let mut flash = dp.FLASH.constrain();
        let mut rcc = dp.RCC.freeze(
            Config::hse(8.MHz()).sysclk(72.MHz()).pclk1(36.MHz()).pclk2(72.MHz()),
            &mut flash.acr,
        );
        let mut afio = dp.AFIO.constrain(&mut rcc);
        let mut gpioa = dp.GPIOA.split(&mut rcc);
        let mut gpiob = dp.GPIOB.split(&mut rcc);
        let mut gpioc = dp.GPIOC.split(&mut rcc);
        let (_pa15, pb3, pb4) = afio.mapr.disable_jtag(gpioa.pa15, gpiob.pb3, gpiob.pb4);

        // Step/dir/enable: push-pull outputs on GPIOB, all low but EN high (drivers off).
        let crl = &mut gpiob.crl;
        let crh = &mut gpiob.crh;
        let _ = gpiob.pb0.into_push_pull_output(crl);
        let _ = gpiob.pb1.into_push_pull_output(crl);
        let _ = pb3.into_push_pull_output(crl);
        let _ = pb4.into_push_pull_output(crl);
        let _ = gpiob.pb5.into_push_pull_output(crl);
        let _ = gpiob.pb6.into_push_pull_output(crl);
        let _ = gpiob.pb7.into_push_pull_output(crl);
        let _ = gpiob.pb8.into_push_pull_output_with_state(crh, stm32f1xx_hal::gpio::PinState::High);
        let _ = gpiob.pb9.into_push_pull_output(crh);
        let _ = gpiob.pb10.into_push_pull_output(crh);
        let _ = gpiob.pb11.into_push_pull_output(crh);
        let _ = gpiob.pb12.into_push_pull_output(crh);
        let _ = gpiob.pb13.into_push_pull_output(crh);
        let _ = gpiob.pb14.into_push_pull_output(crh);
        let _ = gpiob.pb15.into_push_pull_output(crh);
        // Limit switches (reserved): inputs with pull-ups.
        let _ = gpioa.pa0.into_pull_up_input(&mut gpioa.crl);
        let _ = gpioa.pa1.into_pull_up_input(&mut gpioa.crl);
        let _ = gpioa.pa2.into_pull_up_input(&mut gpioa.crl);
        let _ = gpioa.pa3.into_pull_up_input(&mut gpioa.crl);
        let _ = gpioa.pa4.into_pull_up_input(&mut gpioa.crl);
        let _ = gpioa.pa5.into_pull_up_input(&mut gpioa.crl);
        let _ = gpioa.pa8.into_pull_up_input(&mut gpioa.crh);
        let _ = gpioc.pc13.into_push_pull_output_with_state(&mut gpioc.crh, stm32f1xx_hal::gpio::PinState::High);
        let _ = board::LED_PIN;

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

        // SysTick at 1 kHz from the 72 MHz core clock.
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(72_000 - 1);
        syst.clear_current();
        syst.enable_counter();
        syst.enable_interrupt();
        core::mem::forget(syst);

        Board { tx, rx }
    }
}

/// TIM2 as the step timer: 72 MHz, no prescaler, buffered ARR, update and compare-1 interrupts.
fn setup_tim2(rcc: &mut stm32f1xx_hal::rcc::Rcc) {
    use stm32f1xx_hal::rcc::{Enable, Reset};
    pac::TIM2::enable(rcc);
    pac::TIM2::reset(rcc);
    let t = tim2();
    t.psc().write(|w| unsafe { w.bits(0) });
    t.arr().write(|w| unsafe { w.bits(IDLE_TICKS - 1) });
    // Compare 1 "frozen" (no pin), CCR1 preloaded so a new pulse width starts at an update.
    t.ccmr1_output().write(|w| unsafe { w.bits(1 << 3) });
    t.ccr1().write(|w| unsafe { w.bits(ddastep::timing::Timing::DEFAULT.pulse_ticks) });
    t.egr().write(|w| w.ug().set_bit());
    t.sr().write(|w| unsafe { w.bits(0) });
    t.dier().write(|w| unsafe { w.bits(SR_UIF | SR_CC1IF) });
    // ARPE | URS | CEN
    t.cr1().write(|w| unsafe { w.bits((1 << 7) | (1 << 2) | 1) });
}
