//! DMA1 on the emulated bus: TIM2's requests to channels (RM0008 table 78), each transfer
//! timed with the constants of `dma.rs` and the shared AHB-to-APB bridge, its memory side
//! read from unicorn's SRAM and its peripheral side landed through the same register
//! dispatch as a CPU access. For `mcu.rs` (sync, next event), the block hook in `cpu.rs`
//! and the run loop in `board.rs` (both call [`service`]).
//!
//! Order of events: TIM2 queues a request at its event's cycle r (during `sync`, which the
//! run loop reaches at the first block boundary at or after r: the CPU is stopped at the
//! timer's next event). [`service`] then serves it where the Unicorn handle is: at that block
//! boundary (block hook) or at the top of the run loop's next turn. The memory read sees what
//! the CPU had written by then, i.e. by the end of the instruction running at r (a refill of
//! the half just consumed never races with the half being read). The transfer is timed from
//! r, not from the service: its write lands at r + latency (`Transfer::at`), in `sync`, in
//! cycle order with the CPU's own accesses (a CPU access at cycle c first lands every DMA
//! write due by c). GPIO writes record pin edges (trace, VCD, plant) at the landing cycle,
//! TIM2 writes go through `Timer::write` at that cycle. A landing that falls before the
//! service (the run loop reached r late, e.g. after an exception entry) is applied at once,
//! still stamped with its own cycle.
//!
//! Timing (constants in `dma.rs`). One transfer from memory to an APB register with APB
//! divider d, on an idle bus:
//!   request → [ARBITRATION 1][ADDRESS 1][SRAM read AHB_ACCESS 2][bridge 1 + 2·d] → lands,
//! 7 cycles to a GPIO register (APB2, d = 1) and 9 to TIM2 (APB1, d = 2) at 72 MHz. The steps
//! are those of AN2548 ("Using the STM32F0/F1/F3/Gx/Lx Series DMA controller") §4.1, DMA
//! transfer timing, with the per-step costs ST gives for them (also tabulated in AN4031
//! §3.1, tables 4 and 5): one AHB cycle of request arbitration, one of address computation,
//! then per access one of bus-matrix arbitration plus the slave's (SRAM: one; an APB
//! register: two APB cycles behind the bridge, which is the bench's `memory::bridge_cycles`,
//! 1 + 2·d, as for CPU accesses). The F1's DMA has one AHB master, so arbitration and address
//! are paid once per transfer and transfers of all channels are serialized. The bus-matrix
//! arbitration cycle is counted even without a competing access (AN4031 counts 0 then): one
//! cycle pessimistic. The peripheral side uses the bridge the CPU uses
//! (`Mcu::bridge_free`): CPU peripheral accesses and DMA transfers queue behind each
//! other. Bus cost: the DMA holds the bus matrix for its SRAM access and its bridge transfer,
//! AHB_ACCESS + 1 + 2·d cycles (5 per GPIO write, 7 per TIM2 write); the bench charges all of
//! them to the CPU whenever it is running, none while it sleeps in WFI. That is the
//! pessimistic end: the CPU waits only when it wants the same slave in those cycles, and the
//! round-robin bus matrix keeps at least half the bandwidth for it (RM0008 §13.3). Not
//! checked against silicon.
use unicorn_engine::Unicorn;

use super::mcu::Mcu;
use super::dma::{size_mask, Beat, Transfer, ADDRESS, AHB_ACCESS, ARBITRATION};
use super::memory::{bus_of, Bus};

// DMA1 channel index (0 = channel 1) of a TIM2 request source (`timer::DMA_UP` or CCx = x):
// UP → 2, CH1 → 5, CH2 → 7, CH3 → 1, CH4 → 7 (RM0008 table 78)
pub fn tim2_channel(source: u8) -> Option<usize> {
    match source {
        0 => Some(1),
        1 => Some(4),
        2 | 4 => Some(6),
        3 => Some(0),
        _ => None,
    }
}

// the word a DMA write of `bytes` puts on the bus at `addr`, and the lanes the slave takes:
// byte and half-word data are duplicated on the unused lanes (RM0008 §13.3.4); an APB
// register takes the whole word, an AHB slave only the addressed lanes
fn lanes(addr: u32, bytes: u32, value: u32) -> (u32, u32) {
    let v = value & size_mask(bytes);
    let word = match bytes {
        1 => v * 0x0101_0101,
        2 => v * 0x0001_0001,
        _ => v,
    };
    if bytes >= 4 || bus_of(addr) != Bus::Other {
        (word, u32::MAX)
    } else {
        (word, size_mask(bytes) << ((addr & 3) * 8))
    }
}

impl Mcu {
    // hand the requests TIM2 raised to the DMA controller
    pub(super) fn dma_collect(&mut self) {
        if self.tim2.dma_requests.is_empty() {
            return;
        }
        for (t, source) in std::mem::take(&mut self.tim2.dma_requests) {
            if let Some(x) = tim2_channel(source) {
                self.dma.request(x, t);
            }
        }
    }

