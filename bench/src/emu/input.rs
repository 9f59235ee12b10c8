//! Input pins driven from outside the firmware: which port, and a scheduled level change.
//! Used by the board's run loop, `mcu.rs` (plant flips) and plants; a leaf.

/// GPIO port of a pin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Port {
    A = 0,
    B = 1,
    C = 2,
    D = 3,
    E = 4,
}

/// An input level change at a modeled cycle.
#[derive(Clone, Copy, Debug)]
pub struct InputFlip {
    pub cycle: u64,
    pub port: Port,
    pub pin: u8,
    pub level: bool,
}
