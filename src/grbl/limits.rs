//! Soft limits (`$20`): Grbl 1.1's machine travel box.
//!
//! Who uses it: the controller, before it commits a G-code line or a jog. Grbl (without
//! `HOMING_FORCE_SET_ORIGIN`) homes to machine zero and stores the travel as negative, so an
//! axis may go from `-$130+i` to `0` in machine millimetres, whatever the homing direction
//! mask. A G-code target outside is ALARM:2 (the controller stops, flushes and waits for a
//! reset); a jog target outside is `error:15` and nothing changes.

/// Limit pins active (bit i = axis i, X Y Z) from GPIOA's input register: the inputs are
/// pulled up and a switch pulls its pin low (Grbl's wiring); `$5` (`invert`) is for NC
/// switches, whose pin goes high when pressed.
pub fn active_pins(gpioa_idr: u32, invert: bool) -> u8 {
    let mut mask = 0;
    for (i, &pin) in crate::board::LIMIT_PINS[..3].iter().enumerate() {
        let low = gpioa_idr & 1 << pin == 0;
        if low != invert {
            mask |= 1 << i;
        }
    }
    mask
}

/// True when `target` (machine mm) leaves the box `-travel[i] ..= 0` on one of the first
/// `axes` axes.
pub fn outside<const N: usize>(target: &[f32; N], travel: &[f32], axes: usize) -> bool {
    target.iter().zip(travel).take(axes).any(|(&t, &len)| t > 0.0 || t < -len)
}

#[cfg(test)]
mod tests {
    use super::{active_pins, outside};

    #[test]
    fn pins_low_are_active_unless_inverted() {
        // PA0 low, PA1 and PA2 high, other pins ignored.
        let idr = 0b110 | 0xFFF8;
        assert_eq!(active_pins(idr, false), 0b001);
        assert_eq!(active_pins(idr, true), 0b110);
        assert_eq!(active_pins(0xFFFF, false), 0);
    }

    #[test]
    fn box_is_zero_down_to_minus_travel() {
        let travel = [300.0, 200.0, 80.0];
        assert!(!outside(&[0.0, 0.0, 0.0], &travel, 3));
        assert!(!outside(&[-300.0, -200.0, -80.0], &travel, 3));
        assert!(outside(&[0.001, -1.0, -1.0], &travel, 3));
        assert!(outside(&[-1.0, -200.01, -1.0], &travel, 3));
        // Axes beyond the count in use are not checked.
        assert!(!outside(&[-1.0, -1.0, 5.0], &travel, 2));
    }
}
