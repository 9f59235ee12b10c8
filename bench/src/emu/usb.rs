//! The F103's USB full-speed device peripheral (RM0008 §23) at the transaction level: its
//! registers at 0x4000_5C00 (USB_EPnR, CNTR, ISTR, FNR, DADDR, BTABLE), the 512-byte packet
//! memory at 0x4000_6000 seen by the CPU as 16-bit words on a 32-bit stride, the buffer
//! descriptor table in it, and what the hardware does with a SETUP, OUT or IN token (§23.4.2:
//! STAT/DTOG updates, CTR flags, NAK/STALL handshakes). The host that sends the tokens is
//! `usb_host.rs`; the interrupt lines go to the NVIC from `mcu.rs` (USB_LP_CAN1_RX0 = IRQ 20
//! for CTR and the bus events, USB_HP_CAN1_TX = IRQ 19 for CTR of double-buffered and
//! isochronous endpoints).

/// Register block and packet memory (CPU addresses).
pub const REGS: u32 = 0x4000_5C00;
pub const PMA: u32 = 0x4000_6000;
/// Packet memory bytes (256 16-bit words).
pub const PMA_LEN: usize = 512;
/// USB_HP_CAN1_TX and USB_LP_CAN1_RX0 (RM0008 Table 63).
pub const IRQ_HP: u32 = 19;
pub const IRQ_LP: u32 = 20;

// ISTR / CNTR interrupt bits (the same positions in both).
pub const CTR: u16 = 1 << 15;
pub const WKUP: u16 = 1 << 12;
pub const SUSP: u16 = 1 << 11;
pub const RESET: u16 = 1 << 10;
pub const SOF: u16 = 1 << 9;
/// ISTR flags cleared by writing 0 (rc_w0): PMAOVR, ERR, WKUP, SUSP, RESET, SOF, ESOF.
const ISTR_FLAGS: u16 = 0x7F00;
const CNTR_FRES: u16 = 1 << 0;
const CNTR_PDWN: u16 = 1 << 1;

// USB_EPnR fields.
const EP_CTR_RX: u16 = 1 << 15;
const EP_DTOG_RX: u16 = 1 << 14;
const EP_STAT_RX: u16 = 3 << 12;
const EP_SETUP: u16 = 1 << 11;
const EP_TYPE: u16 = 3 << 9;
const EP_KIND: u16 = 1 << 8;
const EP_CTR_TX: u16 = 1 << 7;
const EP_DTOG_TX: u16 = 1 << 6;
const EP_STAT_TX: u16 = 3 << 4;
const EP_EA: u16 = 0xF;
/// Bits a write toggles (writing 1 flips them).
const EP_TOGGLE: u16 = EP_DTOG_RX | EP_STAT_RX | EP_DTOG_TX | EP_STAT_TX;
/// Bits a write sets as written.
const EP_RW: u16 = EP_TYPE | EP_KIND | EP_EA;
const TYPE_CONTROL: u16 = 1 << 9;
const TYPE_ISO: u16 = 2 << 9;
const TYPE_BULK: u16 = 0;

/// STAT_TX / STAT_RX values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stat {
    Disabled,
    Stall,
    Nak,
    Valid,
}

impl Stat {
    fn of(bits: u16) -> Stat {
        [Stat::Disabled, Stat::Stall, Stat::Nak, Stat::Valid][bits as usize & 3]
    }

    /// The handshake of an endpoint direction that does not take the token (None: it does).
    fn refusal(self) -> Option<Handshake> {
        match self {
            Stat::Disabled => Some(Handshake::Timeout),
            Stat::Stall => Some(Handshake::Stall),
            Stat::Nak => Some(Handshake::Nak),
            Stat::Valid => None,
        }
    }
}

/// The device's answer to a token.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Handshake {
    /// Taken (OUT, SETUP) or sent (IN: the data and its DATA0/1 toggle).
    Ack,
    Data(Vec<u8>, bool),
    Nak,
    Stall,
    /// No answer (not powered, address or endpoint not enabled, a SETUP while CTR_RX is
    /// still set): the host times out and retries.
    Timeout,
}

/// The peripheral's registers and packet memory.
pub struct UsbPeripheral {
    ep: [u16; 8],
    cntr: u16,
    istr: u16,
    daddr: u16,
    btable: u16,
    /// Frame number (FNR.FN) and whether SOFs locked it (FNR.LCK).
    pub frame: u16,
    locked: bool,
    pma: [u8; PMA_LEN],
    /// OUT packets ACKed with the wrong DATA0/1 toggle (taken as retransmissions, dropped).
    pub toggle_mismatches: u64,
}

