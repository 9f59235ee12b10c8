//! Endpoint 0: the control requests a host sends a CDC ACM device (USB 2.0 §9.4, CDC PSTN 1.2
//! §6.3), as an explicit state machine over the three stages of a control transfer.
//!
//! Who uses it: the firmware's USB glue, which calls [`Control::setup`], [`Control::out`] and
//! [`Control::in_complete`] on endpoint 0's events and gives it an [`Ep0`] to answer through;
//! `tests/usb_control.rs` drives it as a host does.
//!
//! Answered: GET_DESCRIPTOR (device, configuration, strings 0..2), SET_ADDRESS (applied after
//! the status stage, §9.4.6), SET/GET_CONFIGURATION, GET_STATUS, GET/SET_INTERFACE (alternate
//! setting 0), CLEAR_FEATURE(ENDPOINT_HALT) (no endpoint is ever halted; SET_CONFIGURATION and
//! it restart the endpoints' data toggles at DATA0, §9.1.1.5, §9.4.5), and the CDC requests
//! SET/GET_LINE_CODING (kept and read back, not used: a virtual port has no baud rate),
//! SET_CONTROL_LINE_STATE (DTR) and SEND_BREAK. Anything else (device qualifier, BOS, other
//! strings, SET_FEATURE, unknown requests, a request with a wLength it cannot have) STALLs
//! endpoint 0 until the next SETUP (§9.2.7). No input panics: every slice is taken with
//! `get`.

use core::ops::Range;

use super::descriptors::{BULK_IN_EP, BULK_OUT_EP, CONFIG, DEVICE, EP0_LEN, LANGIDS, MANUFACTURER, NOTIFY_EP, PRODUCT};

/// Endpoint 0 as the control pipe sees it (the firmware's bus, a test's recorder).
pub trait Ep0 {
    /// Loads one IN packet (data, or zero-length for a status stage) on endpoint 0.
    fn write(&mut self, data: &[u8]);
    /// STALLs endpoint 0 both ways (the hardware takes the next SETUP regardless).
    fn stall(&mut self);
    /// Sets the device address.
    fn set_address(&mut self, addr: u8);
    /// Restarts the data toggle of endpoint `addr` (number and direction bit) at DATA0.
    fn clear_toggle(&mut self, addr: u8);
}

/// The data stage of a control read: which bytes of the reply each IN packet carries. The
/// reply is cut to wLength; it ends with a short packet when shorter than wLength, which is a
/// zero-length one when its length is a multiple of the packet size (§5.5.3), and with its
/// last full packet when it is exactly wLength long.
#[derive(Clone, Copy, Debug, Default)]
pub struct Split {
    len: u16,
    sent: u16,
    /// The reply is shorter than wLength: the host waits for a short packet.
    short_end: bool,
    /// The last packet was full (more may follow).
    last_full: bool,
}

impl Split {
    /// A reply of `reply_len` bytes to a request asking for `w_length`.
    pub fn new(reply_len: usize, w_length: u16) -> Split {
        let len = w_length.min(reply_len.min(u16::MAX as usize) as u16);
        Split { len, sent: 0, short_end: len < w_length, last_full: true }
    }

    /// The next packet's bytes of the reply; `None` when the data stage is over.
    pub fn next(&mut self) -> Option<Range<usize>> {
        if self.sent == self.len && !(self.last_full && self.short_end) {
            return None;
        }
        let start = self.sent;
        self.sent = self.len.min(start.saturating_add(EP0_LEN as u16));
        self.last_full = self.sent - start == EP0_LEN as u16;
        Some(start as usize..self.sent as usize)
    }
}

/// Where a control transfer is (each branch names what endpoint 0 waits for).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// Nothing in progress: the next SETUP.
    Idle,
    /// An IN data packet is loaded: its completion sends the next one.
    DataIn,
    /// The data stage of a read is over: the host's zero-length OUT ends it.
    StatusOut,
    /// SET_LINE_CODING's 7 bytes.
    DataOut,
    /// Our zero-length IN is loaded: its completion ends the transfer (and applies an address).
    StatusIn,
}

