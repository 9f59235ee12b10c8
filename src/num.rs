//! Float-to-integer conversions, out of line.
//!
//! Who uses it: the settings, G-code, planning and report code (never the step interrupt).
//!
//! Rust's `as` casts from `f64` saturate (NaN → 0, beyond the range → its bound). On the
//! soft-float Cortex-M3 each inline cast is a library call plus two compares and selects
//! (~30 bytes); the thread-mode code converts in a few dozen places, so these keep one copy.
//! Each returns exactly what the `as` cast it replaces returns.

/// `x as f64`, out of line: where LLVM sees two widened `f32` compared, it compares them as
/// `f32`, which links the `f32` compare routines (~70 bytes) for one or two call sites.
#[inline(never)]
pub fn f64_of(x: f32) -> f64 {
    x as f64
}

/// `x as f64` for a `u64`: the same correctly rounded value (both halves convert exactly and
/// are summed with one rounding) without the 64-bit conversion routine (~110 bytes).
#[inline(never)]
pub fn f64_of_u64(x: u64) -> f64 {
    ((x >> 32) as u32 as f64) * 4_294_967_296.0 + (x as u32) as f64
}

/// `x as f64` for an `i64`, as [`f64_of_u64`] (the high half signed): no ~150-byte routine.
#[inline(never)]
pub fn f64_of_i64(x: i64) -> f64 {
    ((x >> 32) as i32 as f64) * 4_294_967_296.0 + (x as u32) as f64
}

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

/// `x as i32`.
#[inline(never)]
pub fn i32_of(x: f64) -> i32 {
    x as i32
}

/// `libm::round(x) as i32`.
#[inline(never)]
pub fn round_i32(x: f64) -> i32 {
    libm::round(x) as i32
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
            assert_eq!(i32_of(x), x as i32);
            assert_eq!(i32_of(-x), -x as i32);
            assert_eq!(round_i32(x), libm::round(x) as i32);
            assert_eq!(round_i32(-x), libm::round(-x) as i32);
        }
        // Integers to f64: edges (ties to even at 2^53 and above) and random bit patterns.
        let mut r = 0x9E37_79B9_7F4A_7C15u64;
        let edges = [0, 1, u32::MAX as u64, 1 << 32, (1 << 53) + 1, (1 << 54) + 2, (1 << 54) + 6, u64::MAX, 1 << 63, (1 << 63) - 1];
        let random = (0..100_000).map(|_| {
            r ^= r << 13;
            r ^= r >> 7;
            r ^= r << 17;
            r >> (r % 64)
        });
        for x in edges.into_iter().chain(random) {
            assert_eq!(f64_of_u64(x).to_bits(), (x as f64).to_bits(), "{x}");
            for y in [x as i64, (x as i64).wrapping_neg()] {
                assert_eq!(f64_of_i64(y).to_bits(), (y as f64).to_bits(), "{y}");
            }
        }
        assert_eq!(f64_of(0.1f32), 0.1f32 as f64);
    }
}
