//! Random bulk OUT packet lengths for the modeled host (`Board::usb_random_splits`): each
//! packet takes 1..=64 of the bytes written, across write boundaries, so a line can end or
//! start anywhere in a packet. A seed makes a run repeatable. For `usb_host.rs`.

/// The packet length generator (SplitMix64).
#[derive(Clone, Debug)]
pub struct Splits {
    state: u64,
}

impl Splits {
    pub fn new(seed: u64) -> Self {
        Splits { state: seed }
    }

    // the next packet's length, 1..=max
    pub fn next_len(&mut self, max: usize) -> usize {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        1 + (z % max as u64) as usize
    }
}