/// What a request gets.
enum Answer {
    /// These bytes, in a data stage.
    In(&'static [u8]),
    /// The line coding, in a data stage.
    Coding,
    /// A status stage with no data.
    Ack,
    /// A data stage from the host (SET_LINE_CODING).
    Out,
    Stall,
}

/// The line coding a host reads before it sets one: 115 200 baud, 1 stop bit, no parity, 8 bits.
const CODING: [u8; 7] = [0x00, 0xC2, 0x01, 0x00, 0, 0, 8];

/// Endpoint 0's state, the device's configuration and the port's DTR.
pub struct Control {
    stage: Stage,
    reply: &'static [u8],
    /// The reply is the line coding, not `reply`.
    coding_reply: bool,
    split: Split,
    /// SET_ADDRESS's address, applied when its status stage completes.
    address: Option<u8>,
    configured: bool,
    dtr: bool,
    coding: [u8; 7],
}

impl Default for Control {
    fn default() -> Self {
        Self::new()
    }
}

impl Control {
    pub const fn new() -> Self {
        Control {
            stage: Stage::Idle,
            reply: &[],
            coding_reply: false,
            split: Split { len: 0, sent: 0, short_end: false, last_full: false },
            address: None,
            configured: false,
            dtr: false,
            coding: CODING,
        }
    }

    /// A bus reset: address 0 (the hardware's), not configured, port closed.
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// SET_CONFIGURATION(1) came and no reset since.
    pub fn configured(&self) -> bool {
        self.configured
    }

    /// The host's DTR (a program has the port open).
    pub fn dtr(&self) -> bool {
        self.dtr
    }

    /// The line coding last set (dwDTERate, bCharFormat, bParityType, bDataBits).
    pub fn coding(&self) -> [u8; 7] {
        self.coding
    }

    /// A SETUP packet: starts a new transfer (whatever the last one was doing).
    pub fn setup(&mut self, ep: &mut impl Ep0, s: &[u8; 8]) {
        let [request_type, request, v0, v1, i0, _, l0, l1] = *s;
        let length = u16::from_le_bytes([l0, l1]);
        self.stage = Stage::Idle;
        self.address = None;
        self.coding_reply = false;
        let answer = match (request_type, request) {
            // GET_DESCRIPTOR: type in the high byte of wValue, index in the low one.
            (0x80, 6) => match (v1, v0) {
                (1, _) => Answer::In(&DEVICE),
                (2, 0) => Answer::In(&CONFIG),
                (3, 0) => Answer::In(&LANGIDS),
                (3, 1) => Answer::In(&MANUFACTURER),
                (3, 2) => Answer::In(&PRODUCT),
                _ => Answer::Stall,
            },
            // GET_STATUS of the device (bus powered, no remote wakeup), an interface or an
            // endpoint (not halted).
            (0x80..=0x82, 0) => Answer::In(&[0, 0]),
            // GET_CONFIGURATION.
            (0x80, 8) => Answer::In(if self.configured { &[1] } else { &[0] }),
            // SET_ADDRESS (7 bits).
            (0x00, 5) if v0 < 0x80 && v1 == 0 => {
                self.address = Some(v0);
                Answer::Ack
            }
            // SET_CONFIGURATION 0 or 1: the endpoints' toggles restart at DATA0 (§9.1.1.5),
            // also when the host sends it again mid-session (macOS does).
            (0x00, 9) if v0 < 2 && v1 == 0 => {
                ep.clear_toggle(NOTIFY_EP);
                ep.clear_toggle(BULK_OUT_EP);
                ep.clear_toggle(BULK_IN_EP);
                self.configured = v0 == 1;
                self.dtr &= self.configured;
                Answer::Ack
            }
            // GET_INTERFACE, SET_INTERFACE: alternate setting 0 only.
            (0x81, 10) => Answer::In(&[0]),
            (0x01, 11) if v0 == 0 && v1 == 0 => Answer::Ack,
            // CLEAR_FEATURE(ENDPOINT_HALT): the endpoint's toggle restarts at DATA0 (§9.4.5;
            // libusb's clear_halt). Not endpoint 0: its toggles follow the SETUP just taken.
            (0x02, 1) if v0 == 0 && v1 == 0 => {
                if i0 & 0x7F != 0 {
                    ep.clear_toggle(i0);
                }
                Answer::Ack
            }
            // CDC: SET_LINE_CODING, GET_LINE_CODING, SET_CONTROL_LINE_STATE, SEND_BREAK.
            (0x21, 0x20) if length == 7 => Answer::Out,
            (0xA1, 0x21) => Answer::Coding,
            (0x21, 0x22) => {
                self.dtr = v0 & 1 != 0;
                Answer::Ack
            }
            (0x21, 0x23) => Answer::Ack,
            _ => Answer::Stall,
        };
        match answer {
            Answer::In(reply) => self.start_in(ep, reply, false, length),
            Answer::Coding => self.start_in(ep, &[], true, length),
            Answer::Ack if length == 0 => self.ack(ep),
            Answer::Out => self.stage = Stage::DataOut,
            Answer::Ack | Answer::Stall => self.stall(ep),
        }
    }

