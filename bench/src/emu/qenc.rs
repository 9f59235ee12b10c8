//! TIM3 as a quadrature encoder counter (RM0008 §15.3.12, "Encoder interface mode"): CR1,
//! SMCR, CCMR1, CCER, CNT, ARR; other registers keep what is written. For `mcu.rs`, which
//! hands it every level change of PA6 (TI1) and PA7 (TI2).
//!
//! With CR1.CEN set and SMCR.SMS = 001, 010 or 011 the counter counts the edges of TI1, TI2
//! or both (x4) up or down by RM0008's table 83 (TI1 rising while TI2 is low counts up, and
//! so on; CCER.CC1P/CC2P invert the inputs), wrapping between 0 and ARR. The digital input
//! filter (CCMR1.IC1F/IC2F) is kept but not modeled: the virtual machine's edges are clean
//! and at least its filter time apart. Every read of CNT is timed, so tests can check how
//! often the firmware samples the counter.

/// TIM3's model.
#[derive(Clone, Debug)]
pub struct EncoderTimer {
    cr1: u32,
    smcr: u32,
    pub ccmr1: u32,
    ccer: u32,
    arr: u32,
    cnt: u32,
    /// Registers without a model (what was written).
    other: std::collections::HashMap<u32, u32>,
    /// Counter reads: the last one's cycle and the longest gap between two.
    last_read: Option<u64>,
    pub longest_read_gap: u64,
    pub reads: u64,
    /// Edges counted (up or down).
    pub counted: u64,
}

impl Default for EncoderTimer {
    fn default() -> Self {
        EncoderTimer {
            cr1: 0,
            smcr: 0,
            ccmr1: 0,
            ccer: 0,
            arr: 0xFFFF,
            cnt: 0,
            other: Default::default(),
            last_read: None,
            longest_read_gap: 0,
            reads: 0,
            counted: 0,
        }
    }
}

impl EncoderTimer {
    /// A register read at cycle `t` (offset from TIM3's base).
    pub fn read(&mut self, off: u32, t: u64) -> u32 {
        match off {
            0x00 => self.cr1,
            0x08 => self.smcr,
            0x18 => self.ccmr1,
            0x20 => self.ccer,
            0x24 => {
                if let Some(last) = self.last_read {
                    self.longest_read_gap = self.longest_read_gap.max(t - last);
                }
                self.last_read = Some(t);
                self.reads += 1;
                self.cnt
            }
            0x2C => self.arr,
            _ => self.other.get(&off).copied().unwrap_or(0),
        }
    }

    /// A register write (offset from TIM3's base).
    pub fn write(&mut self, off: u32, v: u32) {
        match off {
            0x00 => self.cr1 = v & 0x3FF,
            0x08 => self.smcr = v & 0xFFF7,
            0x18 => self.ccmr1 = v & 0xFFFF,
            0x20 => self.ccer = v & 0x3333,
            0x24 => self.cnt = v & 0xFFFF,
            0x2C => self.arr = v & 0xFFFF,
            _ => {
                self.other.insert(off, v);
            }
        }
    }

    /// The 16-bit counter.
    pub fn count(&self) -> u16 {
        self.cnt as u16
    }

    /// True in an encoder mode with the counter enabled.
    pub fn counting(&self) -> bool {
        self.cr1 & 1 != 0 && (1..=3).contains(&(self.smcr & 7))
    }

    /// Input `ch` (0: TI1 on PA6, 1: TI2 on PA7) changed to `level`; the other input is at
    /// `other_level`.
    pub fn input(&mut self, ch: usize, level: bool, other_level: bool) {
        let polarity = self.ccer >> (4 * ch + 1) & 1 != 0;
        let ti = level != polarity;
        let sms = self.smcr & 7;
        if !self.counting() || sms & (1 << ch) == 0 {
            return;
        }
        let other_pol = self.ccer >> (4 * (1 - ch) + 1) & 1 != 0;
        let other = other_level != other_pol;
        // Table 83: an edge of TI1 counts up when TI2 differs from TI1's new level; an edge of
        // TI2 counts up when TI1 equals TI2's new level.
        let up = if ch == 0 { other != ti } else { other == ti };
        self.counted += 1;
        self.cnt = match (up, self.cnt) {
            (true, c) if c >= self.arr => 0,
            (true, c) => c + 1,
            (false, 0) => self.arr,
            (false, c) => c - 1,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (A, B) for quadrature state k (A leads B going forward).
    fn ab(k: i64) -> (bool, bool) {
        [(false, false), (true, false), (true, true), (false, true)][k.rem_euclid(4) as usize]
    }

    fn drive(t: &mut EncoderTimer, from: i64, to: i64) {
        let step = if to > from { 1 } else { -1 };
        let mut k = from;
        while k != to {
            let (a0, b0) = ab(k);
            k += step;
            let (a1, b1) = ab(k);
            if a0 != a1 {
                t.input(0, a1, b1);
            }
            if b0 != b1 {
                t.input(1, b1, a1);
            }
        }
    }

    #[test]
    fn x4_counts_every_edge_both_ways_and_wraps() {
        let mut t = EncoderTimer::default();
        drive(&mut t, 0, 8);
        assert_eq!(t.count(), 0, "not counting before CEN and SMS");
        t.write(0x08, 3);
        t.write(0x00, 1);
        drive(&mut t, 8, 18);
        assert_eq!(t.count(), 10);
        drive(&mut t, 18, 5);
        assert_eq!(t.count(), 0xFFFF - 2);
        // CC1P inverts A: the direction flips.
        t.write(0x20, 1 << 1);
        t.write(0x24, 100);
        drive(&mut t, 4, 8);
        assert_eq!(t.count(), 96);
        assert_eq!(t.counted, 10 + 13 + 4);
    }
}
