//! Independent watchdog (RM0008 §19) and the system reset it causes (AIRCR.SYSRESETREQ
//! causes one too, flagged SFTRSTF). For `mcu.rs` and the board.
//!
//! KR: 0xCCCC starts the watchdog (and reloads it), 0xAAAA reloads, 0x5555 unlocks PR and RLR
//! until the next other key. The counter runs from the LSI, modeled at its nominal 40 kHz
//! (silicon: 30–60 kHz), divided by 4 << PR (PR ≥ 6: 256); it counts RLR down to 0 and then
//! resets the MCU. Once started it runs until a reset. SR (update flags) always reads 0: the
//! new prescaler and reload take effect at once.

/// Modeled LSI frequency, Hz.
pub const LSI_HZ: u64 = 40_000;
/// RCC_CSR reset flags: IWDG reset, power-on reset, pin reset; RMVF clears them.
pub const CSR_IWDGRSTF: u32 = 1 << 29;
pub const CSR_SFTRSTF: u32 = 1 << 28;
pub const CSR_PORRSTF: u32 = 1 << 27;
pub const CSR_PINRSTF: u32 = 1 << 26;
pub const CSR_RMVF: u32 = 1 << 24;

#[derive(Clone, Copy, Debug)]
pub struct Iwdg {
    pr: u32,
    rlr: u32,
    unlocked: bool,
    /// Cycle of the last reload while running.
    reloaded: Option<u64>,
}

impl Default for Iwdg {
    fn default() -> Self {
        Self { pr: 0, rlr: 0xFFF, unlocked: false, reloaded: None }
    }
}

impl Iwdg {
    // register read at `offset`
    pub fn read(&self, offset: u32) -> u32 {
        match offset {
            0x04 => self.pr,
            0x08 => self.rlr,
            _ => 0, // KR is write-only, SR: no update pending
        }
    }

    // register write at `offset` at cycle `t`
    pub fn write(&mut self, offset: u32, v: u32, t: u64) {
        match offset {
            0x00 => {
                let key = v & 0xFFFF;
                self.unlocked = key == 0x5555;
                if key == 0xCCCC || (key == 0xAAAA && self.reloaded.is_some()) {
                    self.reloaded = Some(t);
                }
            }
            0x04 if self.unlocked => self.pr = v & 7,
            0x08 if self.unlocked => self.rlr = v & 0xFFF,
            _ => {}
        }
    }

    // modeled cycles of one counter step at `hz` core cycles per second
    fn period(&self, hz: u64) -> u64 {
        let div = (4u64 << self.pr).min(256);
        div * hz / LSI_HZ
    }

    // the cycle at which the counter reaches 0 and resets the MCU (`None`: not running)
    pub fn expires_at(&self, hz: u64) -> Option<u64> {
        self.reloaded.map(|t| t + (self.rlr as u64 + 1) * self.period(hz))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timeout_follows_pr_and_rlr_and_needs_the_unlock_key() {
        let mut w = Iwdg::default();
        assert_eq!(w.expires_at(72_000_000), None);
        w.write(0x04, 2, 0); // locked: ignored
        assert_eq!(w.read(0x04), 0);
        w.write(0x00, 0x5555, 0);
        w.write(0x04, 2, 0);
        w.write(0x08, 624, 0);
        w.write(0x00, 0xAAAA, 0); // not running yet: no effect
        assert_eq!(w.expires_at(72_000_000), None);
        w.write(0x00, 0xCCCC, 1000);
        // 625 counts of 16 LSI periods at 40 kHz = 250 ms = 18 M cycles.
        assert_eq!(w.expires_at(72_000_000), Some(1000 + 18_000_000));
        w.write(0x00, 0xAAAA, 5000);
        assert_eq!(w.expires_at(72_000_000), Some(5000 + 18_000_000));
        w.write(0x08, 1, 6000); // locked again after another key
        assert_eq!(w.read(0x08), 624);
    }
}
