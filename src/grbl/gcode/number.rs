//! G-code numbers: a decimal read exactly (up to 15 significant digits as an integer, then the
//! nearest `f32` to the decimal, as `str::parse` gives; [`parse_word`] also returns the decimal
//! itself, for exact step targets).
//!
//! Who uses it: the block parser ([`crate::grbl::gcode::block`]) for every word's value, and the
//! `$` commands for setting values.

use crate::error::Error;
use crate::planning::exact::Decimal;

/// Largest significand read: 15 decimal digits (below 2^50, as [`decimal_f32`] needs).
const MAX_SIGNIFICAND: u64 = 999_999_999_999_999;
/// Most digits after the point (5^22 < 2^52, as [`decimal_f32`] needs).
const MAX_FRAC: usize = 22;

/// Reads a decimal number at `s[*i..]` (optional sign, digits, at most one point) and moves
/// `*i` past it. No exponent, no `inf`/`nan`: anything else is [`Error::BadNumberFormat`].
pub fn parse_number(s: &[u8], i: &mut usize) -> Result<f32, Error> {
    parse_word(s, i).map(|(v, _)| v)
}

/// [`parse_number`], with the decimal exactly as written (`sig / 10^frac`, trailing zeros after
/// the point dropped).
pub fn parse_word(s: &[u8], i: &mut usize) -> Result<(f32, Decimal), Error> {
    let mut j = *i;
    let neg = s.get(j) == Some(&b'-');
    if matches!(s.get(j), Some(b'-' | b'+')) {
        j += 1;
    }
    let (mut sig, mut frac, mut zeros, mut digits, mut point) = (0u64, 0usize, 0usize, 0, false);
    while let Some(&c) = s.get(j) {
        match c {
            b'0'..=b'9' => {
                digits += 1;
                let d = (c - b'0') as u64;
                if point && d == 0 {
                    zeros += 1; // zeros after the point count only once a digit follows
                } else {
                    let shift = if point { zeros as u32 + 1 } else { 1 };
                    if point {
                        frac += zeros + 1;
                        zeros = 0;
                    }
                    // ×10 a step at a time: below the cap before each step, so no overflow (a
                    // product over the cap is refused, as the sum after it would be).
                    for _ in 0..shift {
                        sig *= 10;
                        if sig > MAX_SIGNIFICAND {
                            return Err(Error::BadNumberFormat);
                        }
                    }
                    sig += d;
                }
                if sig > MAX_SIGNIFICAND || frac > MAX_FRAC {
                    return Err(Error::BadNumberFormat);
                }
            }
            b'.' if !point => point = true,
            _ => break,
        }
        j += 1;
    }
    if digits == 0 {
        return Err(Error::BadNumberFormat);
    }
    *i = j;
    let v = decimal_f32(sig, frac as u32);
    // sig ≤ MAX_SIGNIFICAND < 2^50 and frac ≤ MAX_FRAC: within a Decimal's bounds.
    let d = Decimal { sig: if neg { -(sig as i64) } else { sig as i64 }, frac: frac as u8 };
    Ok((if neg { -v } else { v }, d))
}

