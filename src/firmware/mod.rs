//! The RTIC application and its hardware glue (MCU only).

mod hw;
mod panic;

use defmt_rtt as _;

#[rtic::app(device = stm32f1xx_hal::pac, peripherals = true, dispatchers = [SPI1, SPI2])]
mod app {
    use core::sync::atomic::{AtomicU32, Ordering::Relaxed};

    use ddastep::board;
    use ddastep::engine::Engine;
    use ddastep::queue::{Feeder, Move, Shared};
    use ddastep::ramp::RampSlot;
    use heapless::spsc::{Consumer, Producer, Queue};
    use stm32f1xx_hal::pac;
    use stm32f1xx_hal::serial::{Rx, Tx};

    use super::hw;

    /// Axes the firmware drives: X Y Z A B C U.
    pub const AXES: usize = ddastep::MAX_AXES;

    /// Lock-free state shared with the step interrupt.
    pub static SHARED: Shared<AXES> = Shared::new();
    /// Ramp table and step timing, rebuilt by the settings code while the engine is parked.
    pub static PROFILE: RampSlot = RampSlot::new();
    /// Milliseconds since boot (SysTick).
    pub static MILLIS: AtomicU32 = AtomicU32::new(0);

    #[shared]
    struct SharedRes {
        tx: Tx<pac::USART1>,
    }

    #[local]
    struct Local {
        engine: Engine<'static, AXES>,
        rx: Rx<pac::USART1>,
        rx_in: Producer<'static, u8>,
        rx_out: Consumer<'static, u8>,
        tx_in: Producer<'static, u8>,
        tx_out: Consumer<'static, u8>,
        feeder: Feeder<'static, AXES>,
    }

    #[init(local = [
        moves: Queue<Move<AXES>, 16> = Queue::new(),
        rxq: Queue<u8, 256> = Queue::new(),
        txq: Queue<u8, 512> = Queue::new(),
    ])]
    fn init(cx: init::Context) -> (SharedRes, Local) {
        let dp = cx.device;
        let board = hw::Board::setup(dp, cx.core.SYST);
        let (mv_in, mv_out) = cx.local.moves.split();
        let (rx_in, rx_out) = cx.local.rxq.split();
        let (tx_in, tx_out) = cx.local.txq.split();
        let engine = Engine::new(&SHARED, mv_out, &PROFILE, board::pin_map::<AXES>(0, 0));
        defmt::info!("ddastep up: 72 MHz, TIM2 step timer");
        (
            SharedRes { tx: board.tx },
            Local {
                engine,
                rx: board.rx,
                rx_in,
                rx_out,
                tx_in,
                tx_out,
                feeder: Feeder::new(mv_in, &SHARED),
            },
        )
    }

    /// The step interrupt: store the precomputed word first, then compute the next one.
    #[task(binds = TIM2, priority = 3, local = [engine])]
    fn step(cx: step::Context) {
        let engine = cx.local.engine;
        let sr = hw::tim2().sr().read().bits();
        if sr & hw::SR_UIF != 0 {
            hw::gpiob().bsrr().write(|w| unsafe { w.bits(engine.word()) });
            hw::tim2().sr().write(|w| unsafe { w.bits(!hw::SR_UIF) });
            let arr = engine.tick();
            hw::tim2().arr().write(|w| unsafe { w.bits(arr as u32) });
        }
        // The compare event ends the pulse; if it came while we computed, end it now.
        if hw::tim2().sr().read().bits() & hw::SR_CC1IF != 0 {
            hw::gpiob().bsrr().write(|w| unsafe { w.bits(engine.step_off()) });
            hw::tim2().sr().write(|w| unsafe { w.bits(!hw::SR_CC1IF) });
        }
    }

    /// USART1: received bytes into the RX ring, TX ring out to the wire.
    #[task(binds = USART1, priority = 2, local = [rx, rx_in, tx_out], shared = [tx])]
    fn usart(mut cx: usart::Context) {
        while let Ok(b) = cx.local.rx.read() {
            let _ = cx.local.rx_in.enqueue(b);
        }
        let tx_out = cx.local.tx_out;
        cx.shared.tx.lock(|tx| {
            while tx.is_tx_empty() {
                match tx_out.dequeue() {
                    Some(b) => {
                        let _ = tx.write_u8(b);
                    }
                    None => {
                        tx.unlisten();
                        break;
                    }
                }
            }
        });
    }

    /// 1 kHz clock for the protocol (dwell, idle delay) and the heartbeat; wakes `idle`.
    #[task(binds = SysTick, priority = 1)]
    fn systick(_: systick::Context) {
        MILLIS.store(MILLIS.load(Relaxed).wrapping_add(1), Relaxed);
    }

    #[idle(local = [rx_out, tx_in, feeder], shared = [tx])]
    fn idle(mut cx: idle::Context) -> ! {
        loop {
            let mut sent = false;
            while let Some(b) = cx.local.rx_out.dequeue() {
                // Bring-up: echo until the protocol lands.
                let _ = cx.local.tx_in.enqueue(b);
                sent = true;
            }
            if sent {
                cx.shared.tx.lock(|tx| tx.listen());
            }
            let _ = &cx.local.feeder;
            cortex_m::asm::wfi();
        }
    }
}
