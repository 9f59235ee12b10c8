//! USART1 (RM0008 §27) at the byte level with real byte times: 10 bit times per byte (8N1)
//! at the baud rate set by BRR (f_PCLK2 / BRR). RX bytes come from the host queue at line
//! pace; TX bytes go to the transcript when their stop bit ends. For the bus and the run loop.

use std::collections::VecDeque;

const TXE: u32 = 1 << 7;
const TC: u32 = 1 << 6;
const RXNE: u32 = 1 << 5;
const ORE: u32 = 1 << 3;

/// USART registers, shift registers and host-side queues.
pub struct Usart {
    sr: u32,
    dr_rx: u8,
    brr: u32,
    cr1: u32,
    cr2: u32,
    cr3: u32,
    /// Byte waiting in TDR, and the byte in the TX shift register with its end cycle.
    tdr: Option<u8>,
    tx_shift: Option<(u8, u64)>,
    /// Host bytes not yet on the wire, and the byte on the wire with its end cycle.
    pub rx_queue: VecDeque<u8>,
    rx_wire: Option<(u8, u64)>,
    /// Everything the firmware sent, with the cycle each byte ended.
    pub transcript: Vec<u8>,
    pub tx_times: Vec<u64>,
    pub rx_overruns: u64,
}

impl Default for Usart {
    fn default() -> Self {
        Self {
            sr: TXE | TC,
            dr_rx: 0,
            brr: 0,
            cr1: 0,
            cr2: 0,
            cr3: 0,
            tdr: None,
            tx_shift: None,
            rx_queue: VecDeque::new(),
            rx_wire: None,
            transcript: Vec::new(),
            tx_times: Vec::new(),
            rx_overruns: 0,
        }
    }
}

impl Usart {
    // cycles per byte (start + 8 data + stop) at the programmed baud rate
    pub fn byte_cycles(&self) -> u64 {
        10 * self.brr.max(16) as u64
    }

    fn receiving(&self) -> bool {
        self.cr1 & (1 << 13) != 0 && self.cr1 & (1 << 2) != 0 && self.brr != 0
    }

    // the cycle of the next byte boundary (TX done or RX arrival)
    pub fn next_event(&self) -> Option<u64> {
        let tx = self.tx_shift.map(|(_, end)| end);
        let rx = self.rx_wire.map(|(_, end)| end);
        match (tx, rx) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    // put the next host byte on the wire at cycle `t` if the line is free
    pub fn start_rx(&mut self, t: u64) {
        if self.rx_wire.is_none() && self.receiving() {
            if let Some(b) = self.rx_queue.pop_front() {
                self.rx_wire = Some((b, t + self.byte_cycles()));
            }
        }
    }

    // replay byte boundaries up to cycle `t`
    pub fn advance(&mut self, t: u64) {
        loop {
            if let Some((b, end)) = self.tx_shift {
                if end <= t {
                    self.transcript.push(b);
                    self.tx_times.push(end);
                    self.tx_shift = self.tdr.take().map(|n| (n, end + self.byte_cycles()));
                    self.sr |= TXE;
                    if self.tx_shift.is_none() {
                        self.sr |= TC;
                    }
                    continue;
                }
            }
            if let Some((b, end)) = self.rx_wire {
                if end <= t {
                    self.rx_wire = None;
                    if self.sr & RXNE != 0 {
                        self.sr |= ORE;
                        self.rx_overruns += 1;
                    } else {
                        self.dr_rx = b;
                        self.sr |= RXNE;
                    }
                    self.start_rx(end);
                    continue;
                }
            }
            break;
        }
        self.start_rx(t);
    }

    // interrupt request line
    pub fn irq(&self) -> bool {
        let c = self.cr1;
        (c & (1 << 5) != 0 && self.sr & (RXNE | ORE) != 0)
            || (c & (1 << 7) != 0 && self.sr & TXE != 0)
            || (c & (1 << 6) != 0 && self.sr & TC != 0)
    }

    // register read at `offset` at cycle `t`
    pub fn read(&mut self, offset: u32, t: u64) -> u32 {
        self.advance(t);
        match offset {
            0x00 => self.sr,
            0x04 => {
                self.sr &= !(RXNE | ORE);
                self.dr_rx as u32
            }
            0x08 => self.brr,
            0x0C => self.cr1,
            0x10 => self.cr2,
            0x14 => self.cr3,
            _ => 0,
        }
    }

    // register write at `offset` at cycle `t`
    pub fn write(&mut self, offset: u32, value: u32, t: u64) {
        self.advance(t);
        match offset {
            0x00 => self.sr &= value | !(TC | RXNE),
            0x04 => {
                let b = value as u8;
                self.sr &= !TC;
                if self.tx_shift.is_none() {
                    self.tx_shift = Some((b, t + self.byte_cycles()));
                } else {
                    self.tdr = Some(b);
                    self.sr &= !TXE;
                }
            }
            0x08 => self.brr = value & 0xFFFF,
            0x0C => {
                self.cr1 = value;
                self.start_rx(t);
            }
            0x10 => self.cr2 = value,
            0x14 => self.cr3 = value,
            _ => {}
        }
    }
}