impl Default for UsbPeripheral {
    fn default() -> Self {
        UsbPeripheral { ep: [0; 8], cntr: CNTR_FRES | CNTR_PDWN, istr: 0, daddr: 0, btable: 0, frame: 0, locked: false, pma: [0; PMA_LEN], toggle_mismatches: 0 }
    }
}

impl UsbPeripheral {
    /// Powered and out of reset (CNTR.PDWN and FRES clear).
    pub fn powered(&self) -> bool {
        self.cntr & (CNTR_PDWN | CNTR_FRES) == 0
    }

    /// The endpoint whose CTR the ISTR shows (the lowest), with DIR (1: CTR_RX).
    fn ctr(&self) -> Option<(usize, bool)> {
        self.ep.iter().position(|e| e & (EP_CTR_RX | EP_CTR_TX) != 0).map(|n| (n, self.ep[n] & EP_CTR_RX != 0))
    }

    /// The low-priority interrupt line: CTR of a single-buffered endpoint, or a bus event,
    /// each gated by its CNTR mask.
    pub fn irq_lp(&self) -> bool {
        let ctr = self.ep.iter().any(|&e| e & (EP_CTR_RX | EP_CTR_TX) != 0 && !Self::high_priority(e));
        (ctr && self.cntr & CTR != 0) || self.istr & self.cntr & ISTR_FLAGS != 0
    }

    /// The high-priority line: CTR of an isochronous or double-buffered bulk endpoint.
    pub fn irq_hp(&self) -> bool {
        self.cntr & CTR != 0 && self.ep.iter().any(|&e| e & (EP_CTR_RX | EP_CTR_TX) != 0 && Self::high_priority(e))
    }

    fn high_priority(e: u16) -> bool {
        e & EP_TYPE == TYPE_ISO || (e & EP_TYPE == TYPE_BULK && e & EP_KIND != 0)
    }

    /// Register read at `offset` from 0x4000_5C00.
    pub fn read(&self, offset: u32) -> u32 {
        (match offset {
            0x00..=0x1C => self.ep[offset as usize / 4],
            0x40 => self.cntr,
            0x44 => {
                let (id, dir) = self.ctr().map_or((0, false), |(n, d)| (n as u16, d));
                let ctr = if self.ctr().is_some() { CTR } else { 0 };
                self.istr & ISTR_FLAGS | ctr | (dir as u16) << 4 | id
            }
            0x48 => self.frame & 0x7FF | (self.locked as u16) << 13,
            0x4C => self.daddr,
            0x50 => self.btable,
            _ => 0,
        }) as u32
    }

    /// Register write at `offset`; `mask` holds the byte lanes written.
    pub fn write(&mut self, offset: u32, value: u32, mask: u32) {
        let v = value as u16;
        let m = mask as u16;
        match offset {
            0x00..=0x1C => {
                let n = offset as usize / 4;
                let old = self.ep[n];
                // Lanes not written act as "no effect": 1 for rc_w0, 0 for toggles, old for rw.
                let v = v & m | (EP_CTR_RX | EP_CTR_TX | old & EP_RW) & !m;
                let ctr = old & v & (EP_CTR_RX | EP_CTR_TX);
                let toggled = (old ^ v) & EP_TOGGLE;
                self.ep[n] = ctr | toggled | old & EP_SETUP | v & EP_RW;
            }
            0x40 => self.cntr = self.cntr & !m | v & m,
            // rc_w0: a 0 clears a flag, a 1 leaves it.
            0x44 => self.istr &= v | !m | !ISTR_FLAGS,
            0x4C => self.daddr = (self.daddr & !m | v & m) & 0xFF,
            0x50 => self.btable = (self.btable & !m | v & m) & 0xFFF8,
            _ => {}
        }
    }

    /// Packet memory read at `offset` from 0x4000_6000: the 16-bit word at PMA byte
    /// `offset / 2` in the low half, 0 in the high half (RM0008 §23.5.3).
    pub fn pma_read(&self, offset: u32) -> u32 {
        let at = (offset as usize / 4) * 2;
        if at + 1 < PMA_LEN {
            u16::from_le_bytes([self.pma[at], self.pma[at + 1]]) as u32
        } else {
            0
        }
    }

    /// Packet memory write at `offset` (the low half-word's lanes only).
    pub fn pma_write(&mut self, offset: u32, value: u32, mask: u32) {
        let at = (offset as usize / 4) * 2;
        if at + 1 < PMA_LEN {
            if mask & 0xFF != 0 {
                self.pma[at] = value as u8;
            }
            if mask & 0xFF00 != 0 {
                self.pma[at + 1] = (value >> 8) as u8;
            }
        }
    }

    fn pma_u16(&self, at: usize) -> u16 {
        let at = at % PMA_LEN & !1;
        u16::from_le_bytes([self.pma[at], self.pma[(at + 1) % PMA_LEN]])
    }

