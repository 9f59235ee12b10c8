//! DMA1 (RM0008 §13): seven channels, each moving one data item between memory and a
//! peripheral register per peripheral request (here TIM2's requests, RM0008 table 78; see
//! `dma_run.rs`). This file is the register file and the per-transfer bookkeeping;
//! `dma_run.rs` times each transfer on the bus, reads its memory side from unicorn and lands
//! its peripheral side. For `mcu.rs` (registers, interrupt lines) and the run loop.
//!
//! Registers: ISR (read-only), IFCR (write 1 to clear; CGIFx clears all four flags of
//! channel x), and per channel x at 0x08 + 0x14·(x−1): CCR (EN, TCIE, HTIE, TEIE, DIR, CIRC,
//! PINC, MINC, PSIZE, MSIZE, PL; MEM2MEM is stored but memory-to-memory transfers are not
//! modeled), CNDTR (16 bit, written only while EN = 0, reads the current count), CPAR, CMAR.
//!
//! Semantics: a request on an enabled channel with CNDTR > 0 moves one item: read MSIZE
//! (DIR = 1) from CMAR (+ offset if MINC), write it to CPAR (+ offset if PINC), zero-extended
//! or truncated to PSIZE (RM0008 table 79); DIR = 0 the other way. CNDTR counts the
//! transfer when the DMA takes the request (a few cycles before the data lands). HTIF is set
//! when the remaining count reaches half the programmed count, TCIF at 0; in circular mode
//! the count and addresses reload, otherwise the channel stops serving requests. GIFx is the
//! OR of the channel's flags; the interrupt line of channel x (IRQ 10 + x) is its flags AND
//! its enables. Flags are set when the transfer lands. TEIF is never set (no bus errors).
//!
//! Requests (RM0008 §13.3.1, request/acknowledge): a peripheral holds its request until the
//! DMA acknowledges it, so a request that finds its channel disabled (or its count at 0)
//! waits and is served when the channel is enabled (unless the peripheral withdraws it first:
//! for TIM2, clearing the DIER enable). A request that arrives before the
//! channel's previous one was acknowledged merges with it: it is lost, and counted.
//! Overruns ([`Dma::overruns`], added to `Board::overruns()`): those merged requests, plus
//! every HTIF/TCIF set again while still set with its interrupt enabled (the firmware did
//! not serve the half-transfer in time).
//!
//! Timing and bus cost: the constants below, applied and explained in `dma_run.rs`.

use std::collections::VecDeque;

/// DMA1 channels.
pub const CHANNELS: usize = 7;
/// IRQ of channel 1 (DMA1_Channel1); channel x raises IRQ 10 + x.
pub const IRQ_CHANNEL1: u32 = 11;
/// Request arbitration: one AHB cycle (AN2548 §4.1; see `dma_run.rs`).
pub const ARBITRATION: u64 = 1;
/// Address computation: one AHB cycle (AN2548 §4.1).
pub const ADDRESS: u64 = 1;
/// One access to SRAM (or another AHB slave) through the bus matrix: bus-matrix arbitration
/// 1 + the access 1 AHB cycle. APB registers cost `memory::bridge_cycles` instead.
pub const AHB_ACCESS: u64 = 2;

const EN: u32 = 1;
const DIR: u32 = 1 << 4;
const CIRC: u32 = 1 << 5;
const PINC: u32 = 1 << 6;
const MINC: u32 = 1 << 7;
/// ISR flag bits of one channel (shifted by 4·(x−1)); TCIF/HTIF/TEIF sit where CCR has
/// TCIE/HTIE/TEIE.
pub const GIF: u32 = 1;
pub const TCIF: u32 = 2;
pub const HTIF: u32 = 4;
const TEIF: u32 = 8;

/// One channel's registers and transfer state.
#[derive(Clone, Copy, Debug, Default)]
pub struct Channel {
    pub ccr: u32,
    /// Current count (CNDTR) and the programmed one it reloads from.
    pub cndtr: u32,
    reload: u32,
    pub cpar: u32,
    pub cmar: u32,
    /// Transfers since the channel was enabled or reloaded: the address offset.
    done: u32,
    /// A request waits for the channel to be enabled.
    latched: bool,
    /// Cycle at which the DMA acknowledged the channel's last request.
    ack: u64,
}

impl Channel {
    fn can_transfer(&self) -> bool {
        self.ccr & EN != 0 && self.cndtr > 0
    }
}

/// What one transfer moves (sizes in bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Beat {
    /// Channel index (0 = channel 1).
    pub ch: usize,
    pub mem: u32,
    pub msize: u32,
    pub periph: u32,
    pub psize: u32,
    /// DIR = 1: memory to peripheral.
    pub to_periph: bool,
    /// HTIF/TCIF the transfer sets when it lands.
    pub flags: u32,
}

