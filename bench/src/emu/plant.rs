//! The machine around the board: something that watches the output latches and drives input
//! pins back (the virtual machine's carriages and switches, `crate::machine`). For `mcu.rs`,
//! which calls it on every latch change, and the board, which applies what it schedules.

use std::any::Any;

use super::input::InputFlip;

/// A model of what the board's pins are wired to.
pub trait Plant: Send {
    /// Input levels at power-on (pushed as flips at cycle 0 or later).
    fn initial(&mut self, flips: &mut Vec<InputFlip>);
    /// Output latch of GPIO port `port` (0 = A) changed from `old` to `new` at cycle `t`; push
    /// the input changes this causes (at `t` or later).
    fn outputs(&mut self, t: u64, port: u8, old: u32, new: u32, flips: &mut Vec<InputFlip>);
    /// For downcasting to the concrete model.
    fn as_any(&self) -> &dyn Any;
}
