//! The step engine's fixed periods (timer ticks): the longest one event holds, and the waits
//! while idle or priming a move.
//!
//! Who uses it: both halves of the engine, the DMA burst fill and the TIM2 model.

use crate::TICKS_PER_MS;

/// Longest timer period one tick can set (ARR is 16 bits).
pub const MAX_TICK: u32 = 1 << 16;
/// Period of idle ticks while no move runs (0.5 ms: a new move starts within this).
pub const IDLE_TICKS: u32 = TICKS_PER_MS / 2;
/// Period of the ticks that wait for the ramp half to prime a move (a start from rest, a
/// resume): 50 µs, ample for the ramp interrupt's work.
pub const PRIME_TICKS: u32 = TICKS_PER_MS / 20;
