//! Grbl 1.1 wire format, the sending half: the byte sink replies go to, `ok` and `error:N`
//! (with [`crate::error::Error`]'s numbers), and exact decimal formatting.
//!
//! Who uses it: the controller and the reports write through [`Out`]; the firmware's TX ring
//! and the host rigs' buffers implement it.

use crate::error::Error;
use crate::num::div_rem_u64;

/// Where replies go: a bounded buffer that drops what does not fit (never blocks, never
/// panics). Replies are short, so a full TX ring only truncates a report.
///
/// The controller checks [`Out::room`] before it starts a reply, so with a sink that reports
/// its room no `ok` is ever lost: it takes no line byte unless [`REPLY_ROOM`] bytes are free,
/// writes long listings (`$$`, `$#`) a line at a time as room appears, and delays a status
/// report until it fits. The TX ring should hold at least 400 bytes.
pub trait Out {
    /// Writes as many of `bytes` as fit.
    fn put(&mut self, bytes: &[u8]);
    /// Bytes that fit now (`usize::MAX` for a sink that cannot tell).
    fn room(&self) -> usize {
        usize::MAX
    }
}

/// Free TX bytes needed before a line byte is taken: the longest single reply (`$I` with its
/// build-info string, the DMA caps and the step path's self-measurement line with its late
/// fills, or `$N` with two stored lines).
pub const REPLY_ROOM: usize = 392;

impl<const C: usize> Out for heapless::Vec<u8, C> {
    fn put(&mut self, bytes: &[u8]) {
        let n = bytes.len().min(C - self.len());
        let _ = self.extend_from_slice(&bytes[..n]);
    }
    fn room(&self) -> usize {
        C - self.len()
    }
}

impl Out for heapless::spsc::Producer<'_, u8> {
    fn put(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.enqueue(b).is_err() {
                break;
            }
        }
    }
    fn room(&self) -> usize {
        self.capacity() - self.len()
    }
}

/// Writes `ok`.
pub fn put_ok(out: &mut impl Out) {
    out.put(b"ok\r\n");
}

/// Writes `error:N`.
pub fn put_error(out: &mut impl Out, e: Error) {
    put_u32_after(out, b"error:", e as u32);
    out.put(b"\r\n");
}

/// Writes an unsigned decimal.
pub fn put_u32(out: &mut impl Out, v: u32) {
    put_padded(out, v, 1);
}

/// Writes `head`, then `v` in decimal: one call for the pair most report fields are.
#[inline(never)]
pub fn put_u32_after(out: &mut impl Out, head: &[u8], v: u32) {
    out.put(head);
    put_u32(out, v);
}

/// Writes `head`, then `x` as [`put_fixed`] does.
#[inline(never)]
pub fn put_fixed_after(out: &mut impl Out, head: &[u8], x: f32, decimals: u32) {
    out.put(head);
    put_fixed(out, x, decimals);
}

/// Writes `v` as eight upper-case hex digits.
pub fn put_hex(out: &mut impl Out, v: u32) {
    for i in (0..8).rev() {
        let n = (v >> (4 * i) & 0xF) as usize;
        out.put(&b"0123456789ABCDEF"[n..n + 1]);
    }
}

/// Writes `v` in decimal with at least `width` digits (leading zeros; at most 10).
fn put_padded(out: &mut impl Out, mut v: u32, width: usize) {
    let mut buf = [b'0'; 10];
    let mut start = buf.len();
    for (i, d) in buf.iter_mut().enumerate().rev() {
        *d = b'0' + (v % 10) as u8;
        v /= 10;
        start = i;
        if v == 0 && i + width <= 10 {
            break;
        }
    }
    out.put(buf.get(start..).unwrap_or_default());
}

