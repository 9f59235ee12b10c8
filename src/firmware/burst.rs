//! DMA burst step output (`$581=1`): TIM2 paces every edge and DMA stores the words the engine
//! buffered (`ddastep::motion::burst`); no interrupt runs per edge.
//!
//! TIM2's update event requests DMA1 channel 2, which stores the next step word into GPIOB's
//! BSRR; its compare 3 event, one tick later, requests channel 1, which stores the next period
//! into the (preloaded) ARR; with full pulses its compare 1 event, the pulse width after the
//! update, requests channel 5, which stores the constant falling-edge word. Both buffers are
//! circular; channel 1's half-transfer and transfer-complete interrupt (after the period store,
//! so both channels are done with the half) fills the half just played. The fill runs at
//! RTIC's lowest priority, below the serial interrupt (see `install`), and does the ramp half's
//! work itself, so the ramp vector stays off.
//!
//! Hard limits stop TIM2 (`limits.rs`), and with it every DMA request, at once; entries already
//! buffered (≤ 1 ms) are then never played, so the position is lost as in interrupt mode (it
//! is anyway after a hard limit). Feed hold and stop reach the pins after the buffered
//! entries: ≤ `Layout::latency_ticks` (1 ms).

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicU32, Ordering::Relaxed};

use ddastep::motion::burst::{Burst, Layout, HALF_MAX};
use ddastep::steptime::STEP_TIME;
use stm32f1xx_hal::pac::{self, interrupt};

use super::axes::AXES;
use super::dwt::cycles;
use super::tim2::{dma1, setup_dma};

/// The engine and the buffers DMA reads, owned by the fill interrupt after `init`.
struct State {
    burst: MaybeUninit<Burst<'static, AXES>>,
    words: [u32; 2 * HALF_MAX],
    periods: [u16; 2 * HALF_MAX],
    /// The falling-edge word channel 5 stores at every compare event.
    off: u32,
}

struct Slot(UnsafeCell<State>);

// SAFETY: written by `install` and read back by `uninstall` with the fill interrupt masked
// and DMA off, otherwise only by the fill interrupt (one context, never re-entered); DMA reads
// the half the fill is not writing.
unsafe impl Sync for Slot {}

static STATE: Slot = Slot(UnsafeCell::new(State {
    burst: MaybeUninit::uninit(),
    words: [0; 2 * HALF_MAX],
    periods: [0; 2 * HALF_MAX],
    off: 0,
}));

/// Entries per half in use (0: interrupt mode).
static HALF: AtomicU32 = AtomicU32::new(0);
/// The layout's longest entry (0: interrupt mode).
static MAX_TICK: AtomicU32 = AtomicU32::new(0);

/// DMA1 interrupt flags of channel 1: global, transfer complete, half transfer.
const ISR_CH1: u32 = 0xF;
const HTIF1: u32 = 1 << 2;
const TCIF1: u32 = 1 << 1;

/// Whether the step output runs on DMA.
pub fn active() -> bool {
    HALF.load(Relaxed) != 0
}

/// The compare value of the falling edge for a pulse of `ticks` in DMA mode, if the buffers'
/// layout holds it (else the layout must change: a rebuild, `output::rebuild`).
pub fn fall_ticks(ticks: u32) -> Option<u32> {
    let fall = ddastep::motion::timing::dma_fall_ticks(ticks);
    (fall < MAX_TICK.load(Relaxed) / 2).then_some(fall)
}