/// A transfer on its way: the beat, the data read from memory (DIR = 1) and the cycle its
/// peripheral access completes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Transfer {
    pub beat: Beat,
    pub value: u32,
    pub at: u64,
}

/// DMA1: registers, requests waiting for the run loop, transfers in flight, counters.
#[derive(Default)]
pub struct Dma {
    pub ch: [Channel; CHANNELS],
    isr: u32,
    /// Requests taken from the peripherals, not yet served: (cycle, channel index).
    queue: Vec<(u64, usize)>,
    inflight: VecDeque<Transfer>,
    /// The DMA's AHB master is busy until this cycle.
    pub free: u64,
    /// Data items moved per channel.
    pub transfers: [u64; CHANNELS],
    /// HTIF/TCIF set again while set with the interrupt enabled.
    pub flag_overruns: u64,
    /// Requests lost because the channel's previous one was not yet acknowledged.
    pub merged: u64,
    /// Bus-matrix cycles of all transfers, and the part charged to the running CPU.
    pub bus_cycles: u64,
    pub stolen: u64,
    /// SRAM writes of DIR = 0 transfers, for the run loop: (address, bytes, value).
    pub mem_writes: Vec<(u32, u32, u32)>,
}

// bytes of a PSIZE/MSIZE field (the reserved 11 reads as 32 bit)
fn size(field: u32) -> u32 {
    1 << (field & 3).min(2)
}

// mask of the low `bytes` bytes
pub fn size_mask(bytes: u32) -> u32 {
    if bytes >= 4 {
        u32::MAX
    } else {
        (1 << (8 * bytes)) - 1
    }
}

impl Dma {
    // register read at `offset`
    pub fn read(&self, offset: u32) -> u32 {
        match offset {
            0x00 => self.isr,
            0x08..=0x8F => {
                let c = &self.ch[((offset - 0x08) / 0x14) as usize];
                match (offset - 0x08) % 0x14 {
                    0x0 => c.ccr,
                    0x4 => c.cndtr,
                    0x8 => c.cpar,
                    0xC => c.cmar,
                    _ => 0,
                }
            }
            _ => 0, // IFCR reads 0
        }
    }

    // register write at `offset` at cycle `t`
    pub fn write(&mut self, offset: u32, value: u32, t: u64) {
        match offset {
            0x04 => {
                for x in 0..CHANNELS {
                    let bits = value >> (4 * x) & 0xF;
                    let clear = if bits & GIF != 0 { 0xF } else { bits };
                    self.isr &= !(clear << (4 * x));
                    let left = self.isr >> (4 * x) & (TCIF | HTIF | TEIF);
                    if left == 0 {
                        self.isr &= !(GIF << (4 * x));
                    }
                }
            }
            0x08..=0x8F => {
                let x = ((offset - 0x08) / 0x14) as usize;
                let c = &mut self.ch[x];
                match (offset - 0x08) % 0x14 {
                    0x0 => {
                        let enable = value & EN != 0 && c.ccr & EN == 0;
                        c.ccr = value & 0x7FFF;
                        if enable {
                            c.done = 0;
                            if c.latched && c.can_transfer() {
                                c.latched = false;
                                self.queue.push((t, x));
                            }
                        }
                    }
                    0x4 if c.ccr & EN == 0 => {
                        c.cndtr = value & 0xFFFF;
                        c.reload = c.cndtr;
                    }
                    0x8 => c.cpar = value,
                    0xC => c.cmar = value,
                    _ => {}
                }
            }
            _ => {} // ISR is read-only
        }
    }

    // a peripheral request for channel index `x` at cycle `t`
    pub fn request(&mut self, x: usize, t: u64) {
        if self.ch[x].can_transfer() {
            self.queue.push((t, x));
        } else {
            self.ch[x].latched = true;
        }
    }

    // the peripheral no longer requests on channel `x`: a held request is dropped
    pub fn withdraw(&mut self, x: usize) {
        self.ch[x].latched = false;
    }

    // the waiting requests in service order: by cycle, then priority (PL, then channel number)
    pub fn take_requests(&mut self) -> Vec<(u64, usize)> {
        let mut q = std::mem::take(&mut self.queue);
        q.sort_by_key(|&(t, x)| (t, 3 - (self.ch[x].ccr >> 12 & 3), x));
        q
    }

    // does the run loop have work here (requests to serve, memory to write)?
    pub fn needs_service(&self) -> bool {
        !self.queue.is_empty() || !self.mem_writes.is_empty()
    }

