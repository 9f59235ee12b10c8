//! The RTIC application and its hardware glue (MCU only), one file per peripheral or handler:
//! - `setup`: what `init` brings up (clocks, USART1, SysTick, then each peripheral's setup);
//! - `gpio`: pin modes, the BSRR outputs and the inputs; `boot`: GPIOB before RAM exists;
//! - `tim2`: the step timer and the DMA1 channels it drives; `pulse`: the step pulse width;
//! - `step`: the step and ramp interrupts; `burst`: DMA burst mode's buffers and fill interrupt;
//! - `output`: which of the two runs the engine, built in `init` and rebuilt at rest;
//! - `tim1_pwm`: the spindle PWM; `encoder`: TIM3 as the encoder counter;
//! - `limits`: the limit and probe EXTIs; `watchdog`: the IWDG and the reset cause;
//! - `usb`: USB CDC ACM on PA11/PA12, the second port to the same protocol (cargo feature
//!   `usb`, on by default; without it a USART1-only image);
//! - `flash_store`: the settings pages; `chip`: the flash size, unique ID and CPUID;
//! - `dwt`: the cycle counter; `panic`, `mem`;
//! - `axes`: the axis count (a leaf, so the app and the handlers do not import each other).

// Every unsafe block says why it is sound (CI: bench/tests/firmware_clippy.rs).
#![deny(clippy::undocumented_unsafe_blocks)]

mod axes;
mod boot;
mod burst;
mod chip;
mod dwt;
mod encoder;
mod flash_store;
mod gpio;
mod limits;
mod mem;
mod output;
mod panic;
mod pulse;
mod setup;
mod step;
mod tim1_pwm;
mod tim2;
#[cfg(feature = "usb")]
mod usb;
mod watchdog;

use defmt_rtt as _;

#[rtic::app(device = stm32f1xx_hal::pac, peripherals = true, dispatchers = [SPI1, SPI2])]
mod app {
    use core::sync::atomic::{AtomicBool, AtomicU32, Ordering::Relaxed};

    use ddastep::grbl::controller::Controller;
    use ddastep::motion::engine::Engine;
    use ddastep::grbl::shell::{dispatch, idle_step, take_inputs, Inputs, Requests, StepOutput};
    use ddastep::motion::shared::Shared;
    use ddastep::planning::feeder::Feeder;
    use ddastep::planning::lookahead::Buffer;
    use ddastep::motion::ring::MoveRing;
    use ddastep::motion::ramp::RampSlot;
    use ddastep::steptime::STEP_TIME;
    use heapless::spsc::{Consumer, Producer, Queue};
    use stm32f1xx_hal::pac;
    use stm32f1xx_hal::serial::{Rx, Tx};

    use super::axes::AXES;
    use super::setup::Board;
    use super::{chip, dwt, encoder, flash_store, gpio, limits, output, pulse, tim1_pwm, tim2, watchdog};
    #[cfg(feature = "usb")]
    use super::usb;

    /// Lock-free state shared with the step interrupt.
    pub static SHARED: Shared<AXES> = Shared::new();
    /// Ramp table and step timing, rebuilt by the settings code while the engine is parked.
    pub static PROFILE: RampSlot = RampSlot::new();
    /// Milliseconds since boot (SysTick).
    pub static MILLIS: AtomicU32 = AtomicU32::new(0);
    /// `?` and Ctrl-X, left by the USART interrupt for `idle`.
    static REQUESTS: Requests = Requests::new();
    /// Work for `idle`: set by SysTick (every ms) and USART1, not by the step interrupt, so
    /// `idle` sleeps through step ticks instead of polling after each one.
    static POLL: AtomicBool = AtomicBool::new(true);
    /// Replies (the one TX ring) go to USB, else to USART1: the port that last sent a line
    /// byte or opened (DTR rose); USART1 again when the USB port is gone. Realtime bytes do not
    /// move it: a pendant's `?` on one port does not take the `ok`s of a sender on the other
    /// (its status reports go to the sender, which takes them as unsolicited).
    static REPLY_USB: AtomicBool = AtomicBool::new(false);
    /// DTR rose: `idle` sends the banner (no reset).
    #[cfg(feature = "usb")]
    static BANNER: AtomicBool = AtomicBool::new(false);

