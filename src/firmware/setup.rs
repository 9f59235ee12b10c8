//! What `init` brings up: clocks (72 MHz from the 8 MHz crystal), USART1 and SysTick through
//! the HAL, then each peripheral's own setup (GPIO, TIM2, TIM1, TIM3).

use cortex_m::peripheral::syst::SystClkSource;
use stm32f1xx_hal::flash;
use stm32f1xx_hal::pac;
use stm32f1xx_hal::prelude::*;
use stm32f1xx_hal::rcc::Config;
use stm32f1xx_hal::serial::{self, Rx, Tx};
#[cfg(feature = "usb")]
use stm32f1xx_hal::usb;

use super::{encoder, gpio, tim1_pwm, tim2};

/// What `init` hands to the tasks.
pub struct Board {
    pub tx: Tx<pac::USART1>,
    pub rx: Rx<pac::USART1>,
    pub flash: flash::Parts,
    /// The USB peripheral and its pins (D+ already pulsed low: `usb::detach`).
    #[cfg(feature = "usb")]
    pub usb: usb::Peripheral,
}

impl Board {
    /// Clocks 72 MHz from the 8 MHz crystal (USB 48 MHz: the HAL's USBPRE /1.5), pins, USART1
    /// at 115200 8N1, the USB detach pulse, TIM2 running idle.
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
        gpio::setup();

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

        // USB on PA11/PA12, after a detach the host sees.
        #[cfg(feature = "usb")]
        let pin_dp = super::usb::detach(gpioa.pa12, &mut gpioa.crh);
        #[cfg(feature = "usb")]
        let usb = usb::Peripheral { usb: dp.USB, pin_dm: gpioa.pa11, pin_dp };

        tim2::setup(&mut rcc);
        tim1_pwm::setup(&mut rcc);
        encoder::setup(&mut rcc);

        // SysTick at 1 kHz from the 72 MHz core clock.
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(72_000 - 1);
        syst.clear_current();
        syst.enable_counter();
        syst.enable_interrupt();
        // (SYST has no Drop: configured, it runs on when `syst` goes.)
        drop(syst);

        Board {
            tx,
            rx,
            flash,
            #[cfg(feature = "usb")]
            usb,
        }
    }
}