    /// An OUT packet that is not a SETUP: SET_LINE_CODING's data, or the status stage of a read.
    pub fn out(&mut self, ep: &mut impl Ep0, data: &[u8]) {
        match self.stage {
            Stage::DataOut => match <[u8; 7]>::try_from(data) {
                Ok(coding) => {
                    self.coding = coding;
                    self.ack(ep);
                }
                Err(_) => self.stall(ep),
            },
            // The status stage, or the host ending a read early: done.
            Stage::DataIn | Stage::StatusOut => self.stage = Stage::Idle,
            // (Nothing expected: a stray packet, ignored.)
            Stage::Idle | Stage::StatusIn => {}
        }
    }

    /// The IN packet loaded on endpoint 0 was sent.
    pub fn in_complete(&mut self, ep: &mut impl Ep0) {
        match self.stage {
            Stage::DataIn => self.send_next(ep),
            Stage::StatusIn => {
                if let Some(a) = self.address.take() {
                    ep.set_address(a);
                }
                self.stage = Stage::Idle;
            }
            Stage::Idle | Stage::StatusOut | Stage::DataOut => {}
        }
    }

    // starts a control read's data stage (a status stage alone when wLength is 0)
    fn start_in(&mut self, ep: &mut impl Ep0, reply: &'static [u8], coding: bool, length: u16) {
        if length == 0 {
            self.ack(ep);
            return;
        }
        self.reply = reply;
        self.coding_reply = coding;
        let n = if coding { self.coding.len() } else { reply.len() };
        self.split = Split::new(n, length);
        self.send_next(ep);
    }

    // loads the next IN packet of the reply, or waits for the status stage after the last
    fn send_next(&mut self, ep: &mut impl Ep0) {
        self.stage = match self.split.next() {
            Some(r) => {
                let reply: &[u8] = if self.coding_reply { &self.coding } else { self.reply };
                ep.write(reply.get(r).unwrap_or(&[]));
                Stage::DataIn
            }
            None => Stage::StatusOut,
        };
    }

    // a status stage: a zero-length IN packet
    fn ack(&mut self, ep: &mut impl Ep0) {
        ep.write(&[]);
        self.stage = Stage::StatusIn;
    }

    // a request error: STALL until the next SETUP
    fn stall(&mut self, ep: &mut impl Ep0) {
        ep.stall();
        self.stage = Stage::Idle;
        self.address = None;
    }
}
