//! Soft limits (`$20`): Grbl 1.1's machine travel box.
//!
//! Who uses it: the controller, before it commits a G-code line or a jog. Grbl (without
//! `HOMING_FORCE_SET_ORIGIN`) homes to machine zero and stores the travel as negative, so an
//! axis may go from `-$130+i` to `0` in machine millimetres, whatever the homing direction
//! mask. A G-code target outside is ALARM:2 (the controller stops, flushes and waits for a
//! reset); a jog target outside is `error:15` and nothing changes.

/// True when `target` (machine mm) leaves the box `-travel[i] ..= 0` on one of the first
/// `axes` axes.
pub fn outside<const N: usize>(target: &[f64; N], travel: &[f32], axes: usize) -> bool {
    target.iter().zip(travel).take(axes).any(|(&t, &len)| t > 0.0 || t < -(len as f64))
}

#[cfg(test)]
mod tests {
    use super::outside;

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
