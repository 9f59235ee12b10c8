//! USB CDC ACM on the Blue Pill's own connector (PA11 D−, PA12 D+), beside USART1: the same
//! protocol on both (one RX ring, one TX ring; see `mod.rs` for which port the replies take).
//!
//! Who uses it: `init` (via `setup`) and the USB task in `mod.rs`. The device side is the
//! library's (`ddastep::usb`: descriptors, control requests, the IN packet rule;
//! `ddastep::grbl::packet`: the OUT packet rule); this file moves packets between it and
//! stm32-usbd's register driver (`usb_device::bus::UsbBus`), as usb-device's `UsbDevice::poll`
//! would.
//!
//! - Clock: the HAL sets USBPRE to /1.5 for a 72 MHz PLL from the crystal: 48 MHz (RM0008 §7.2).
//! - Boot: D+ is driven low for 10 ms, so the host sees a detach and enumerates a fresh device
//!   after every reset (the Blue Pill's D+ pull-up R10 is always on).
//! - Receive: an OUT packet is read only when the last one's line bytes are all in the RX ring;
//!   until then the USB interrupt is masked (a CTR_RX that is not read stays set and would
//!   re-enter the handler forever) and `idle` unmasks it after each pass, while the hardware
//!   NAKs the host's next packet. No byte is dropped.
//! - Transmit: at most one IN packet in flight, filled from the TX ring when the port is open
//!   and the last one completed (`ddastep::usb::bulk_in`).

use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicBool, Ordering::Relaxed};

use ddastep::grbl::packet::Held;
use ddastep::num::wrapping_diff;
use ddastep::usb::bulk_in::InPacket;
use ddastep::usb::control::{Control, Ep0};
use ddastep::usb::descriptors::{BULK_IN_EP, BULK_LEN, BULK_OUT_EP, EP0_LEN, NOTIFY_EP, NOTIFY_LEN};
use heapless::spsc::{Consumer, Producer};
use stm32f1xx_hal::gpio::{gpioa::PA12, Cr, Floating, Input};
use stm32f1xx_hal::pac;
use stm32f1xx_hal::usb::{Peripheral, UsbBusType};
use usb_device::bus::{PollResult, UsbBus as _};
use usb_device::endpoint::{EndpointAddress, EndpointType};
use usb_device::UsbDirection;

/// The vector of the USB low-priority interrupt (RM0008 Table 63: CTR, RESET, SUSP, WKUP).
pub const IRQ: pac::Interrupt = pac::Interrupt::USB_LP_CAN_RX0;

/// D+ held low at boot: 10 ms at 72 MHz on the DWT cycle counter (a host sees a detach after
/// 2.5 µs of SE0, USB 2.0 §7.1.7.3; 10 ms is what the Blue Pill examples use). Counted, not
/// `asm::delay`: with the flash wait states its loop takes several times its nominal cycles
/// (50 ms on the bench's model), which delayed the banner as much.
const DETACH_CYCLES: i32 = 72_000_000 / 100;

/// Endpoint 0's two directions (as `EndpointAddress::from` takes them).
const EP0_OUT: u8 = 0x00;
const EP0_IN: u8 = 0x80;

/// An OUT packet's line bytes wait for room: the USB interrupt is masked until `idle` retries.
pub static HELD: AtomicBool = AtomicBool::new(false);

/// Pulls D+ low for 10 ms (the host sees the device leave), then lets the pull-up take it
/// (after `dwt::start_cycle_counter`).
pub fn detach(pa12: PA12<Input<Floating>>, crh: &mut Cr<'A', true>) -> PA12<Input<Floating>> {
    let dp = pa12.into_push_pull_output(crh);
    let start = super::dwt::cycles();
    while wrapping_diff(super::dwt::cycles(), start) < DETACH_CYCLES {}
    dp.into_floating_input(crh)
}

/// What one run of the USB task found.
pub struct Event {
    /// DTR rose: a sender opened the port (send the banner, replies go here).
    pub opened: bool,
    /// Not configured (cable pulled, bus reset, suspend) or DTR fell: replies go to USART1.
    pub gone: bool,
}

/// Endpoint 0 through the register driver.
struct Port<'a>(&'a UsbBusType);

impl Ep0 for Port<'_> {
    fn write(&mut self, data: &[u8]) {
        // (After a SETUP or an IN completion the endpoint is NAKing: the write is taken.)
        let _ = self.0.write(EndpointAddress::from(EP0_IN), data);
    }

    fn stall(&mut self) {
        self.0.set_stalled(EndpointAddress::from(EP0_IN), true);
        self.0.set_stalled(EndpointAddress::from(EP0_OUT), true);
    }

    fn set_address(&mut self, addr: u8) {
        self.0.set_device_address(addr);
    }

    fn clear_toggle(&mut self, addr: u8) {
        self.0.clear_toggle(EndpointAddress::from(addr));
    }
}

/// The CDC ACM device and its packet state.
pub struct Usb {
    bus: UsbBusType,
    ctl: Control,
    held: Held,
    tx: InPacket,
    suspended: bool,
    /// DTR as last seen (for its edges).
    dtr: bool,
}