    fn set_pma_u16(&mut self, at: usize, v: u16) {
        let at = at % PMA_LEN & !1;
        self.pma[at] = v as u8;
        self.pma[(at + 1) % PMA_LEN] = (v >> 8) as u8;
    }

    /// Buffer descriptor `n`: (ADDRn_TX, COUNTn_TX, ADDRn_RX, COUNTn_RX) at BTABLE + 8n.
    fn descriptor(&self, n: usize) -> [u16; 4] {
        let at = self.btable as usize + 8 * n;
        [0, 2, 4, 6].map(|o| self.pma_u16(at + o))
    }

    /// The RX buffer size COUNTn_RX allocates (BL_SIZE, NUM_BLOCK).
    fn rx_size(count_rx: u16) -> usize {
        let blocks = (count_rx >> 10 & 0x1F) as usize;
        if count_rx & 0x8000 != 0 {
            (blocks + 1) * 32
        } else {
            blocks * 2
        }
    }

    /// The endpoint register answering `ep` at device address `addr`, if the function is
    /// enabled and that address is its own.
    fn endpoint(&self, addr: u8, ep: u8) -> Option<usize> {
        if !self.powered() || self.daddr & 0x80 == 0 || (self.daddr & 0x7F) as u8 != addr {
            return None;
        }
        self.ep.iter().position(|&e| (e & EP_EA) as u8 == ep)
    }

    /// A bus reset from the host: DADDR and every endpoint disabled, ISTR.RESET set.
    pub fn bus_reset(&mut self) {
        if self.powered() {
            self.ep = [0; 8];
            self.daddr = 0;
            self.istr |= RESET;
        }
    }

    /// A start of frame (FNR counts; ISTR.SOF).
    pub fn sof(&mut self) {
        self.frame = (self.frame + 1) & 0x7FF;
        self.locked = true;
        if self.powered() {
            self.istr |= SOF;
        }
    }

    /// 3 ms with no bus activity (the host gone or suspending): ISTR.SUSP.
    pub fn suspend(&mut self) {
        self.locked = false;
        if self.powered() {
            self.istr |= SUSP;
        }
    }

    /// Bus activity after a suspend: ISTR.WKUP.
    pub fn wakeup(&mut self) {
        if self.powered() {
            self.istr |= WKUP;
        }
    }

    /// A SETUP token and its 8 bytes: always taken by a control endpoint unless its last
    /// reception is not yet read (CTR_RX set: no handshake, the host retries).
    pub fn setup(&mut self, addr: u8, ep: u8, data: &[u8; 8]) -> Handshake {
        let Some(n) = self.endpoint(addr, ep) else { return Handshake::Timeout };
        let e = self.ep[n];
        if e & EP_TYPE != TYPE_CONTROL || Stat::of(e >> 12) == Stat::Disabled || e & EP_CTR_RX != 0 {
            return Handshake::Timeout;
        }
        let [_, _, addr_rx, count_rx] = self.descriptor(n);
        if Self::rx_size(count_rx) < 8 {
            return Handshake::Stall;
        }
        for (i, pair) in data.chunks(2).enumerate() {
            self.set_pma_u16(addr_rx as usize + 2 * i, u16::from_le_bytes([pair[0], pair[1]]));
        }
        self.set_pma_u16(self.btable as usize + 8 * n + 6, count_rx & 0xFC00 | 8);
        // DTOG_TX 1 (the data stage's first IN is DATA1), DTOG_RX 1 after the DATA0 SETUP,
        // both directions NAK until the software decides, SETUP and CTR_RX set.
        let stat_nak = 2 << 12 | 2 << 4;
        self.ep[n] = e & (EP_RW | EP_CTR_TX) | EP_DTOG_TX | EP_DTOG_RX | stat_nak | EP_SETUP | EP_CTR_RX;
        Handshake::Ack
    }

    /// An OUT token and its data packet with toggle `data1`.
    pub fn out(&mut self, addr: u8, ep: u8, data1: bool, data: &[u8]) -> Handshake {
        let Some(n) = self.endpoint(addr, ep) else { return Handshake::Timeout };
        let e = self.ep[n];
        if let Some(h) = Stat::of(e >> 12).refusal() {
            return h;
        }
        let [_, _, addr_rx, count_rx] = self.descriptor(n);
        if data.len() > Self::rx_size(count_rx) {
            return Handshake::Stall; // buffer overrun: STALL, no interrupt (§23.4.2)
        }
        if data1 != (e & EP_DTOG_RX != 0) {
            // A retransmission of a packet already taken: ACKed and dropped.
            self.toggle_mismatches += 1;
            return Handshake::Ack;
        }
        for (i, pair) in data.chunks(2).enumerate() {
            let hi = pair.get(1).copied().unwrap_or(0);
            self.set_pma_u16(addr_rx as usize + 2 * i, u16::from_le_bytes([pair[0], hi]));
        }
        self.set_pma_u16(self.btable as usize + 8 * n + 6, count_rx & 0xFC00 | data.len() as u16);
        self.ep[n] = (e ^ EP_DTOG_RX) & !(EP_STAT_RX | EP_SETUP) | 2 << 12 | EP_CTR_RX;
        Handshake::Ack
    }

