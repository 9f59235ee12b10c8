//! The receive side of a packet port (USB CDC's bulk OUT endpoint): realtime bytes taken out of
//! each packet as it is read, line bytes into the RX ring with no byte ever dropped.
//!
//! Who uses it: the firmware's USB task (`src/firmware/usb.rs`) and `tests/packet_props.rs`.
//! The USART's interrupt feeds the same RX ring through the same per-byte dispatch
//! ([`crate::grbl::shell::dispatch`]), so both ports reach the same protocol.
//!
//! Flow control (the invariant): the next OUT packet is read only when nothing is held, and a
//! packet's line bytes enter the RX ring only all together, when the ring has room for all of
//! them. Until then they are held here and the endpoint is left unread, so the hardware NAKs
//! the host's next packet and the host retries it: a full ring delays bytes, it never drops
//! them (a UART can only drop them). Realtime bytes (`?` `!` `~` Ctrl-X, 0x80–0xFF) of a packet
//! that was read act at once, also when its line bytes have to wait, as in Grbl's receive
//! interrupt.

use heapless::spsc::Producer;

/// The largest packet read: the CDC data endpoints' size (full speed's largest bulk packet).
pub const PACKET_LEN: usize = crate::usb::descriptors::BULK_LEN;

/// Line bytes of the last packet read, waiting for room in the RX ring.
pub struct Held {
    bytes: [u8; PACKET_LEN],
    len: usize,
}

impl Default for Held {
    fn default() -> Self {
        Self::new()
    }
}

impl Held {
    pub const fn new() -> Self {
        Held { bytes: [0; PACKET_LEN], len: 0 }
    }

    /// Nothing is held: the next OUT packet may be read (otherwise leave it NAKing).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Takes a packet just read (call only when [`Self::is_empty`]): `dispatch` acts on each
    /// realtime byte at once and returns the line bytes, which are kept in order.
    pub fn take(&mut self, packet: &[u8], mut dispatch: impl FnMut(u8) -> Option<u8>) {
        for &b in packet {
            if let Some(b) = dispatch(b) {
                // (`get_mut`: a packet longer than PACKET_LEN cannot come from the endpoint; no
                // panic path either way.)
                if let Some(slot) = self.bytes.get_mut(self.len) {
                    *slot = b;
                    self.len += 1;
                }
            }
        }
    }

    /// Moves the held bytes into the RX ring if it has room for all of them; true when nothing
    /// is held afterwards (the next packet may be read).
    pub fn flush(&mut self, rx: &mut Producer<'_, u8>) -> bool {
        if rx.capacity() - rx.len() < self.len {
            return false;
        }
        for &b in &self.bytes[..self.len] {
            // (Room was checked: never fails.)
            let _ = rx.enqueue(b);
        }
        self.len = 0;
        true
    }
}