    // TIM2's DIER was written: a held request whose enable (UDE, CCxDE) is now clear is
    // withdrawn (assumed: the request line is the event latch AND the enable; TIM2_CH2 and
    // CH4 share channel 7, either enable keeps it)
    pub(super) fn dma_requests_enabled(&mut self) {
        for x in 0..super::dma::CHANNELS {
            let on = (0..=4u8).any(|s| tim2_channel(s) == Some(x) && self.tim2.dier & 1 << (8 + s) != 0);
            if !on {
                self.dma.withdraw(x);
            }
        }
    }

    // land every transfer due by cycle `t`, each at its own cycle
    pub(super) fn dma_land(&mut self, t: u64) {
        while let Some(tr) = self.dma.land(t) {
            self.dma_access(tr);
        }
    }

    // the peripheral side of a transfer, at its landing cycle
    fn dma_access(&mut self, tr: Transfer) {
        let b = tr.beat;
        let word = b.periph & !3;
        let keep = self.first_bsrr; // a DMA write is no store of the step ISR
        if b.to_periph {
            let (v, mask) = lanes(b.periph, b.psize, tr.value);
            self.write_reg(word, v & mask, mask, tr.at, tr.at);
        } else {
            let v = self.read_reg(word, tr.at) >> ((b.periph & 3) * 8) & size_mask(b.psize);
            self.dma.mem_writes.push((b.mem, b.msize, v & size_mask(b.msize)));
        }
        self.first_bsrr = keep;
    }

    // time the transfer `beat` requested at cycle `r` (`value`: the data read from memory)
    // and charge its bus-matrix cycles to the CPU if it is `running`
    pub(super) fn dma_launch(&mut self, r: u64, beat: Beat, value: u32, running: bool) {
        let start = (r + ARBITRATION + ADDRESS).max(self.dma.free);
        // DIR = 1: SRAM read, then the peripheral write; DIR = 0: the other way round.
        let periph_from = if beat.to_periph { start + AHB_ACCESS } else { start };
        let (ack, at) = self.bridge(beat.periph, periph_from).unwrap_or((periph_from, periph_from + AHB_ACCESS));
        self.dma.free = if beat.to_periph { at } else { at + AHB_ACCESS };
        let bus = AHB_ACCESS + (at - ack);
        self.dma.bus_cycles += bus;
        if running {
            self.stall += bus;
            self.dma.stolen += bus;
        }
        self.dma.launch(beat, value, at, ack);
    }
}

// read `bytes` of memory at `addr` (zero-extended; 0 where nothing is mapped)
fn read_mem(uc: &Unicorn<'_, Mcu>, addr: u32, bytes: u32) -> u32 {
    let mut b = [0u8; 4];
    let n = bytes.min(4) as usize;
    if uc.mem_read(addr as u64, &mut b[..n]).is_err() {
        return 0;
    }
    u32::from_le_bytes(b)
}