    /// An IN token: the packet armed in the endpoint's TX buffer, sent and ACKed by the host.
    pub fn in_(&mut self, addr: u8, ep: u8) -> Handshake {
        let Some(n) = self.endpoint(addr, ep) else { return Handshake::Timeout };
        let e = self.ep[n];
        if let Some(h) = Stat::of(e >> 4).refusal() {
            return h;
        }
        let [addr_tx, count_tx, _, _] = self.descriptor(n);
        let len = (count_tx & 0x3FF) as usize;
        let data: Vec<u8> = (0..len).map(|i| self.pma[(addr_tx as usize + i) % PMA_LEN]).collect();
        let data1 = e & EP_DTOG_TX != 0;
        self.ep[n] = (e ^ EP_DTOG_TX) & !EP_STAT_TX | 2 << 4 | EP_CTR_TX;
        Handshake::Data(data, data1)
    }

    /// The next token on this endpoint would do something the CPU sees (not a NAK).
    pub fn ready(&self, addr: u8, ep: u8, dir_in: bool) -> bool {
        match self.endpoint(addr, ep) {
            Some(n) => {
                let e = self.ep[n];
                Stat::of(if dir_in { e >> 4 } else { e >> 12 }) != Stat::Nak
            }
            None => false,
        }
    }

    /// A SETUP to endpoint 0 at `addr` would be taken now.
    pub fn takes_setup(&self, addr: u8) -> bool {
        self.endpoint(addr, 0).is_some_and(|n| self.ep[n] & EP_CTR_RX == 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn epnr_write_toggles_and_clears_as_rm0008_says() {
        let mut u = UsbPeripheral::default();
        // STAT_TX 00 -> write 11 -> VALID; write 11 again -> back to DISABLED (toggle).
        u.write(0, (3 << 4) | 1, 0xFFFF);
        assert_eq!(u.read(0) as u16 & (EP_STAT_TX | EP_EA), 3 << 4 | 1);
        u.write(0, 3 << 4 | 1, 0xFFFF);
        assert_eq!(u.read(0) as u16 & EP_STAT_TX, 0);
        // CTR bits: writing 1 leaves, writing 0 clears.
        u.ep[0] |= EP_CTR_RX | EP_CTR_TX;
        u.write(0, (EP_CTR_RX | EP_CTR_TX) as u32, 0xFFFF);
        assert_eq!(u.ep[0] & (EP_CTR_RX | EP_CTR_TX), EP_CTR_RX | EP_CTR_TX);
        u.write(0, EP_CTR_TX as u32, 0xFFFF);
        assert_eq!(u.ep[0] & (EP_CTR_RX | EP_CTR_TX), EP_CTR_TX);
    }

    #[test]
    fn pma_is_16_bit_words_on_a_32_bit_stride() {
        let mut u = UsbPeripheral::default();
        u.pma_write(4, 0xBEEF, 0xFFFF);
        assert_eq!(u.pma[2..4], [0xEF, 0xBE]);
        assert_eq!(u.pma_read(4), 0xBEEF);
        assert_eq!(u.pma_read(6), 0xBEEF); // upper half of the word: the same 16-bit cell
    }

    #[test]
    fn out_packet_lands_in_pma_and_naks_until_read() {
        let mut u = UsbPeripheral::default();
        u.cntr = 0;
        u.daddr = 0x80 | 5;
        u.btable = 0;
        // EP1 bulk OUT, RX buffer at 0x40, 64 bytes (BL_SIZE 1, NUM_BLOCK 1).
        u.set_pma_u16(8 + 4, 0x40);
        u.set_pma_u16(8 + 6, 0x8000 | 1 << 10);
        u.ep[1] = 1 | 3 << 12; // EA 1, bulk, STAT_RX VALID, DTOG_RX 0
        assert_eq!(u.out(5, 1, false, b"G1X1\n"), Handshake::Ack);
        assert_eq!(&u.pma[0x40..0x45], b"G1X1\n");
        assert_eq!(u.descriptor(1)[3] & 0x3FF, 5);
        assert!(u.ep[1] & EP_CTR_RX != 0 && u.ep[1] & EP_DTOG_RX != 0);
        assert_eq!(u.out(5, 1, true, b"?"), Handshake::Nak);
        assert_eq!(u.read(0x44) as u16, CTR | 1 << 4 | 1);
    }
}
