//! The bulk IN side of the CDC ACM port: up to 64 bytes of the TX ring per packet, one packet
//! in flight, and a zero-length packet after a full one when the ring runs dry, so that a
//! transfer whose length is a multiple of 64 ends (USB 2.0 §5.8.3: the host's read completes
//! on a short packet; without it the last 64 bytes wait for the next reply).
//!
//! Who uses it: the firmware's USB glue (`src/firmware/usb.rs`) and `tests/usb_bulk_in.rs`.

use heapless::spsc::Consumer;

use super::descriptors::BULK_LEN;

/// The IN packet being sent: loaded again until the endpoint takes it.
pub struct InPacket {
    bytes: [u8; BULK_LEN],
    len: usize,
    /// `bytes[..len]` is waiting for the endpoint.
    loaded: bool,
    /// The last packet taken was full: the transfer is not over.
    after_full: bool,
}

impl Default for InPacket {
    fn default() -> Self {
        Self::new()
    }
}

impl InPacket {
    pub const fn new() -> Self {
        InPacket { bytes: [0; BULK_LEN], len: 0, loaded: false, after_full: false }
    }

    /// The packet to write to the IN endpoint: the one not taken yet, else the next bytes of
    /// `tx`, else a zero-length one after a full packet; `None` when there is nothing to send.
    #[inline]
    pub fn next(&mut self, tx: &mut Consumer<'_, u8>) -> Option<&[u8]> {
        if !self.loaded {
            self.len = 0;
            for slot in self.bytes.iter_mut() {
                match tx.dequeue() {
                    Some(b) => *slot = b,
                    None => break,
                }
                self.len += 1;
            }
            if self.len == 0 && !self.after_full {
                return None;
            }
            self.loaded = true;
        }
        self.bytes.get(..self.len)
    }

    /// The endpoint took the packet [`Self::next`] returned.
    pub fn taken(&mut self) {
        self.after_full = self.len == BULK_LEN;
        self.loaded = false;
    }

    /// A bus reset or suspend: nothing is in flight (the bytes of a packet not taken are lost
    /// with the host that was to read them).
    pub fn clear(&mut self) {
        self.loaded = false;
        self.after_full = false;
    }
}
