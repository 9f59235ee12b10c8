//! Grbl 1.1's override realtime bytes (0x90–0x9D): how each changes the override percentages
//! the engine's shared state holds.
//!
//! Who uses it: the shell's realtime dispatch (`grbl::shell::dispatch`).

use crate::motion::moves::Overrides;

/// The overrides `o` after one Grbl 1.1 override byte `b` (0x90–0x9D; others change nothing):
/// feed and spindle 100 % / ±10 / ±1 within 10–200 %, rapid 100, 50 or 25 %.
pub fn apply(mut o: Overrides, b: u8) -> Overrides {
    match b {
        0x95 => o.rapid = 100,
        0x96 => o.rapid = 50,
        0x97 => o.rapid = 25,
        // Feed (0x90–0x94) and spindle (0x99–0x9D) take the same five bytes: 100 %, +10,
        // −10, +1, −1.
        0x90..=0x94 | 0x99..=0x9D => {
            let v = if b < 0x95 { &mut o.feed } else { &mut o.spindle };
            *v = match [0, 10, -10, 1, -1].get(((b - 0x90) % 9) as usize) {
                Some(&d) if d != 0 => (*v as i16 + d).clamp(10, 200) as u8,
                _ => 100,
            };
        }
        _ => {}
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Grbl's table, byte by byte (the former match), for every override byte and value.
    fn reference(mut o: Overrides, b: u8) -> Overrides {
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

    #[test]
    fn every_byte_acts_as_grbls_table() {
        for b in 0..=255u8 {
            for v in 0..=255u8 {
                let o = Overrides { feed: v, rapid: v, spindle: v.wrapping_add(37) };
                assert_eq!(apply(o, b), reference(o, b), "byte {b:#x} on {v}");
            }
        }
    }
}
