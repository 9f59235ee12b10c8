//! Float-to-integer conversions, out of line.
//!
//! Who uses it: the settings, G-code, planning and report code (never the step interrupt).
//!
//! Rust's `as` casts from `f64` saturate (NaN → 0, beyond the range → its bound). On the
//! soft-float Cortex-M3 each inline cast is a library call plus two compares and selects
//! (~30 bytes); the thread-mode code converts in a few dozen places, so these keep one copy.
//! Each returns exactly what the `as` cast it replaces returns.

/// `x as u32`.
#[inline(never)]
pub fn u32_of(x: f64) -> u32 {
    x as u32
}

/// `x as u64`.
#[inline(never)]
pub fn u64_of(x: f64) -> u64 {
    x as u64
}

/// `libm::round(x) as u32`.
#[inline(never)]
pub fn round_u32(x: f64) -> u32 {
    libm::round(x) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_as_the_casts() {
        for x in [f64::NAN, f64::NEG_INFINITY, -1.5, -0.4, 0.0, 0.49, 0.5, 1.5, 2.5, 4294967295.4, 4294967295.6, 1e300, f64::INFINITY] {
            assert_eq!(u32_of(x), x as u32);
            assert_eq!(u64_of(x), x as u64);
            assert_eq!(round_u32(x), libm::round(x) as u32);
        }
    }
}