/// The nearest `f32` to `sig / 10^frac` (`sig` < 2^50, `frac` ≤ 22), as `str::parse` gives.
///
/// A significand of 24 bits over 10^frac ≤ 10^9 (both exact in `f32`) is one correctly rounded
/// division. Otherwise in integers: 10^frac = 5^frac · 2^frac (5^22 < 2^52), so the quotient
/// by 5^frac is taken to 26 bits with a sticky bit (which the one rounding of the `u32`
/// conversion then rounds correctly), and the powers of two are exact.
fn decimal_f32(sig: u64, frac: u32) -> f32 {
    if sig < 1 << 24 && frac <= 9 {
        // 10^frac in integers (no soft-float products), exact in f32 up to 10^9 (5^9 < 2^24).
        return sig as u32 as f32 / 10u32.pow(frac) as f32;
    }
    if sig == 0 {
        return 0.0;
    }
    // NonZero: dividing by it has no panic path.
    let d = core::num::NonZeroU64::new(5u64.pow(frac)).unwrap_or(core::num::NonZeroU64::MIN);
    // sig / d = (q + r/d) · 2^-shift, q brought to 26 bits (r < d < 2^52: 2r fits).
    let ((mut q, mut r), mut shift) = (crate::num::div_rem_u64(sig, d), 0i32);
    let d = d.get();
    while q < 1 << 25 {
        r <<= 1;
        q = q << 1 | (r >= d) as u64;
        if r >= d {
            r -= d;
        }
        shift += 1;
    }
    let mut sticky = r != 0;
    while q >= 1 << 26 {
        sticky |= q & 1 != 0;
        q >>= 1;
        shift -= 1;
    }
    // 2^-(shift + frac): within f32's normal range here (shift ≤ 77, frac ≤ 22; shift ≥ -24).
    let scale = f32::from_bits(((127 - shift - frac as i32) as u32) << 23);
    (q as u32 | sticky as u32) as f32 * scale
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    /// The former reader (a table of powers of ten, checked 64-bit arithmetic), as the reference
    /// for the syntax; its value is `str::parse::<f32>`'s (the nearest `f32`).
    fn reference(s: &[u8], i: &mut usize) -> Result<f32, Error> {
        const POW10: [f32; 23] = [
            1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
            1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
        ];
        let mut j = *i;
        let neg = s.get(j) == Some(&b'-');
        if matches!(s.get(j), Some(b'-' | b'+')) {
            j += 1;
        }
        let (mut sig, mut frac, mut zeros, mut digits, mut point) = (0u64, 0usize, 0usize, 0, false);
        while let Some(&c) = s.get(j) {
            match c {
                b'0'..=b'9' => {
                    digits += 1;
                    let d = (c - b'0') as u64;
                    if point && d == 0 {
                        zeros += 1;
                    } else {
                        let shift = if point { zeros as u32 + 1 } else { 1 };
                        if point {
                            frac += zeros + 1;
                            zeros = 0;
                        }
                        let scaled = match sig {
                            0 => Some(0),
                            _ => 10u64.checked_pow(shift).and_then(|k| sig.checked_mul(k)),
                        };
                        sig = scaled.and_then(|v| v.checked_add(d)).ok_or(Error::BadNumberFormat)?;
                    }
                    if sig > MAX_SIGNIFICAND || frac >= POW10.len() {
                        return Err(Error::BadNumberFormat);
                    }
                }
                b'.' if !point => point = true,
                _ => break,
            }
            j += 1;
        }
        if digits == 0 {
            return Err(Error::BadNumberFormat);
        }
        *i = j;
        // The nearest f32 to the decimal (core's reader is correctly rounded).
        let v: f32 = std::format!("{sig}e-{frac}").parse().unwrap();
        Ok(if neg { -v } else { v })
    }

    #[test]
    fn parse_number_matches_the_former_reader() {
        let mut rng = crate::num::xorshift(0x2545_F491_4F6C_DD1Du64);
        let mut next = |n: u64| rng() % n;
        // Mostly digits and zeros (long runs of zeros after the point), some signs and points.
        let alphabet = b"0000000123456789..-+X";
        let edges = ["1.00000000000000000001", "9.0000000000000000000001", "0.0000000000000000000009", "99999.0000000001",
            "999999999999999.1", "99999999999999.9", "1.000000000000000000000000007", "0.00000000000000000000001"];
        let random = (0..300_000).map(|_| {
            let len = next(32) as usize;
            (0..len).map(|_| alphabet[next(alphabet.len() as u64) as usize]).collect::<std::vec::Vec<u8>>()
        });
        for s in edges.iter().map(|e| e.as_bytes().to_vec()).chain(random) {
            let (mut i, mut k) = (0, 0);
            let (a, b) = (parse_number(&s, &mut i), reference(&s, &mut k));
            assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "{:?}", core::str::from_utf8(&s));
            assert_eq!(i, k);
        }
    }
}