/// Writes `x` rounded to `decimals` places (0..=3, halves away from zero), e.g. `-1.250`.
/// Non-finite values and magnitudes beyond 1e15 are written as 0 (reports only; never reached
/// by settings).
///
/// Exact, in integers: `x` is `m · 2^e` with a 24-bit `m`, so `m · 10^decimals` (below 2^34)
/// shifted by `e` and rounded once is the decimal of `x` itself. (`x · 1000` in `f32` would
/// round first, and a value just below a half could print one digit up.)
pub fn put_fixed(out: &mut impl Out, x: f32, decimals: u32) {
    let decimals = decimals.min(3);
    // NonZero: dividing by it has no panic path.
    let scale = core::num::NonZeroU32::new(10u32.pow(decimals)).unwrap_or(core::num::NonZeroU32::MIN);
    let bits = x.to_bits();
    let exp = (bits >> 23 & 0xFF) as i32;
    let m = bits & 0x7F_FFFF | if exp == 0 { 0 } else { 0x80_0000 };
    let e = exp.max(1) - 150;
    let p = m as u64 * scale.get() as u64;
    let scaled = match e {
        _ if exp == 0xFF => 0, // ±∞, NaN
        0..=29 => p << e,      // below 2^63; from 2^30 up, |x| ≥ 2^53 > 10^15
        -63..=-1 => (p + (1 << (-e - 1))) >> -e,
        _ => 0, // too small to round up to 1
    };
    let scaled = if scaled < 1_000_000_000_000_000 { scaled } else { 0 };
    if scaled != 0 && bits >> 31 != 0 {
        out.put(b"-");
    }
    let (hi, lo) = div_rem_u64(scaled, core::num::NonZeroU64::new(1_000_000_000).unwrap_or(core::num::NonZeroU64::MIN));
    let (hi, lo) = (hi as u32, lo as u32);
    if hi > 0 {
        put_u32(out, hi);
        put_padded(out, lo / scale, 9 - decimals as usize);
    } else {
        put_u32(out, lo / scale);
    }
    if decimals > 0 {
        out.put(b".");
        put_padded(out, lo % scale, decimals as usize);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::{format, string::String};

    /// The former formatting (the `f32` widened to `f64`, whose product with 10^decimals is
    /// exact, rounded; 64-bit integers), as the reference.
    fn reference(x: f32, decimals: u32) -> String {
        let scale = 10i64.pow(decimals);
        let s = libm::round(x as f64 * scale as f64);
        let s = if s.is_finite() && libm::fabs(s) < 1e15 { s as i64 } else { 0 };
        let (sign, a, scale) = (if s < 0 { "-" } else { "" }, s.unsigned_abs(), scale as u64);
        match decimals {
            0 => format!("{sign}{a}"),
            d => format!("{sign}{}.{:0w$}", a / scale, a % scale, w = d as usize),
        }
    }

    fn fixed(x: f32, decimals: u32) -> String {
        let mut b = heapless::Vec::<u8, 64>::new();
        put_fixed(&mut b, x, decimals);
        String::from_utf8(b.to_vec()).unwrap()
    }

    #[test]
    fn put_fixed_matches_64_bit_formatting() {
        let edges = [
            0.0, -0.0, 0.0004, -0.0004, -0.0005, 1.25, -1.2345, 999_999.999_5, 999_999_999.0, 1e9,
            1_000_000_000.000_5, 999_999_999_999.999, 999_999_999_999_999.0, 1e15, -1e15, 3e38, 1e-40, 0.0005, -0.0125, 2.5e-4,
            f32::NAN, f32::INFINITY, f32::NEG_INFINITY,
        ];
        let mut rng = crate::num::xorshift(0x9E37_79B9_7F4A_7C15);
        let random = (0..20_000).map(|_| {
            let r = rng();
            // Magnitudes from 10^-4 to 10^16, both signs.
            let m = (r >> 11) as f64 / (1u64 << 53) as f64;
            let v = libm::pow(10.0, -4.0 + 20.0 * m) as f32;
            if r & 1 == 0 { v } else { -v }
        });
        for x in edges.into_iter().chain(random) {
            for d in 0..=3 {
                assert_eq!(fixed(x, d), reference(x, d), "{x} with {d} decimals");
            }
        }
        assert_eq!(fixed(1.5, 7), "1.500");
        assert_eq!(put_u32_text(u32::MAX), "4294967295");
        assert_eq!(put_u32_text(0), "0");
    }

    fn put_u32_text(v: u32) -> String {
        let mut b = heapless::Vec::<u8, 16>::new();
        put_u32(&mut b, v);
        String::from_utf8(b.to_vec()).unwrap()
    }
}
