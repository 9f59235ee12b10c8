//! TIM2 (16-bit general-purpose timer, RM0008 §15) in up-counting mode, evaluated lazily:
//! the state is a counter value at a reference cycle, and `advance(t)` replays the update and
//! compare events up to cycle `t`. For `mcu.rs` (register access) and the run loop (next event).
//!
//! Modeled: CR1 (CEN, UDIS, URS, OPM, ARPE), CR2.CCDS, DIER (UIE, CC1IE..CC4IE, UDE,
//! CC1DE..CC4DE), SR (rc_w0), EGR (UG, CC1G..CC4G), CNT, PSC (preloaded), ARR (preloaded when
//! ARPE), CCR1..4 (preloaded when OCxPE in CCMR1/2). Update event: the counter wraps from ARR
//! to 0. Compare event: CNT becomes CCRx. An event whose flag is still set (and whose
//! interrupt is enabled) counts as an overrun.
//!
//! DMA requests (RM0008 §15.4.4): an update event (not UG when URS = 1) with UDE, and a
//! compare event (or CCxG) with CCxDE, queue `(cycle, source)` in `dma_requests` (source
//! [`DMA_UP`] or 1..=4 for CCx; with CCDS = 1 the CCx requests come with the update event
//! instead). The bus hands them to `dma.rs` at the next sync.

/// Timer register file and lazy counter.
#[derive(Default)]
pub struct Timer {
    pub cr1: u32,
    pub cr2: u32,
    pub dier: u32,
    pub sr: u32,
    pub ccmr: [u32; 2],
    pub ccer: u32,
    psc: u32,
    psc_pre: u32,
    arr: u32,
    arr_pre: u32,
    ccr: [u32; 4],
    ccr_pre: [u32; 4],
    /// Counter value at `base` (after the events of that cycle).
    cnt: u32,
    base: u64,
    /// Update events so far and the cycle of the last one.
    pub updates: u64,
    pub last_update: u64,
    /// Events that found their flag still set.
    pub overruns: u64,
    /// DMA requests raised and not yet taken by the DMA controller: (cycle, source).
    pub dma_requests: Vec<(u64, u8)>,
}

/// DMA request source of the update event (CCx requests are 1..=4).
pub const DMA_UP: u8 = 0;
/// DIER.UDE; CCxDE is `UDE << x`.
const UDE: u32 = 1 << 8;

const UIF: u32 = 1;
const TOP: u32 = 0xFFFF;

impl Timer {
    // a timer in its reset state (ARR = 0xFFFF)
    pub fn new() -> Self {
        Self { arr: TOP, arr_pre: TOP, ..Self::default() }
    }

    fn running(&self) -> bool {
        self.cr1 & 1 != 0
    }

    fn tick(&self) -> u64 {
        self.psc as u64 + 1
    }

    // the cycle of the next update or compare event after `base`, if the counter runs
    pub fn next_event(&self) -> Option<u64> {
        if !self.running() {
            return None;
        }
        let top = if self.cnt <= self.arr { self.arr } else { TOP };
        let mut ticks = (top - self.cnt) as u64 + 1;
        for &c in &self.ccr {
            if c > self.cnt && c <= top {
                ticks = ticks.min((c - self.cnt) as u64);
            }
        }
        Some(self.base + ticks * self.tick())
    }

    // replay all events up to and including cycle `t`
    pub fn advance(&mut self, t: u64) {
        while let Some(te) = self.next_event() {
            if te > t {
                break;
            }
            let top = if self.cnt <= self.arr { self.arr } else { TOP };
            let ticks = (te - self.base) / self.tick();
            let cnt = self.cnt as u64 + ticks;
            self.base = te;
            if cnt > top as u64 {
                self.cnt = 0;
                self.update_event(te, true);
            } else {
                self.cnt = cnt as u32;
                self.compare(self.cnt, te);
            }
        }
        if self.running() && t > self.base {
            let ticks = (t - self.base) / self.tick();
            self.cnt += ticks as u32;
            self.base += ticks * self.tick();
        }
    }

    // counter value at cycle `t` (after `advance(t)`; a cycle before `base` reads as `base`)
    fn count_at(&self, t: u64) -> u32 {
        if !self.running() {
            return self.cnt;
        }
        self.cnt + (t.saturating_sub(self.base) / self.tick()) as u32
    }

    fn set_flag(&mut self, bit: u32) {
        if self.sr & bit != 0 && self.dier & bit != 0 {
            self.overruns += 1;
        }
        self.sr |= bit;
    }

    // compare events of the channels whose CCR equals `cnt`, at cycle `t`
    fn compare(&mut self, cnt: u32, t: u64) {
        for i in 0..4 {
            if self.ccr[i] == cnt {
                self.set_flag(2 << i);
                self.cc_dma(i, t, false);
            }
        }
    }

    // the DMA request of channel `i`'s CCx event at `t` (`on_update`: sent with the update
    // event, CR2.CCDS = 1)
    fn cc_dma(&mut self, i: usize, t: u64, on_update: bool) {
        let ccds = self.cr2 & 8 != 0;
        if self.dier & UDE << (i + 1) != 0 && ccds == on_update {
            self.dma_requests.push((t, i as u8 + 1));
        }
    }