    // take the request of channel `x` made at cycle `r`: the item to move, or `None` when the
    // channel cannot serve it (it waits) or it merged with an unacknowledged one
    pub fn begin(&mut self, x: usize, r: u64) -> Option<Beat> {
        let c = &mut self.ch[x];
        if !c.can_transfer() {
            c.latched = true;
            return None;
        }
        if r < c.ack {
            self.merged += 1;
            return None;
        }
        let (msize, psize) = (size(c.ccr >> 10), size(c.ccr >> 8));
        let mem = c.cmar.wrapping_add(if c.ccr & MINC != 0 { c.done * msize } else { 0 });
        let periph = c.cpar.wrapping_add(if c.ccr & PINC != 0 { c.done * psize } else { 0 });
        c.done += 1;
        c.cndtr -= 1;
        let mut flags = 0;
        if c.cndtr == c.reload / 2 {
            flags |= HTIF;
        }
        if c.cndtr == 0 {
            flags |= TCIF;
            if c.ccr & CIRC != 0 {
                c.cndtr = c.reload;
                c.done = 0;
            }
        }
        self.transfers[x] += 1;
        Some(Beat { ch: x, mem, msize, periph, psize, to_periph: c.ccr & DIR != 0, flags })
    }

    // a begun transfer is on its way: it was acknowledged at `ack`, lands at `at`
    pub fn launch(&mut self, beat: Beat, value: u32, at: u64, ack: u64) {
        self.ch[beat.ch].ack = ack;
        self.inflight.push_back(Transfer { beat, value, at });
    }

    // the earliest cycle at which something here is due (a request to serve, a landing)
    pub fn next_event(&self) -> Option<u64> {
        let queued = self.queue.iter().map(|q| q.0).min();
        [queued, self.inflight.front().map(|t| t.at)].into_iter().flatten().min()
    }

    // the next transfer landing by cycle `t`, its flags set
    pub fn land(&mut self, t: u64) -> Option<Transfer> {
        if self.inflight.front()?.at > t {
            return None;
        }
        let tr = self.inflight.pop_front()?;
        let shift = 4 * tr.beat.ch;
        let again = self.isr >> shift & tr.beat.flags & self.ch[tr.beat.ch].ccr;
        self.flag_overruns += again.count_ones() as u64;
        if tr.beat.flags != 0 {
            self.isr |= (tr.beat.flags | GIF) << shift;
        }
        Some(tr)
    }

    // interrupt line of channel index `x`: flags AND enables
    pub fn irq(&self, x: usize) -> bool {
        self.isr >> (4 * x) & self.ch[x].ccr & (TCIF | HTIF | TEIF) != 0
    }

