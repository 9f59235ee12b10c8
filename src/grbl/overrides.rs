//! Grbl 1.1's override realtime bytes (0x90–0x9D): how each changes the override percentages
//! the engine's shared state holds.
//!
//! Who uses it: the shell's realtime dispatch (`grbl::shell::dispatch`).

use crate::motion::moves::Overrides;

/// The overrides `o` after one Grbl 1.1 override byte `b` (0x90–0x9D; others change nothing):
/// feed and spindle 100 % / ±10 / ±1 within 10–200 %, rapid 100, 50 or 25 %.
pub fn apply(mut o: Overrides, b: u8) -> Overrides {
    let step = |v: u8, d: i16| (v as i16 + d).clamp(10, 200) as u8;
    match b {
        0x90 => o.feed = 100,
        0x91 => o.feed = step(o.feed, 10),
        0x92 => o.feed = step(o.feed, -10),
        0x93 => o.feed = step(o.feed, 1),
        0x94 => o.feed = step(o.feed, -1),
        0x95 => o.rapid = 100,
        0x96 => o.rapid = 50,
        0x97 => o.rapid = 25,
        0x99 => o.spindle = 100,
        0x9A => o.spindle = step(o.spindle, 10),
        0x9B => o.spindle = step(o.spindle, -10),
        0x9C => o.spindle = step(o.spindle, 1),
        0x9D => o.spindle = step(o.spindle, -1),
        _ => {}
    }
    o
}