    // update event at cycle `t`: reload preloads; `overflow` = counter wrap (not UG)
    fn update_event(&mut self, t: u64, overflow: bool) {
        if self.cr1 & 2 != 0 {
            return; // UDIS
        }
        self.psc = self.psc_pre;
        self.arr = self.arr_pre;
        for i in 0..4 {
            self.ccr[i] = self.ccr_pre[i];
        }
        if overflow || self.cr1 & 4 == 0 {
            self.set_flag(UIF);
            if self.dier & UDE != 0 {
                self.dma_requests.push((t, DMA_UP));
            }
            for i in 0..4 {
                self.cc_dma(i, t, true);
            }
        }
        if overflow {
            self.updates += 1;
            self.last_update = t;
            if self.cr1 & 8 != 0 {
                self.cr1 &= !1; // one-pulse mode stops the counter
            }
        }
        self.compare(self.cnt, t);
    }

    // true when an enabled interrupt flag is set
    pub fn irq(&self) -> bool {
        self.sr & self.dier & 0x1F != 0
    }

    fn ccr_preloaded(&self, i: usize) -> bool {
        self.ccmr[i / 2] >> (8 * (i % 2)) & 0x8 != 0
    }

    // register read at `offset` at cycle `t`
    pub fn read(&mut self, offset: u32, t: u64) -> u32 {
        let t = t.max(self.base); // a DMA access that lands after the counter was brought on
        self.advance(t);
        match offset {
            0x00 => self.cr1,
            0x04 => self.cr2,
            0x0C => self.dier,
            0x10 => self.sr,
            0x18 => self.ccmr[0],
            0x1C => self.ccmr[1],
            0x20 => self.ccer,
            0x24 => self.count_at(t),
            0x28 => self.psc_pre,
            0x2C => self.arr_pre,
            0x34..=0x40 => self.ccr_pre[(offset as usize - 0x34) / 4],
            _ => 0,
        }
    }

    // register write at `offset` at cycle `t`
    pub fn write(&mut self, offset: u32, value: u32, t: u64) {
        let t = t.max(self.base); // a DMA write that lands after the counter was brought on
        self.advance(t);
        let cnt = self.count_at(t);
        self.cnt = cnt;
        self.base = t;
        match offset {
            0x00 => self.cr1 = value & 0x3FF,
            0x04 => self.cr2 = value,
            0x0C => self.dier = value & 0x5F5F,
            0x10 => self.sr &= value,
            0x14 => {
                if value & 1 != 0 {
                    self.cnt = 0;
                    self.update_event(t, false);
                }
                for i in 0..4 {
                    if value & (2 << i) != 0 {
                        self.set_flag(2 << i);
                        self.cc_dma(i, t, false);
                    }
                }
            }
            0x18 => self.ccmr[0] = value,
            0x1C => self.ccmr[1] = value,
            0x20 => self.ccer = value,
            0x24 => self.cnt = value & TOP,
            0x28 => self.psc_pre = value & TOP,
            0x2C => {
                self.arr_pre = value & TOP;
                if self.cr1 & 0x80 == 0 {
                    self.arr = self.arr_pre;
                }
            }
            0x34..=0x40 => {
                let i = (offset as usize - 0x34) / 4;
                self.ccr_pre[i] = value & TOP;
                if !self.ccr_preloaded(i) {
                    self.ccr[i] = self.ccr_pre[i];
                }
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn update_period_is_arr_plus_one_and_arr_preload_waits_for_update() {
        let mut t = Timer::new();
        t.write(0x2C, 99, 0); // ARR = 99 (no preload yet)
        t.write(0x00, 0x81, 0); // ARPE | CEN
        assert_eq!(t.next_event(), Some(100));
        t.write(0x2C, 49, 10); // preloaded: the period ending at 100 stays
        assert_eq!(t.next_event(), Some(100));
        t.advance(100);
        assert_eq!(t.sr & UIF, UIF);
        assert_eq!(t.next_event(), Some(150));
    }

    #[test]
    fn update_and_compare_raise_dma_requests_ccr1_included() {
        let mut t = Timer::new();
        t.write(0x2C, 99, 0); // ARR = 99: updates at 100, 200, ...
        t.write(0x34, 40, 0); // CCR1 = 40
        t.write(0x3C, 1, 0); // CCR3 = 1: one tick after the update at CNT = 0
        t.write(0x0C, UDE | UDE << 1 | UDE << 3, 0); // UDE | CC1DE | CC3DE, no interrupts
        t.write(0x00, 0x81, 0);
        t.advance(250);
        let expect = vec![(1, 3), (40, 1), (100, DMA_UP), (101, 3), (140, 1), (200, DMA_UP), (201, 3), (240, 1)];
        assert_eq!(t.dma_requests, expect);
        assert!(!t.irq(), "DMA enables raise no interrupt");
        assert_eq!(t.overruns, 0, "flags without interrupt enables are no overruns");
        // CCDS = 1: the CC requests come with the update event instead
        t.dma_requests.clear();
        t.write(0x04, 8, 250);
        t.advance(300);
        assert_eq!(t.dma_requests, vec![(300, DMA_UP), (300, 1), (300, 3)]);
    }
}
