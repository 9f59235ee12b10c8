//! Number helpers: float-to-integer conversions (out of line), and a 64-by-32-bit [`mul_div`].
//!
//! Who uses it: the settings, G-code, planning and report code, status reports and the
//! feeder (never the step interrupt).
//!
//! The library computes in `f32`, as Grbl does (the Cortex-M3 has no FPU: each `f64` operation
//! would link a second, larger soft-float set and pass two registers per operand). Rust's `as`
//! casts from `f32` saturate (NaN → 0, beyond the range → its bound). On the soft-float
//! Cortex-M3 each inline cast is a library call plus two compares and selects (~30 bytes); the
//! thread-mode code converts in a few dozen places, so these keep one copy. Each returns
//! exactly what the `as` cast it replaces returns.

/// `x as f32` for a `u64`: the same correctly rounded value, without the 64-bit conversion
/// routine. The high half is cut to the bits `f32` can use plus a sticky bit (so the one
/// rounding of the `u32` conversion is the correct one), then scaled by a power of two.
#[inline(never)]
pub fn f32_of_u64(x: u64) -> f32 {
    if x >> 32 == 0 {
        return x as u32 as f32;
    }
    // Shift so the value fits 32 bits; OR the lost bits in as a sticky bit (below the rounding
    // point: a u32 of 32 significant bits rounds at bit 8, and the sticky bit is bit 0).
    let shift = 32 - x.leading_zeros();
    let lost = x & ((1u64 << shift) - 1);
    let top = (x >> shift) as u32 | (lost != 0) as u32;
    top as f32 * f32::from_bits((127 + shift) << 23)
}

/// `x as f32` for an `i64`, as [`f32_of_u64`] on the magnitude.
#[inline(never)]
pub fn f32_of_i64(x: i64) -> f32 {
    let m = f32_of_u64(x.unsigned_abs());
    if x < 0 {
        -m
    } else {
        m
    }
}

/// `x as u32`.
#[inline(never)]
pub fn u32_of(x: f32) -> u32 {
    x as u32
}

/// `x as u64`.
#[inline(never)]
pub fn u64_of(x: f32) -> u64 {
    x as u64
}

/// `x as i32`.
#[inline(never)]
pub fn i32_of(x: f32) -> i32 {
    x as i32
}

/// `libm::roundf(x) as i32`.
#[inline(never)]
pub fn round_i32(x: f32) -> i32 {
    libm::roundf(x) as i32
}

/// `libm::roundf(x) as u32`.
#[inline(never)]
pub fn round_u32(x: f32) -> u32 {
    libm::roundf(x) as u32
}

/// `(a * b + add) / d` for a quotient that fits 32 bits (`a * b + add < d * 2^32`), without a
/// 64-bit division: shift-subtract on the 64-bit product. Saves the ~900 B `__aeabi_uldivmod`
/// the firmware otherwise links (only status reports and the feeder's horizon call this).
pub fn mul_div(a: u32, b: u32, add: u32, d: u32) -> u32 {
    let n = a as u64 * b as u64 + add as u64;
    let d64 = d as u64;
    let mut rem = n >> 32;
    let mut q = 0u32;
    for bit in (0..32).rev() {
        rem = (rem << 1) | ((n >> bit) & 1);
        q <<= 1;
        if rem >= d64 {
            rem -= d64;
            q |= 1;
        }
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn same_as_the_casts() {
        for x in [f32::NAN, f32::NEG_INFINITY, -1.5, -0.4, 0.0, 0.49, 0.5, 1.5, 2.5, 4294967040.0, 4294967296.0, 1e30, f32::INFINITY] {
            assert_eq!(u32_of(x), x as u32);
            assert_eq!(u64_of(x), x as u64);
            assert_eq!(round_u32(x), libm::roundf(x) as u32);
            assert_eq!(i32_of(x), x as i32);
            assert_eq!(i32_of(-x), -x as i32);
            assert_eq!(round_i32(x), libm::roundf(x) as i32);
            assert_eq!(round_i32(-x), libm::roundf(-x) as i32);
        }
        // Integers to f32: edges (ties to even above 2^24) and random bit patterns.
        let mut r = 0x9E37_79B9_7F4A_7C15u64;
        let edges = [0, 1, u32::MAX as u64, 1 << 32, (1 << 53) + 1, (1 << 54) + 2, (1 << 54) + 6, u64::MAX, 1 << 63, (1 << 63) - 1,
            (1 << 24) + 1, (1 << 25) + 2, (1 << 25) + 6, (1 << 40) + (1 << 16), (1 << 40) + (1 << 16) + 1, (1 << 40) + (3 << 16)];
        let random = (0..100_000).map(|_| {
            r ^= r << 13;
            r ^= r >> 7;
            r ^= r << 17;
            r >> (r % 64)
        });
        for x in edges.into_iter().chain(random) {
            assert_eq!(f32_of_u64(x).to_bits(), (x as f32).to_bits(), "{x}");
            for y in [x as i64, (x as i64).wrapping_neg()] {
                assert_eq!(f32_of_i64(y).to_bits(), (y as f32).to_bits(), "{y}");
            }
        }
    }

    fn reference(a: u32, b: u32, add: u32, d: u32) -> u64 {
        (a as u64 * b as u64 + add as u64) / d as u64
    }

    #[test]
    fn mul_div_edges() {
        let m = u32::MAX;
        for (a, b, add, d) in [(0, 0, 0, 1), (m, m, m / 2, m), (m, 1, 0, 1), (m - 1, m, 0, m), (7, 3, 1, 2), (1, 1, 0, m)] {
            assert_eq!(mul_div(a, b, add, d) as u64, reference(a, b, add, d), "{a} {b} {add} {d}");
        }
    }

    proptest! {
        #[test]
        fn mul_div_matches_u64(total in 1u32.., done in any::<u32>(), c in any::<u32>()) {
            let (done, c) = (done % (total as u64 + 1) as u32, c % (total as u64 + 1) as u32);
            prop_assert_eq!(mul_div(done, c, total / 2, total) as u64, reference(done, c, total / 2, total));
            prop_assert_eq!(mul_div(c, done, 0, total) as u64, reference(c, done, 0, total));
        }
    }
}
