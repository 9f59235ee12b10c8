//! The bulk IN side of the CDC ACM port: up to 64 bytes of the TX ring per packet, one packet
//! in flight, and a zero-length packet after a full one when the ring runs dry, so that a
//! transfer whose length is a multiple of 64 ends (USB 2.0 §5.8.3: the host's read completes
//! on a short packet; without it the last 64 bytes wait for the next reply).
//!
//! Bytes leave the TX ring only when the endpoint is free (the last packet's IN completion
//! seen), so no copy of a packet is kept here: the packet memory holds the one in flight.
//!
//! Who uses it: the firmware's USB glue (`src/firmware/usb.rs`) and `tests/usb_bulk_in.rs`.

use heapless::spsc::Consumer;

use super::descriptors::BULK_LEN;

/// Whether a packet is in flight and whether the last one was full.
#[derive(Default)]
pub struct InPacket {
    /// A packet is loaded and the host has not taken it yet.
    busy: bool,
    /// The last packet was full: the transfer is not over.
    after_full: bool,
}

impl InPacket {
    pub const fn new() -> Self {
        InPacket { busy: false, after_full: false }
    }

    /// The next packet, into `buf`, when the endpoint is free: the next bytes of `tx`, else a
    /// zero-length one after a full packet. Its length, or `None` when there is nothing to
    /// send (or a packet is still in flight). The caller loads it on the endpoint.
    #[inline]
    pub fn next(&mut self, tx: &mut Consumer<'_, u8>, buf: &mut [u8; BULK_LEN]) -> Option<usize> {
        if self.busy {
            return None;
        }
        let mut len = 0;
        for slot in buf.iter_mut() {
            match tx.dequeue() {
                Some(b) => *slot = b,
                None => break,
            }
            len += 1;
        }
        if len == 0 && !self.after_full {
            return None;
        }
        self.busy = true;
        self.after_full = len == BULK_LEN;
        Some(len)
    }

    /// The host took the packet in flight (the endpoint's IN completion).
    pub fn complete(&mut self) {
        self.busy = false;
    }
}