/// Serve the DMA requests waiting (and write what DIR = 0 transfers read into SRAM); the CPU
/// loses the bus cycles only when `running`. Returns whether anything was done.
pub fn service(uc: &mut Unicorn<'_, Mcu>, running: bool) -> bool {
    if !uc.get_data().dma.needs_service() {
        return false;
    }
    for (addr, bytes, v) in std::mem::take(&mut uc.get_data_mut().dma.mem_writes) {
        let _ = uc.mem_write(addr as u64, &v.to_le_bytes()[..bytes.min(4) as usize]);
    }
    let requests = uc.get_data_mut().dma.take_requests();
    for (r, x) in requests {
        let Some(beat) = uc.get_data_mut().dma.begin(x, r) else { continue };
        let value = if beat.to_periph { read_mem(uc, beat.mem, beat.msize) } else { 0 };
        uc.get_data_mut().dma_launch(r, beat, value, running);
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::gpio::PinEdge;

    #[test]
    fn request_map_and_write_lanes() {
        // RM0008 table 78: TIM2_UP ch2, TIM2_CH1 ch5, TIM2_CH2/CH4 ch7, TIM2_CH3 ch1
        let map: Vec<_> = (0..=5).map(tim2_channel).collect();
        assert_eq!(map, vec![Some(1), Some(4), Some(6), Some(0), Some(6), None]);
        assert_eq!(lanes(0x4000_002C, 2, 0x1_2345), (0x2345_2345, u32::MAX), "APB: duplicated word");
        assert_eq!(lanes(0x4001_0C10, 4, 0x0200_0001), (0x0200_0001, u32::MAX));
        assert_eq!(lanes(0x2000_0002, 2, 0xBEEF), (0xBEEF_BEEF, 0xFFFF_0000), "AHB: addressed lanes");
    }

    // a Mcu with GPIOB PB9 as output, DMA channel `x` (1-based) memory→peripheral to
    // `cpar`, 32 bit, circular, `n` items
    fn mcu(x: u32, cpar: u32, n: u32) -> Mcu {
        let mut m = Mcu::new();
        m.write_reg(0x4001_0C04, 0x4444_4434, u32::MAX, 0, 0); // GPIOB CRH: PB9 output
        m.write_reg(0x4002_1004, 0x400, u32::MAX, 0, 0); // RCC_CFGR: APB1 = HCLK / 2
        let ch = 0x4002_0008 + 0x14 * (x - 1);
        m.write_reg(ch + 4, n, u32::MAX, 0, 0);
        m.write_reg(ch + 8, cpar, u32::MAX, 0, 0);
        m.write_reg(ch, 2 << 10 | 2 << 8 | 1 << 5 | 1 << 4 | 1, u32::MAX, 0, 0);
        m
    }

    fn launch(m: &mut Mcu, x: usize, r: u64, value: u32, running: bool) {
        m.dma.request(x, r);
        for (r, x) in m.dma.take_requests() {
            let beat = m.dma.begin(x, r).expect("channel serves");
            m.dma_launch(r, beat, value, running);
        }
    }

    #[test]
    fn gpio_write_lands_after_latency_and_shares_the_bridge_with_the_cpu() {
        let mut m = mcu(2, 0x4001_0C10, 4);
        // idle bus: arbitration 1 + address 1 + SRAM 2 + APB2 bridge 3
        launch(&mut m, 1, 100, 1 << 9, true);
        assert_eq!(m.dma.next_event(), Some(107));
        m.sync(106);
        assert!(m.edges.is_empty(), "not landed before 107");
        m.sync(110);
        assert_eq!(m.edges, vec![PinEdge { cycle: 107, port: 1, pin: 9, level: true }]);
        assert_eq!((m.dma.bus_cycles, m.dma.stolen, m.stall), (5, 5, 5), "SRAM 2 + bridge 3, charged to the running CPU");
        // a CPU peripheral access holding the bridge until 205 delays the next transfer
        m.bridge_free = 205;
        launch(&mut m, 1, 200, 1 << 25, false);
        assert_eq!((m.dma.stolen, m.bridge_free), (5, 208), "asleep: nothing stolen; bridge busy 205..208");
        m.sync(300);
        assert_eq!(m.edges[1], PinEdge { cycle: 208, port: 1, pin: 9, level: false });
        // ...and a CPU access queues behind a transfer
        launch(&mut m, 1, 400, 1 << 9, false);
        assert_eq!(m.bridge(0x4001_0C10, 405), Some((407, 410)));
    }

    #[test]
    fn tim2_arr_write_goes_through_the_timer_at_its_landing_cycle() {
        let mut m = mcu(1, 0x4000_002C, 2);
        m.write_reg(0x4000_002C, 999, u32::MAX, 0, 0);
        m.write_reg(0x4000_0000, 0x81, u32::MAX, 0, 0); // ARPE | CEN at 0: updates at 1000, ...
        // APB1 at HCLK / 2: bridge 5, so 1 + 1 + 2 + 5
        launch(&mut m, 0, 10, 499, true);
        m.sync(18);
        assert_eq!(m.tim2.read(0x2C, 18), 999, "not yet");
        m.sync(19);
        assert_eq!(m.tim2.read(0x2C, 19), 499);
        assert_eq!(m.dma.bus_cycles, 7);
        m.sync(1000);
        assert_eq!(m.tim2.next_event(), Some(1500), "the preloaded ARR takes effect at the update");
    }

    #[test]
    fn a_request_waits_for_its_disabled_channel_unless_the_timer_withdraws_it() {
        for withdraw in [false, true] {
            let mut m = mcu(2, 0x4001_0C10, 4);
            let ccr2 = 0x4002_001C;
            let ccr = m.dma.read(ccr2 - 0x4002_0000);
            m.write_reg(ccr2, ccr & !1, u32::MAX, 0, 0); // channel 2 off
            m.write_reg(0x4000_002C, 99, u32::MAX, 0, 0);
            m.write_reg(0x4000_000C, 1 << 8, u32::MAX, 0, 0); // UDE
            m.write_reg(0x4000_0000, 1, u32::MAX, 0, 0); // CEN: update at 100
            m.sync(150);
            assert_eq!((m.tim2.updates, m.dma.next_event()), (1, None), "held, not served");
            if withdraw {
                m.write_reg(0x4000_000C, 0, u32::MAX, 150, 150);
            }
            m.write_reg(ccr2, ccr, u32::MAX, 200, 200); // enabled at 200
            let served: Vec<_> = m.dma.take_requests();
            assert_eq!(served, if withdraw { vec![] } else { vec![(200, 1)] });
        }
    }
}