    #[cfg(feature = "usb")]
    type UsbPort = &'static mut usb::Usb;
    #[cfg(not(feature = "usb"))]
    type UsbPort = ();

    #[shared]
    struct SharedRes {
        tx: Tx<pac::USART1>,
        /// Both ports' receive interrupts fill the one RX ring.
        rx_in: Producer<'static, u8>,
        /// The port replies go to drains the one TX ring.
        tx_out: Consumer<'static, u8>,
    }

    #[local]
    struct Local {
        rx: Rx<pac::USART1>,
        /// The USB device (nothing without the `usb` feature).
        usb: UsbPort,
        rx_out: Consumer<'static, u8>,
        tx_in: Producer<'static, u8>,
        controller: &'static mut Controller<'static, AXES>,
        flash: stm32f1xx_hal::flash::Parts,
        /// For the output's vectors when it is rebuilt (`output::rebuild`).
        nvic: cortex_m::peripheral::NVIC,
    }

    #[init(local = [
        moves: MoveRing<AXES> = MoveRing::new(),
        plans: Buffer<AXES> = Buffer::new(),
        // The controller lives here, not in the returned resources: built in place it costs
        // init one copy of it on the stack instead of three.
        // (MaybeUninit, not Option: `None` would put 2.9 KB of .data in flash.)
        ctl: core::mem::MaybeUninit<Controller<'static, AXES>> = core::mem::MaybeUninit::uninit(),
        rxq: Queue<u8, 256> = Queue::new(),
        txq: Queue<u8, 512> = Queue::new(),
        #[cfg(feature = "usb")]
        usb_slot: core::mem::MaybeUninit<usb::Usb> = core::mem::MaybeUninit::uninit(),
    ])]
    fn init(cx: init::Context) -> (SharedRes, Local) {
        // (Step pins low and drivers off came first: `boot.rs`.)
        let by_watchdog = watchdog::take_reset_cause();
        let mut core = cx.core;
        // (The step interrupt is bound outside RTIC: `step.rs`.)
        dwt::start_cycle_counter(&mut core.DCB, &mut core.DWT);
        let board = Board::setup(cx.device, core.SYST);
        #[cfg(feature = "usb")]
        let usb = usb::Usb::init(cx.local.usb_slot, board.usb);
        #[cfg(not(feature = "usb"))]
        let usb = ();
        // A part with too little flash for the settings pages (`ddastep::grbl::chip`): they
        // are not read, and the controller refuses motion.
        let chip = chip::read();
        let stored = flash_store::load(chip.fits());
        let settings = stored.settings;
        let (mv_in, mv_out) = cx.local.moves.split();
        let (rx_in, rx_out) = cx.local.rxq.split();
        let (tx_in, tx_out) = cx.local.txq.split();
        // Pin map and mode (`$2`, `$3`, `$580`, `$581`; a change rebuilds them at rest).
        let out = StepOutput::<AXES>::of(&settings);
        let pins = out.pins;
        let engine = Engine::new(&SHARED, mv_out, &PROFILE, pins);
        let controller = Controller::init(
            cx.local.ctl,
            Feeder::new(mv_in, cx.local.plans, &SHARED, &PROFILE, pins),
            &SHARED,
            &PROFILE,
            stored,
        );
        // Drivers off at the level `$4` asks for (`boot.rs` assumed active low).
        gpio::ENABLE_OFF_HIGH.store(!settings.enable_invert, Relaxed);
        gpio::set_enable(!settings.enable_invert);
        if by_watchdog {
            controller.watchdog_reset();
        }
        controller.chip_check(chip);
        if !chip.fits() {
            defmt::error!("chip: flash {=u16} KiB, needs {=u16} KiB: motion refused", chip.flash_kib, ddastep::grbl::chip::NEEDED_KIB);
        }
        limits::setup();
        output::install(engine, &SHARED, &out, &mut core.NVIC);
        defmt::info!("ddastep up: 72 MHz, {} axes", AXES);
        tim2::start();
        watchdog::start();
        (
            SharedRes { tx: board.tx, rx_in, tx_out },
            Local {
                rx: board.rx,
                usb,
                rx_out,
                tx_in,
                controller,
                flash: board.flash,
                nvic: core.NVIC,
            },
        )
    }

    /// Limit inputs X, Y, Z (hard limits, `$21`): at RTIC's top priority, just below the step
    /// interrupt.
    #[task(binds = EXTI0, priority = 3)]
    fn limit_x(_: limit_x::Context) {
        limits::on_edge(&SHARED);
    }

    #[task(binds = EXTI1, priority = 3)]
    fn limit_y(_: limit_y::Context) {
        limits::on_edge(&SHARED);
    }

    #[task(binds = EXTI2, priority = 3)]
    fn limit_z(_: limit_z::Context) {
        limits::on_edge(&SHARED);
    }

    /// The probe input (PC14, EXTI line 14): at RTIC's top priority, just below the step
    /// interrupt.
    #[task(binds = EXTI15_10, priority = 3)]
    fn probe(_: probe::Context) {
        limits::on_probe_edge(&SHARED);
    }

    /// USART1: realtime bytes act at once, line bytes go to the RX ring, the TX ring drains
    /// (while replies go here).
    #[task(binds = USART1, priority = 2, local = [rx], shared = [tx, rx_in, tx_out])]
    fn usart(cx: usart::Context) {
        POLL.store(true, Relaxed);
        let rx = cx.local.rx;
        let mut rx_in = cx.shared.rx_in;
        rx_in.lock(|rx_in| {
            while let Ok(b) = rx.read() {
                if let Some(b) = dispatch(b, &SHARED, &REQUESTS) {
                    REPLY_USB.store(false, Relaxed);
                    // A full ring drops the byte: a character-counting sender never fills it.
                    let _ = rx_in.enqueue(b);
                }
            }
        });
        (cx.shared.tx, cx.shared.tx_out).lock(|tx, tx_out| {
            while tx.is_tx_empty() && !REPLY_USB.load(Relaxed) {
                match tx_out.dequeue() {
                    Some(b) => {
                        let _ = tx.write_u8(b);
                    }
                    None => break,
                }
            }
            if tx_out.len() == 0 || REPLY_USB.load(Relaxed) {
                tx.unlisten();
            }
        });
    }

    /// USB (CTR, RESET, SUSP, WKUP; pended by `idle` for TX, unmasked by it for a held
    /// packet): at RTIC's lowest priority, below the step interrupt, with SysTick and the
    /// ramp vector (neither preempts the other). The host NAKs and retries, so a late run
    /// loses nothing.
    #[cfg(feature = "usb")]
    #[task(binds = USB_LP_CAN_RX0, priority = 1, local = [usb], shared = [rx_in, tx_out])]
    fn usb_lp(cx: usb_lp::Context) {
        POLL.store(true, Relaxed);
        let usb = cx.local.usb;
        let ev = usb.poll();
        if ev.gone {
            REPLY_USB.store(false, Relaxed);
        }
        if ev.opened {
            REPLY_USB.store(true, Relaxed);
            BANNER.store(true, Relaxed);
        }
        let mut rx_in = cx.shared.rx_in;
        if rx_in.lock(|rx_in| usb.receive(rx_in, |b| dispatch(b, &SHARED, &REQUESTS))) {
            REPLY_USB.store(true, Relaxed);
        }
        let mut tx_out = cx.shared.tx_out;
        if REPLY_USB.load(Relaxed) {
            tx_out.lock(|tx_out| usb.send(tx_out));
        }
    }

    /// 1 kHz clock for the protocol (dwell, idle delay) and the heartbeat; wakes `idle`;
    /// extends the encoder count.
    #[task(binds = SysTick, priority = 1, local = [enc: ddastep::encoder::count::Sampler = ddastep::encoder::count::Sampler::new()])]
    fn systick(cx: systick::Context) {
        encoder::sample(cx.local.enc);
        MILLIS.store(MILLIS.load(Relaxed).wrapping_add(1), Relaxed);
        POLL.store(true, Relaxed);
        STEP_TIME.tick_ms();
    }

    /// The protocol loop: bytes into the controller, its actions onto the pins and flash.
    #[idle(local = [rx_out, tx_in, controller, flash, nvic], shared = [tx])]
    fn idle(mut cx: idle::Context) -> ! {
        let ctl = cx.local.controller;
        let tx_in = cx.local.tx_in;
        let rx_out = cx.local.rx_out;
        // Spindle outputs last written: peripheral stores only on a change (each APB store can
        // stall the step interrupt's first register access).
        let mut spindle = ddastep::grbl::spindle::SpindleOut::default();
        ctl.welcome(tx_in);
        let mut life = ddastep::watchdog::Liveness::new(MILLIS.load(Relaxed), STEP_TIME.entries());
        let mut hard_reported = false;
        loop {
            if !POLL.swap(false, Relaxed) {
                cortex_m::asm::wfi();
                continue;
            }
            let now = MILLIS.load(Relaxed);
            let halted = limits::HALTED.load(Relaxed);
            if halted && !hard_reported {
                hard_reported = true;
                ctl.hard_limit(tx_in);
            }
            let idr = gpio::gpioa_idr();
            let door_open = gpio::gpioc_idr() & 1 << ddastep::board::DOOR_PIN == 0;
            take_inputs(ctl, &SHARED, Inputs { gpioa_idr: idr, probe_low: gpio::probe_low(), door_open });
            limits::PROBE_INVERT.store(ctl.settings().probe_invert, Relaxed);
            let invert = ctl.settings().limit_invert;
            let (counts, window) = encoder::read();
            ctl.encoder(counts, window, tx_in);
            #[cfg(feature = "usb")]
            if BANNER.swap(false, Relaxed) {
                ctl.welcome(tx_in);
            }
            let act = idle_step(ctl, rx_out, tx_in, now, &REQUESTS);
            #[cfg(feature = "usb")]
            if usb::HELD.load(Relaxed) {
                usb::retry();
            }
            // After the poll: a homing pass it just queued is watched before its move starts.
            limits::arm(ctl.settings().hard_limits, invert, ddastep::grbl::limits::active_pins(idr, invert), ctl.homing_watch());
            gpio::ENABLE_OFF_HIGH.store(!ctl.settings().enable_invert, Relaxed);
            gpio::set_enable(act.enable_pin_high);
            // Ctrl-X after a hard limit: the soft reset (in `idle_step`), then the output rebuilt
            // (HALTED read again: a trip just before the Ctrl-X is cleared by it too).
            let clear_halt = act.reset && limits::HALTED.load(Relaxed);
            let mut rebuild = act.reinit || clear_halt;
            if let Some(ticks) = act.pulse_ticks {
                // (DMA mode: a pulse its buffers' layout cannot hold rebuilds it with a new one.)
                rebuild |= !pulse::set_pulse_ticks(ticks);
            }
            if let Some(t) = act.pwm {
                tim1_pwm::set_timing(t);
            }
            if act.spindle != spindle {
                spindle = act.spindle;
                tim1_pwm::set_duty(spindle.ccr);
                gpio::set_tool_outputs(spindle);
            }
            if act.save {
                flash_store::save(cx.local.flash, &ctl.image());
            }
            if rebuild {
                // At rest (the settings that ask for it are taken only then) or halted.
                let s = ctl.settings();
                output::rebuild(&SHARED, &StepOutput::of(s), s.timing().pulse_ticks, cx.local.nvic);
                if clear_halt {
                    limits::HALTED.store(false, Relaxed);
                    hard_reported = false;
                }
            }
            gpio::heartbeat(now);
            watchdog::stall_hook();
            if life.alive(MILLIS.load(Relaxed), STEP_TIME.entries(), halted) {
                watchdog::feed();
            }
            if tx_in.len() > 0 {
                if REPLY_USB.load(Relaxed) {
                    #[cfg(feature = "usb")]
                    rtic::pend(usb::IRQ);
                } else {
                    cx.shared.tx.lock(|tx| tx.listen());
                }
            }
        }
    }
}
