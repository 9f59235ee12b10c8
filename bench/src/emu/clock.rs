//! The emulated core clock. A leaf: every model that turns cycles into time imports it.

/// Core clock: modeled cycles per second.
pub const HZ: u64 = 72_000_000;
