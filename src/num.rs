//! Number helpers: float-to-integer conversions out of line, 64-bit division without the
//! runtime's routine ([`div_rem_u64`], [`mul_div`]), a small square root, and the wrapping clock
//! comparison.
//!
//! Who uses it: the settings, G-code, planning, controller and report code (never the step
//! interrupt); the feeder uses [`mul_div`].
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

/// `x as u64`: below 2^32 the `u32` conversion (NaN and negatives give 0, as the cast does),
/// from 2^32 up the significand shifted into place, so the 64-bit conversion routine
/// (`__aeabi_f2ulz`) is not linked.
#[inline(never)]
pub fn u64_of(x: f32) -> u64 {
    if !(x >= 4_294_967_296.0) {
        return x as u32 as u64;
    }
    if x >= 18_446_744_073_709_551_616.0 {
        return u64::MAX;
    }
    // x = m · 2^(exp − 150), the shift 9..=40 here (2^32 ≤ x < 2^64).
    let bits = x.to_bits();
    ((bits & 0x7F_FFFF | 0x80_0000) as u64) << ((bits >> 23) - 150)
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

/// `(a * b + add) / d` for a quotient that fits 32 bits (`a * b + add < d * 2^32`), with
/// [`div_rem_u64`] (status reports and the feeder's horizon call this).
pub fn mul_div(a: u32, b: u32, add: u32, d: u32) -> u32 {
    let n = a as u64 * b as u64 + add as u64;
    div_rem_u64(n, core::num::NonZeroU64::new(d as u64).unwrap_or(core::num::NonZeroU64::MIN)).0 as u32
}

/// `(n / d, n % d)` by shift and subtract, one quotient bit a step from the highest that can be
/// set (at most 64 steps; a 2^40 tick count over a 2^20 rate takes 21): the firmware's only
/// 64-bit division, so compiler-builtins' `__aeabi_uldivmod` (~900 B) is not linked. Never in
/// the step interrupt.
#[inline(never)]
pub fn div_rem_u64(n: u64, d: core::num::NonZeroU64) -> (u64, u64) {
    let d = d.get();
    if n < d {
        return (0, n);
    }
    // d shifted up to n's highest bit (no overflow: d ≤ n).
    let s = d.leading_zeros() - n.leading_zeros();
    let (mut q, mut r, mut dd) = (0u64, n, d << s);
    for _ in 0..=s {
        q <<= 1;
        if r >= dd {
            r -= dd;
            q |= 1;
        }
        dd >>= 1;
    }
    (q, r)
}

/// Tests' random numbers: Marsaglia's xorshift64 from `seed` (non-zero), one value per call
/// (the same sequence on every run, so a failure repeats).
#[cfg(test)]
pub(crate) fn xorshift(seed: u64) -> impl FnMut() -> u64 {
    let mut r = seed;
    move || {
        r ^= r << 13;
        r ^= r >> 7;
        r ^= r << 17;
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn same_as_the_casts() {
        for x in [f32::NAN, f32::NEG_INFINITY, -1.5, -0.4, 0.0, 0.49, 0.5, 1.5, 2.5, 4294967040.0, 4294967296.0, 4294967808.0, 1.844_674_3e19, 18446744073709551616.0, 1e30, f32::INFINITY] {
            assert_eq!(u32_of(x), x as u32);
            assert_eq!(u64_of(x), x as u64);
            assert_eq!(round_u32(x), libm::roundf(x) as u32);
            assert_eq!(i32_of(x), x as i32);
            assert_eq!(i32_of(-x), -x as i32);
            assert_eq!(round_i32(x), libm::roundf(x) as i32);
            assert_eq!(round_i32(-x), libm::roundf(-x) as i32);
        }
        // Integers to f32: edges (ties to even above 2^24) and random bit patterns.
        let mut rng = xorshift(0x9E37_79B9_7F4A_7C15);
        let edges = [0, 1, u32::MAX as u64, 1 << 32, (1 << 53) + 1, (1 << 54) + 2, (1 << 54) + 6, u64::MAX, 1 << 63, (1 << 63) - 1,
            (1 << 24) + 1, (1 << 25) + 2, (1 << 25) + 6, (1 << 40) + (1 << 16), (1 << 40) + (1 << 16) + 1, (1 << 40) + (3 << 16)];
        let random = (0..100_000).map(|_| {
            let r = rng();
            r >> (r % 64)
        });
        for x in edges.into_iter().chain(random) {
            // The same bits read as an f32 (every sign, exponent and NaN payload).
            let f = f32::from_bits(x as u32);
            assert_eq!(u64_of(f), f as u64, "{f}");
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

    #[test]
    fn div_rem_u64_edges() {
        let m = u64::MAX;
        let cases = [(0, 1), (1, 1), (m, 1), (m, m), (m - 1, m), (m, 2), (m, 1 << 63), ((1 << 63) - 1, 1 << 63), (1 << 32, (1 << 32) - 1),
            (2_304_000_000_000 + 7, 2 * 7), (999_999_999_999_999, 1_000_000_000), (1 << 50, 2_384_185_791_015_625)];
        for (n, d) in cases {
            assert_eq!(div_rem_u64(n, d.try_into().unwrap()), (n / d, n % d), "{n} / {d}");
        }
    }

    proptest! {
        /// Every numerator and divisor, with both drawn from all bit lengths (a uniform u64 is
        /// almost always 64 bits long).
        #[test]
        fn div_rem_u64_matches_u64(n in any::<u64>(), d in 1u64.., ns in 0u32..64, ds in 0u32..64) {
            let (n, d) = (n >> ns, (d >> ds).max(1));
            prop_assert_eq!(div_rem_u64(n, d.try_into().unwrap()), (n / d, n % d));
        }

        #[test]
        fn mul_div_matches_u64(total in 1u32.., done in any::<u32>(), c in any::<u32>()) {
            let (done, c) = (done % (total as u64 + 1) as u32, c % (total as u64 + 1) as u32);
            prop_assert_eq!(mul_div(done, c, total / 2, total) as u64, reference(done, c, total / 2, total));
            prop_assert_eq!(mul_div(c, done, 0, total) as u64, reference(c, done, 0, total));
        }
    }
}

/// Square root, correctly rounded like `libm::sqrtf`, in ~100 bytes of flash. Digit by digit:
/// the 25-bit truncated root of the significand, then rounded half up; a tie cannot happen,
/// since a 25-bit odd significand squared never fits in 24 bits. Negative inputs give NaN,
/// like libm.
pub fn sqrt(x: f32) -> f32 {
    let bits = x.to_bits();
    if bits > 1 << 31 {
        return f32::NAN;
    }
    if bits == 0 || bits >= 0xFF << 23 {
        return x; // ±0, +∞, NaN
    }
    let mut e = (bits >> 23) as i32 - 127;
    let mut m = bits & ((1 << 23) - 1);
    if e == -127 {
        // Subnormal: normalize.
        e += 1;
        while m < 1 << 23 {
            m <<= 1;
            e -= 1;
        }
    } else {
        m |= 1 << 23;
    }
    // Make the exponent even: √(m · 2^e) = √(m · 2^(e & 1)) · 2^(e >> 1), m now in [2^23, 2^25).
    m <<= e & 1;
    e >>= 1;
    // q = ⌊√(m · 2^25)⌋ (25 bits), one bit at a time; the remainder stays below 2^28.
    let (mut rem, mut s, mut q, mut r) = (m << 1, 0u32, 0u32, 1u32 << 24);
    while r != 0 {
        let t = s + r;
        if t <= rem {
            s = t + r;
            rem -= t;
            q += r;
        }
        rem <<= 1;
        r >>= 1;
    }
    // A carry out of the significand correctly bumps the exponent.
    f32::from_bits((((e + 126) as u32) << 23) + ((q + 1) >> 1))
}

/// `a - b` on a wrapping `u32` clock or counter (milliseconds, sequence numbers), signed:
/// negative while `a` is before `b`. Exact while the two are less than 2^31 apart.
#[inline]
pub const fn wrapping_diff(a: u32, b: u32) -> i32 {
    a.wrapping_sub(b) as i32
}

#[cfg(test)]
mod helper_tests {
    use super::*;

    #[test]
    fn sqrt_matches_libm() {
        let mut x = 0x2545_F491_4F6C_DD1Du64;
        let specials = [0.0, -0.0, 1.0, 2.0, 3800.0, 1e-45, 1.2e-38, 5e-39, f32::MAX, f32::INFINITY];
        for v in specials {
            assert_eq!(sqrt(v).to_bits(), libm::sqrtf(v).to_bits(), "√{v}");
        }
        assert!(sqrt(-1.0).is_nan() && sqrt(f32::NAN).is_nan());
        for i in 0..200_000 {
            // xorshift64: random bit patterns (every exponent) and random lengths² in mm².
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = if i % 2 == 0 { f32::from_bits((x >> 33) as u32) } else { (x >> 40) as f32 / (1u64 << 10) as f32 };
            if v.is_finite() {
                assert_eq!(sqrt(v).to_bits(), libm::sqrtf(v).to_bits(), "√{v}");
            }
        }
    }

    #[test]
    fn wrapping_diff_is_signed_across_the_wrap() {
        assert_eq!(wrapping_diff(1, u32::MAX), 2);
        assert_eq!(wrapping_diff(u32::MAX, 1), -2);
        assert_eq!(wrapping_diff(5, 5), 0);
        assert!(wrapping_diff(0x7FFF_FFFF, 0) > 0 && wrapping_diff(0x8000_0000, 0) < 0);
    }
}