/// Fills both halves, hands the engine to the fill interrupt, starts DMA1 (in `init`,
/// interrupts off, or at rest from `output::rebuild`; TIM2 starts counting later, in
/// `tim2::start`).
pub fn install(burst: Burst<'static, AXES>, layout: Layout, fall: u32, dual: bool, nvic: &mut cortex_m::peripheral::NVIC) {
    let n = 2 * layout.half;
    // SAFETY: the fill interrupt is masked (not yet unmasked, or by `uninstall`) and DMA is
    // off: no other access.
    let s = unsafe { &mut *STATE.0.get() };
    let burst = s.burst.write(burst);
    s.off = burst.step_off();
    burst.fill(s.words.get_mut(..n).unwrap_or_default(), s.periods.get_mut(..n).unwrap_or_default());
    HALF.store(layout.half as u32, Relaxed);
    MAX_TICK.store(layout.max_tick, Relaxed);
    setup_dma(s.words.as_ptr() as u32, s.periods.as_ptr() as u32, &s.off as *const u32 as u32, n as u32, layout.max_tick, fall, dual);
    // SAFETY: RTIC's lowest priority (with SysTick), below the serial interrupt: a fill runs
    // for a whole half (up to ~150 µs near the cap), longer than one byte's time at 115200
    // baud, so above the USART it would lose received bytes; the serial interrupt is short
    // against a half's time. The engine and buffers are in place.
    unsafe {
        nvic.set_priority(pac::Interrupt::DMA1_CHANNEL1, super::step::nvic_priority(1));
        cortex_m::peripheral::NVIC::unmask(pac::Interrupt::DMA1_CHANNEL1);
    }
}

/// Masks the fill interrupt and turns DMA off (TIM2 stopped), takes the engine back; interrupt
/// mode from here until the next `install`.
pub fn uninstall() -> ddastep::motion::engine::Engine<'static, AXES> {
    cortex_m::peripheral::NVIC::mask(pac::Interrupt::DMA1_CHANNEL1);
    cortex_m::peripheral::NVIC::unpend(pac::Interrupt::DMA1_CHANNEL1);
    let dma = dma1();
    for ch in [dma.ch1(), dma.ch2(), dma.ch5()] {
        // Channel off (CR's reset value).
        ch.cr().reset();
    }
    // SAFETY: IFCR is write-1-to-clear; channel 1's four flags.
    dma.ifcr().write(|w| unsafe { w.bits(ISR_CH1) });
    HALF.store(0, Relaxed);
    MAX_TICK.store(0, Relaxed);
    // SAFETY: `install` wrote the engine (DMA mode is on); the fill interrupt is masked and
    // DMA off, and `install` writes it again before unmasking (the copy read here is the only
    // one used).
    unsafe { (*STATE.0.get()).burst.assume_init_read() }.into_engine()
}

/// Channel 1 played a half (or the whole buffer): fill it again. Times itself like the step
/// interrupt (`$I`: cycles per fill of one half).
#[interrupt]
#[link_section = ".fill.dma1_channel1"]
fn DMA1_CHANNEL1() {
    let t0 = cycles();
    let dma = dma1();
    let flags = dma.isr().read().bits() & ISR_CH1;
    // SAFETY: IFCR is write-1-to-clear; `flags` holds only channel 1's four flags (ISR_CH1).
    dma.ifcr().write(|w| unsafe { w.bits(flags) });
    let half = (HALF.load(Relaxed) as usize).min(HALF_MAX);
    // SAFETY: installed before the interrupt was unmasked; this handler is its only user.
    let s = unsafe { &mut *STATE.0.get() };
    // SAFETY: `install` wrote the engine before unmasking this interrupt, the only user of the slot.
    let burst = unsafe { s.burst.assume_init_mut() };
    // The half just played: the first after a half transfer, the second after the transfer
    // complete (both when this interrupt came late; DMA is then in the first again).
    for (flag, at) in [(HTIF1, 0), (TCIF1, half)] {
        if flags & flag != 0 {
            // SAFETY: `at + half ≤ 2 · HALF_MAX`: one half of each buffer, which DMA is not
            // reading now (it plays the other).
            let (w, p) = unsafe {
                (
                    core::slice::from_raw_parts_mut(s.words.as_mut_ptr().add(at), half),
                    core::slice::from_raw_parts_mut(s.periods.as_mut_ptr().add(at), half),
                )
            };
            // Where DMA's word channel (the first to read an entry) is in this half (0 while it
            // plays the other one).
            let played = || ddastep::motion::burst::dma_played(dma.ch2().ndtr().read().bits(), 2 * half, at, half);
            // Late when DMA is in the half already as the fill starts, catches up with it during
            // the fill, or has played all of it when the fill ends (its own flag set again).
            let late = played() > 0;
            let late = burst.fill_watched(w, p, played) | late | (dma.isr().read().bits() & flag != 0);
            if late {
                STEP_TIME.note_late();
            }
        }
    }
    STEP_TIME.record(cycles().wrapping_sub(t0));
}
