//! What the firmware shell runs around the controller, kept here so the host rigs run the same
//! code: the RX interrupt's realtime-byte dispatch, the idle loop's sampled inputs and one pass of it,
//! and how the step output is built from the settings (at boot and when it is rebuilt at rest).
//!
//! Who uses it: `src/firmware` (USART1 interrupt and `idle`) and `tests/protocol_rig`.

use core::sync::atomic::{AtomicBool, Ordering::Relaxed};

use heapless::spsc::Consumer;

use crate::board::PinMap;
use crate::grbl::controller::{Actions, Controller};
use crate::grbl::settings::Settings;
use crate::motion::burst::Layout;
use crate::motion::timing::dma_fall_ticks;
use crate::grbl::overrides;
use crate::grbl::protocol::{realtime, Realtime};
use crate::grbl::reply::Out;
use crate::motion::shared::Shared;

/// Requests the RX interrupt leaves for the idle loop (lock-free flags).
pub struct Requests {
    status: AtomicBool,
    reset: AtomicBool,
    jog_cancel: AtomicBool,
    /// 0x84 arrived.
    door: AtomicBool,
    /// A door cycle is on: `~` goes to the controller, not straight to the hold.
    door_lock: AtomicBool,
    /// `~` during a door cycle.
    resume: AtomicBool,
}

impl Default for Requests {
    fn default() -> Self {
        Self::new()
    }
}

impl Requests {
    pub const fn new() -> Self {
        Requests {
            status: AtomicBool::new(false),
            reset: AtomicBool::new(false),
            jog_cancel: AtomicBool::new(false),
            door: AtomicBool::new(false),
            door_lock: AtomicBool::new(false),
            resume: AtomicBool::new(false),
        }
    }

}

/// One received byte in the RX interrupt: realtime bytes act at once (feed hold, resume,
/// overrides) or leave a request (`?`, Ctrl-X, 0x85 jog cancel, 0x84 door, `~` in a door
/// cycle); a line byte comes back for
/// the RX ring.
#[inline(never)]
pub fn dispatch<const N: usize>(b: u8, shared: &Shared<N>, req: &Requests) -> Option<u8> {
    match realtime(b) {
        Some(Realtime::Hold) => shared.set_hold(true),
        // During a door cycle the controller decides (the door must be closed first).
        Some(Realtime::Resume) if req.door_lock.load(Relaxed) => req.resume.store(true, Relaxed),
        Some(Realtime::Resume) => shared.set_hold(false),
        Some(Realtime::Door) => req.door.store(true, Relaxed),
        Some(Realtime::Status) => req.status.store(true, Relaxed),
        Some(Realtime::Reset) => req.reset.store(true, Relaxed),
        Some(Realtime::JogCancel) => req.jog_cancel.store(true, Relaxed),
        Some(Realtime::Extended(x)) => shared.set_overrides(overrides::apply(shared.overrides(), x)),
        None => return Some(b),
    }
    None
}

/// One pass of the idle loop: a pending soft reset (dropping the RX bytes before it; the
/// returned `Actions::reset` says it ran), a status request, a jog cancel, line bytes into the
/// controller while it takes them (and the bytes left waiting in the RX ring, for `Bf:`), then
/// its poll.
pub fn idle_step<const N: usize>(
    ctl: &mut Controller<'_, N>,
    rx: &mut Consumer<'_, u8>,
    out: &mut impl Out,
    now_ms: u32,
    req: &Requests,
) -> Actions {
    let reset = req.reset.swap(false, Relaxed);
    if reset {
        // Bytes before the Ctrl-X belong to the old stream.
        while rx.dequeue().is_some() {}
        ctl.soft_reset(out);
    }
    if req.status.swap(false, Relaxed) {
        ctl.status_request();
    }
    if req.jog_cancel.swap(false, Relaxed) {
        ctl.jog_cancel();
    }
    if req.door.swap(false, Relaxed) {
        ctl.door_command();
    }
    if req.resume.swap(false, Relaxed) {
        ctl.cycle_start();
    }
    while let Some(&b) = rx.peek() {
        if !ctl.byte(b, out) {
            break;
        }
        rx.dequeue();
    }
    ctl.set_rx_waiting(rx.len());
    let act = ctl.poll(now_ms, out);
    req.door_lock.store(ctl.door_active(), Relaxed);
    Actions { reset, ..act }
}

/// How the step output is built: the pin map, and in DMA burst mode (`$581`) the buffers'
/// layout and the falling edge's compare value (0 in dual-edge mode).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepOutput<const N: usize> {
    pub pins: PinMap<N>,
    pub burst: Option<(Layout, u32)>,
}

impl<const N: usize> StepOutput<N> {
    /// The output `$0`, `$2`, `$3`, `$580` and `$581` ask for.
    pub fn of(s: &Settings) -> Self {
        let pins = s.pins::<N>();
        let burst = s.dma_burst.then(|| {
            let fall = if pins.dual { 0 } else { dma_fall_ticks(s.timing().pulse_ticks) };
            (Layout::for_pulse(fall), fall)
        });
        StepOutput { pins, burst }
    }
}

/// What the shell samples for one idle pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Inputs {
    /// GPIOA's input register: the limit pins (pulled up; a pressed switch reads 0).
    pub gpioa_idr: u32,
    /// The probe pin reads low (pulled to ground; `$6` not applied).
    pub probe_low: bool,
    /// The safety door input is active (door open).
    pub door_open: bool,
}

/// Hands one idle pass's pin inputs to the controller (limit pins for `Pn:` and homing, the
/// probe and door levels) and the probe level to the engine's probe check (backing up the edge
/// interrupt: contact made between the controller's check and its arming). Call before
/// [`idle_step`] (and the encoder's `Controller::encoder`).
pub fn take_inputs<const N: usize>(ctl: &mut Controller<'_, N>, shared: &Shared<N>, inputs: Inputs) {
    ctl.set_limit_inputs(inputs.gpioa_idr);
    ctl.set_probe_input(inputs.probe_low);
    ctl.set_door_input(inputs.door_open);
    shared.probe_input(inputs.probe_low != ctl.settings().probe_invert);
}
