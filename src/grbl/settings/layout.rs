//! Where the settings sit in their flash image: its length, header and byte offsets, and the
//! byte helpers and CRC that write and check it.
//!
//! Who uses it: the settings table (each setting's byte), the image code, the store
//! ([`crate::grbl::store`], which shares `put4`, `copy_bytes` and `crc32`).

use crate::MAX_AXES;

/// Bytes of the flash image.
pub const SETTINGS_LEN: usize = 200;
pub(super) const MAGIC: u8 = 0xD5;
pub(super) const VERSION: u8 = 5;
/// Byte offset of the settings after the axis arrays: `$12`, `$30`, `$31`, `$33` (f32, u32),
/// `$32` (flag byte), `$582` (byte `TAIL + 17`; 0 in an image from before it), the encoder's `$87`-`$99` from `TAIL + 20`, the homing `$24`, `$25`,
/// `$27` (f32) and `$26` (u32) from [`HOME`] (`$23` is byte 23); CRC last.
pub(super) const TAIL: usize = 24 + 4 * 4 * MAX_AXES;
/// Byte offset of the homing settings, after the encoder's.
pub(super) const HOME: usize = TAIL + 20 + crate::encoder::IMAGE_LEN;
const _: () = assert!(HOME + 16 <= SETTINGS_LEN - 4);
/// Byte offset of the flag bits (`$4`, `$5`, `$6`, `$20`, `$22`, `$21`, `$580`, `$581` as bits
/// 0..=7; an image from before `$580`/`$581` has their bits clear: single-edge, interrupt mode,
/// as it ran).
pub(super) const FLAGS: usize = 19;

/// Stores 4 bytes at `at`, if they fit. (Inlined: the callers' offsets are mostly constants,
/// so the check and the copy fold to plain stores.)
pub(crate) fn put4(b: &mut [u8], at: usize, v: [u8; 4]) {
    if let Some(w) = b.get_mut(at..at + 4) {
        w.copy_from_slice(&v);
    }
}

/// Copies `src` to the start of `dst`, as many bytes as both hold: the callers' lengths are
/// equal, and this has no length-mismatch panic path (`copy_from_slice`'s costs flash).
#[inline(never)]
pub(crate) fn copy_bytes(dst: &mut [u8], src: &[u8]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}

/// CRC-32 (IEEE 802.3, reflected), bitwise: small code, run only on load and save.
pub fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}
