//! TIM3's 16-bit quadrature count, extended to 32 bits, and the speed over a fixed window.
//!
//! Who uses it: the firmware's SysTick task ([`Sampler::sample`] once a millisecond, the
//! result kept in a [`Published`]) and the idle loop ([`Published::count_now`] with a fresh
//! read of TIM3's counter).
//!
//! Invariant: the extended count's low 16 bits equal the counter at the time it was taken, so
//! any later counter value extends it by the signed 16-bit difference ([`extend`]). That is
//! exact while fewer than 32 768 counts pass between two extensions: SysTick extends every
//! millisecond, so up to 32.7 M counts/s, above what TIM3 counts with its input filter
//! (README, "Encoder feedback").

use core::sync::atomic::{AtomicI32, Ordering::Relaxed};

/// Milliseconds of the speed window: the speed is the counts of the last `WINDOW_MS` SysTick
/// samples, so its resolution is `1000 / WINDOW_MS` counts/s and it lags by half the window.
pub const WINDOW_MS: usize = 8;

/// `prev` (an extended count) moved on to the 16-bit counter value `raw`.
pub const fn extend(prev: i32, raw: u16) -> i32 {
    prev.wrapping_add(raw.wrapping_sub(prev as u16) as i16 as i32)
}

/// The SysTick side: extends the counter and keeps the counts of the last [`WINDOW_MS`] ms.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    count: i32,
    ring: [i32; WINDOW_MS],
    at: usize,
}

impl Default for Sampler {
    fn default() -> Self {
        Self::new()
    }
}

impl Sampler {
    /// At counter 0 (TIM3's reset value), standing still.
    pub const fn new() -> Self {
        Sampler { count: 0, ring: [0; WINDOW_MS], at: 0 }
    }

    /// One sample of the counter (call every millisecond): the extended count and the counts
    /// over the last [`WINDOW_MS`] ms.
    pub fn sample(&mut self, raw: u16) -> (i32, i32) {
        self.count = extend(self.count, raw);
        let old = core::mem::replace(&mut self.ring[self.at % WINDOW_MS], self.count);
        self.at = (self.at + 1) % WINDOW_MS;
        (self.count, self.count.wrapping_sub(old))
    }
}

/// The last sample, shared lock-free from SysTick (the only writer) to the idle loop.
#[derive(Debug, Default)]
pub struct Published {
    count: AtomicI32,
    window: AtomicI32,
}

impl Published {
    pub const fn new() -> Self {
        Published { count: AtomicI32::new(0), window: AtomicI32::new(0) }
    }

    /// Stores one [`Sampler::sample`] result.
    pub fn publish(&self, (count, window): (i32, i32)) {
        self.count.store(count, Relaxed);
        self.window.store(window, Relaxed);
    }

    /// The extended count now, from a fresh read `raw` of the counter (taken after this
    /// sample's count: a SysTick in between only moves the base closer).
    pub fn count_now(&self, raw: u16) -> i32 {
        extend(self.count.load(Relaxed), raw)
    }

    /// Counts over the last [`WINDOW_MS`] ms.
    pub fn window(&self) -> i32 {
        self.window.load(Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extends_across_wraps_both_ways() {
        assert_eq!(extend(0, 5), 5);
        assert_eq!(extend(65_530, 4), 65_540);
        assert_eq!(extend(3, 65_534), -2);
        assert_eq!(extend(-70_000, (-70_000i32 + 32_767) as u16), -70_000 + 32_767);
        assert_eq!(extend(-70_000, (-70_000i32 - 32_768) as u16), -70_000 - 32_768);
    }

    #[test]
    fn window_is_counts_of_the_last_ms() {
        let mut s = Sampler::new();
        let mut raw = 0u16;
        for ms in 1..=20 {
            raw = raw.wrapping_add(1000);
            let (count, w) = s.sample(raw);
            assert_eq!(count, ms * 1000);
            assert_eq!(w, 1000 * ms.min(WINDOW_MS as i32));
        }
    }
}