impl Usb {
    /// Builds the device in `slot` (in `init`, before interrupts; once): its endpoints in the
    /// packet memory, then the peripheral on. In place and in a frame of its own (`init`'s
    /// frame is the stack's peak).
    #[inline(never)]
    pub fn init(slot: &'static mut MaybeUninit<Usb>, usb: Peripheral) -> &'static mut Usb {
        let mut bus = UsbBusType::new_bare(usb);
        // (Fixed addresses and sizes that fit the 512-byte packet memory: never an error.)
        for (dir, addr, kind, len, interval) in [
            (UsbDirection::Out, EP0_OUT, EndpointType::Control, EP0_LEN, 0),
            (UsbDirection::In, EP0_IN, EndpointType::Control, EP0_LEN, 0),
            (UsbDirection::In, NOTIFY_EP, EndpointType::Interrupt, NOTIFY_LEN, 255),
            (UsbDirection::Out, BULK_OUT_EP, EndpointType::Bulk, BULK_LEN, 0),
            (UsbDirection::In, BULK_IN_EP, EndpointType::Bulk, BULK_LEN, 0),
        ] {
            let _ = bus.alloc_ep(dir, Some(EndpointAddress::from(addr)), kind, len as u16, interval);
        }
        bus.enable();
        slot.write(Usb { bus, ctl: Control::new(), held: Held::new(), tx: InPacket::new(), suspended: false, dtr: false })
    }

    /// Takes the bus event (reset, suspend, resume, endpoint 0's packets); notes DTR's edges.
    pub fn poll(&mut self) -> Event {
        match self.bus.poll() {
            PollResult::Reset => {
                self.bus.reset();
                self.ctl.reset();
                self.tx = InPacket::new();
                self.suspended = false;
            }
            PollResult::Suspend => {
                self.bus.suspend();
                self.suspended = true;
            }
            PollResult::Resume => {
                self.bus.resume();
                self.suspended = false;
            }
            PollResult::Data { ep_out, ep_in_complete, ep_setup } => {
                if ep_in_complete & 1 << (BULK_IN_EP & 0x7F) != 0 {
                    self.tx.complete();
                }
                let port = &mut Port(&self.bus);
                // The last IN's completion first: a SETUP in the same poll starts a new transfer.
                if ep_in_complete & 1 != 0 {
                    self.ctl.in_complete(port);
                }
                let mut packet = [0u8; EP0_LEN];
                if ep_out & 1 != 0 {
                    if let Ok(n) = self.bus.read(EndpointAddress::from(EP0_OUT), &mut packet) {
                        let data = packet.get(..n).unwrap_or(&[]);
                        match <&[u8; 8]>::try_from(data) {
                            Ok(setup) if ep_setup & 1 != 0 => self.ctl.setup(port, setup),
                            _ => self.ctl.out(port, data),
                        }
                    }
                }
            }
            PollResult::None => {}
        }
        let configured = self.ctl.configured() && !self.suspended;
        let dtr = configured && self.ctl.dtr();
        let opened = dtr && !self.dtr;
        let gone = !configured || (self.dtr && !dtr);
        self.dtr = dtr;
        Event { opened, gone }
    }

    /// Moves held line bytes into the RX ring, then reads the next OUT packet if nothing is
    /// held (its realtime bytes act through `dispatch`). Masks the interrupt while bytes wait.
    /// True when the packet read held line bytes.
    pub fn receive(&mut self, rx: &mut Producer<'_, u8>, dispatch: impl FnMut(u8) -> Option<u8>) -> bool {
        let mut read = false;
        if self.held.flush(rx) {
            let mut packet = [0u8; BULK_LEN];
            if let Ok(n) = self.bus.read(EndpointAddress::from(BULK_OUT_EP), &mut packet) {
                self.held.take(packet.get(..n).unwrap_or(&[]), dispatch);
                read = !self.held.is_empty();
                self.held.flush(rx);
            }
        }
        let held = !self.held.is_empty();
        HELD.store(held, Relaxed);
        if held {
            cortex_m::peripheral::NVIC::mask(IRQ);
        }
        read
    }

    /// Sends the next IN packet from the TX ring if the endpoint is free (call only while the
    /// replies go to USB).
    pub fn send(&mut self, tx: &mut Consumer<'_, u8>) {
        if !self.ctl.configured() || self.suspended {
            return;
        }
        let mut packet = [0u8; BULK_LEN];
        if let Some(n) = self.tx.next(tx, &mut packet) {
            // (The endpoint is free: its last IN completed or it was reset. Never refused.)
            let _ = self.bus.write(EndpointAddress::from(BULK_IN_EP), packet.get(..n).unwrap_or(&[]));
        }
    }
}

/// Lets the USB interrupt run again (from `idle`, after a pass took bytes from the RX ring):
/// a held packet is retried at once (its CTR_RX is still pending).
pub fn retry() {
    // SAFETY: RTIC's locks on this target raise BASEPRI and never mask vectors in the NVIC,
    // so unmasking cannot break a critical section; the USB task masked it itself.
    unsafe { cortex_m::peripheral::NVIC::unmask(IRQ) };
}