    // overruns so far: merged requests and flags set again while pending
    pub fn overruns(&self) -> u64 {
        self.flag_overruns + self.merged
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CH1: u32 = 0x08;
    // CCR: MSIZE 16, PSIZE 32, MINC, CIRC, DIR, HTIE, TCIE, EN
    const CCR_CIRC: u32 = 1 << 10 | 2 << 8 | MINC | CIRC | DIR | 4 | 2 | EN;

    // serve every waiting request, landing each `lat` cycles after its request
    fn serve(d: &mut Dma, lat: u64) -> Vec<Transfer> {
        let mut out = Vec::new();
        for (r, x) in d.take_requests() {
            if let Some(b) = d.begin(x, r) {
                d.launch(b, 0, r + lat, r + lat - 1);
            }
        }
        while let Some(t) = d.land(u64::MAX) {
            out.push(t);
        }
        out
    }

    #[test]
    fn cndtr_is_written_only_while_disabled_and_reads_the_count() {
        let mut d = Dma::default();
        d.write(CH1 + 4, 0x1_0004, 0);
        assert_eq!(d.read(CH1 + 4), 4, "16 bit");
        d.write(CH1, CCR_CIRC, 0);
        d.write(CH1 + 4, 9, 0);
        assert_eq!(d.read(CH1 + 4), 4, "ignored while EN = 1");
        d.request(0, 10);
        serve(&mut d, 5);
        assert_eq!(d.read(CH1 + 4), 3, "decremented per transfer");
        d.write(CH1, CCR_CIRC & !EN, 20);
        d.write(CH1 + 4, 9, 20);
        assert_eq!(d.read(CH1 + 4), 9);
    }

    #[test]
    fn half_and_complete_flags_circular_reload_and_addresses() {
        let mut d = Dma::default();
        d.write(CH1 + 8, 0x4000_002C, 0); // CPAR = TIM2_ARR
        d.write(CH1 + 0xC, 0x2000_0100, 0); // CMAR
        d.write(CH1 + 4, 4, 0);
        d.write(CH1, CCR_CIRC, 0);
        let mut seen = Vec::new();
        for k in 0..6u64 {
            d.request(0, 100 * k);
            let t = serve(&mut d, 9);
            assert_eq!(t.len(), 1);
            seen.push((t[0].beat.mem, t[0].beat.periph, t[0].beat.flags, d.read(0) & 0xF, d.irq(0)));
            d.write(0x04, 1, 100 * k + 50); // CGIF1 clears all of channel 1
            assert_eq!(d.read(0), 0);
        }
        let ht = HTIF | GIF;
        let tc = TCIF | GIF;
        assert_eq!(
            seen,
            vec![
                (0x2000_0100, 0x4000_002C, 0, 0, false),
                (0x2000_0102, 0x4000_002C, HTIF, ht, true), // MSIZE 16: +2, no PINC
                (0x2000_0104, 0x4000_002C, 0, 0, false),
                (0x2000_0106, 0x4000_002C, TCIF, tc, true),
                (0x2000_0100, 0x4000_002C, 0, 0, false), // reloaded
                (0x2000_0102, 0x4000_002C, HTIF, ht, true),
            ]
        );
        assert_eq!(d.transfers[0], 6);
        assert_eq!(d.overruns(), 0);
    }

    #[test]
    fn ifcr_clears_single_flags_and_gif_follows() {
        let mut d = Dma::default();
        d.write(CH1 + 4, 2, 0);
        d.write(CH1, CCR_CIRC, 0);
        d.request(0, 0);
        d.request(0, 100);
        serve(&mut d, 7);
        assert_eq!(d.read(0) & 0xF, GIF | HTIF | TCIF);
        d.write(0x04, HTIF, 200);
        assert_eq!(d.read(0) & 0xF, GIF | TCIF, "GIF stays while TCIF is set");
        assert!(d.irq(0));
        d.write(0x04, TCIF, 200);
        assert_eq!(d.read(0), 0);
        assert!(!d.irq(0));
        d.write(0x00, 0xFF, 200);
        assert_eq!(d.read(0), 0, "ISR is read-only");
    }

    #[test]
    fn a_flag_set_again_while_pending_with_its_interrupt_on_is_an_overrun() {
        let mut d = Dma::default();
        d.write(CH1 + 4, 2, 0);
        d.write(CH1, CCR_CIRC, 0);
        for k in 0..4 {
            d.request(0, 100 * k);
        }
        serve(&mut d, 7); // HT, TC, HT (again), TC (again): nobody cleared them
        assert_eq!(d.flag_overruns, 2);
        // interrupts off: flags pile up silently
        let mut q = Dma::default();
        q.write(CH1 + 4, 2, 0);
        q.write(CH1, CCR_CIRC & !6, 0);
        for k in 0..4 {
            q.request(0, 100 * k);
        }
        serve(&mut q, 7);
        assert_eq!(q.overruns(), 0);
    }

    #[test]
    fn non_circular_stops_and_a_request_waits_for_enable() {
        let mut d = Dma::default();
        d.write(CH1 + 4, 1, 0);
        d.write(CH1, CCR_CIRC & !CIRC, 0);
        d.request(0, 0);
        d.request(0, 100);
        assert_eq!(serve(&mut d, 7).len(), 1, "the second request finds CNDTR = 0");
        assert_eq!(d.read(CH1 + 4), 0);
        // reprogram: the held request is served when the channel is enabled again
        d.write(CH1, 0, 200);
        d.write(CH1 + 4, 1, 200);
        d.write(CH1, CCR_CIRC & !CIRC, 300);
        let t = serve(&mut d, 7);
        assert_eq!(t.len(), 1);
        assert_eq!(t[0].at, 307, "served at the enable");
    }

    #[test]
    fn a_request_before_the_previous_ack_merges_and_counts() {
        let mut d = Dma::default();
        d.write(CH1 + 4, 8, 0);
        d.write(CH1, CCR_CIRC, 0);
        d.request(0, 100);
        d.request(0, 103); // ack of the first at 100 + 7 - 1
        let t = serve(&mut d, 7);
        assert_eq!(t.len(), 1);
        assert_eq!(d.merged, 1);
        assert_eq!(d.read(CH1 + 4), 7);
    }

    #[test]
    fn priority_orders_simultaneous_requests() {
        let mut d = Dma::default();
        for x in [0usize, 4] {
            d.write(0x08 + 0x14 * x as u32 + 4, 4, 0);
        }
        d.write(0x08, CCR_CIRC, 0); // channel 1, PL low
        d.write(0x08 + 0x14 * 4, CCR_CIRC | 2 << 12, 0); // channel 5, PL high
        d.request(0, 50);
        d.request(4, 50);
        d.request(0, 40);
        let order: Vec<_> = d.take_requests().into_iter().map(|r| r.1).collect();
        assert_eq!(order, vec![0, 4, 0]);
    }
}
