//! USB CDC ACM on the Blue Pill's own connector (PA11 D−, PA12 D+), beside USART1: the same
//! protocol on both (one RX ring, one TX ring; see `mod.rs` for which port the replies take).
//!
//! Who uses it: `init` (via `setup`) and the USB task in `mod.rs`; the packet rule is the
//! library's (`ddastep::grbl::packet`).
//!
//! - Clock: the HAL sets USBPRE to /1.5 for a 72 MHz PLL from the crystal: 48 MHz (RM0008 §7.2).
//! - Boot: D+ is driven low for 10 ms, so the host sees a detach and enumerates a fresh device
//!   after every reset (the Blue Pill's D+ pull-up R10 is always on).
//! - Receive: an OUT packet is read only when the last one's line bytes are all in the RX ring;
//!   until then the USB interrupt is masked (a CTR_RX that is not read stays set and would
//!   re-enter the handler forever) and `idle` unmasks it after each pass, while the hardware
//!   NAKs the host's next packet. No byte is dropped.
//! - Transmit: at most one IN packet in flight, filled from the TX ring when the port is open.
//! - Class: `CdcAcmClass` (usbd-serial), device class 0x02 with no IAD; the line coding is
//!   accepted and ignored (a virtual port has no baud rate).

use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicBool, Ordering::Relaxed};

use ddastep::grbl::packet::{Held, PACKET_LEN};
use heapless::spsc::{Consumer, Producer};
use stm32f1xx_hal::gpio::{gpioa::PA12, Cr, Floating, Input};
use stm32f1xx_hal::pac;
use stm32f1xx_hal::usb::{Peripheral, UsbBus, UsbBusType};
use usb_device::bus::UsbBusAllocator;
use usb_device::device::{StringDescriptors, UsbDevice, UsbDeviceBuilder, UsbDeviceState, UsbRev, UsbVidPid};
use usbd_serial::{CdcAcmClass, USB_CLASS_CDC};

/// The vector of the USB low-priority interrupt (RM0008 Table 63: CTR, RESET, SUSP, WKUP).
pub const IRQ: pac::Interrupt = pac::Interrupt::USB_LP_CAN_RX0;

/// obdev's shared VID/PID for CDC ACM devices (V-USB `USB-IDs-for-free.txt`: told apart by
/// their manufacturer and product strings).
const VID_PID: UsbVidPid = UsbVidPid(0x16c0, 0x27dd);

/// D+ held low at boot: 10 ms at 72 MHz (a host sees a detach after 2.5 µs of SE0, USB 2.0
/// §7.1.7.3; 10 ms is what the Blue Pill examples use).
const DETACH_CYCLES: u32 = 72_000_000 / 100;

/// An OUT packet's line bytes wait for room: the USB interrupt is masked until `idle` retries.
pub static HELD: AtomicBool = AtomicBool::new(false);

/// Pulls D+ low for 10 ms (the host sees the device leave), then lets the pull-up take it.
pub fn detach(pa12: PA12<Input<Floating>>, crh: &mut Cr<'A', true>) -> PA12<Input<Floating>> {
    let dp = pa12.into_push_pull_output(crh);
    cortex_m::asm::delay(DETACH_CYCLES);
    dp.into_floating_input(crh)
}

/// What one run of the USB task found.
pub struct Event {
    /// DTR rose: a sender opened the port (send the banner, replies go here).
    pub opened: bool,
    /// Not configured (cable pulled, bus reset, suspend) or DTR fell: replies go to USART1.
    pub gone: bool,
}

/// The CDC ACM device and its packet state.
pub struct Usb {
    dev: UsbDevice<'static, UsbBusType>,
    acm: CdcAcmClass<'static, UsbBusType>,
    held: Held,
    /// The IN packet being sent (written again until the endpoint takes it).
    out: [u8; PACKET_LEN],
    out_len: usize,
    /// The last IN packet was full: a zero-length one ends the transfer.
    zlp: bool,
    configured: bool,
    dtr: bool,
}

impl Usb {
    /// Builds the device on the bus in `slot` (in `init`, before interrupts; once). In place
    /// and in a frame of its own: the device is 0.9 KB, and `init`'s frame is the stack's peak.
    #[inline(never)]
    pub fn init(slot: &'static mut MaybeUninit<Usb>, usb: Peripheral) -> &'static mut Usb {
        let bus: &'static UsbBusAllocator<UsbBusType> =
            cortex_m::singleton!(: UsbBusAllocator<UsbBusType> = UsbBus::new(usb)).unwrap_or_else(|| cortex_m::asm::udf());
        let acm = CdcAcmClass::new(bus, PACKET_LEN as u16);
        let strings = StringDescriptors::default().manufacturer("ddastep").product("ddastep Grbl");
        let dev = UsbDeviceBuilder::new(bus, VID_PID)
            .device_class(USB_CLASS_CDC)
            // USB 2.0, as most CDC ACM devices say (usb-device's default 2.1 adds a BOS read).
            .usb_rev(UsbRev::Usb200)
            .strings(&[strings])
            // (One language, fewer than the builder's limit: never an error.)
            .unwrap_or_else(|_| cortex_m::asm::udf())
            .build();
        slot.write(Usb { dev, acm, held: Held::new(), out: [0; PACKET_LEN], out_len: 0, zlp: false, configured: false, dtr: false })
    }

    /// Runs the device's state machine (bus reset, control requests); notes DTR's edges.
    pub fn poll(&mut self) -> Event {
        self.dev.poll(&mut [&mut self.acm]);
        self.configured = self.dev.state() == UsbDeviceState::Configured;
        let dtr = self.configured && self.acm.dtr();
        let opened = dtr && !self.dtr;
        let gone = !self.configured || (self.dtr && !dtr);
        self.dtr = dtr;
        if !self.configured {
            // A bus reset or suspend: nothing in flight any more.
            self.out_len = 0;
            self.zlp = false;
        }
        Event { opened, gone }
    }

    /// Moves held line bytes into the RX ring, then reads the next OUT packet if nothing is
    /// held (its realtime bytes act through `dispatch`). Masks the interrupt while bytes wait.
    /// True when the packet read held line bytes.
    pub fn receive(&mut self, rx: &mut Producer<'_, u8>, dispatch: impl FnMut(u8) -> Option<u8>) -> bool {
        let mut read = false;
        if self.held.flush(rx) {
            let mut packet = [0u8; PACKET_LEN];
            if let Ok(n) = self.acm.read_packet(&mut packet) {
                self.held.take(&packet[..n], dispatch);
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
        if !self.configured {
            return;
        }
        if self.out_len == 0 {
            while self.out_len < PACKET_LEN {
                match tx.dequeue() {
                    Some(b) => {
                        self.out[self.out_len] = b;
                        self.out_len += 1;
                    }
                    None => break,
                }
            }
            if self.out_len == 0 && !self.zlp {
                return;
            }
        }
        if self.acm.write_packet(&self.out[..self.out_len]).is_ok() {
            self.zlp = self.out_len == PACKET_LEN;
            self.out_len = 0;
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
