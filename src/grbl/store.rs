//! What survives a power cut: settings, coordinate systems, `$N` startup lines and the `$I`
//! build-info string, kept as one image in *two* flash pages (A/B).
//!
//! Who uses it: the firmware shell (load at boot, save after [`crate::grbl::controller::Actions::save`])
//! and the controller (which owns the [`Stored`] copy and bumps its sequence number).
//!
//! Invariant: a save never touches the page holding the newest valid image. It erases the
//! other page (blank, corrupt or older), programs the new image there and reads it back; the
//! image carries a sequence number and a CRC-32. A power cut at any moment therefore leaves
//! either the new image complete (it wins: higher sequence) or the previous one untouched —
//! coordinates are never lost when settings change, and settings never when coordinates do.
//! Each page sees every second write, halving flash wear per page.

use crate::grbl::coords::{Coords, COORDS_LEN};
use crate::num::wrapping_diff;
use crate::grbl::settings::{copy_bytes, crc32, put4, Settings, SETTINGS_LEN};

/// Bytes a stored text line can hold (Grbl keeps 80 with its terminator).
pub const TEXT_LEN: usize = 79;
/// `$N0`, `$N1`.
pub const STARTUP_LINES: usize = 2;
const MAGIC: [u8; 4] = *b"DDS2";
const SETTINGS_AT: usize = 8;
const COORDS_AT: usize = SETTINGS_AT + SETTINGS_LEN;
const TEXT_AT: usize = COORDS_AT + COORDS_LEN;
const TEXTS: usize = STARTUP_LINES + 1;
/// Bytes of the image (a multiple of 4, within one 1 KiB page).
pub const IMAGE_LEN: usize = TEXT_AT + TEXTS * (TEXT_LEN + 1) + 4;
/// Flash page size.
pub const PAGE_LEN: usize = 1024;
/// The two pages' offsets from the start of flash: fixed, the last two pages of a 64 KiB
/// part (memory.x ends the program below them; a larger part keeps them here too).
pub const PAGE_OFFSETS: [u32; 2] = [62 * 1024, 63 * 1024];
const _: () = assert!(IMAGE_LEN <= PAGE_LEN && IMAGE_LEN.is_multiple_of(4));

/// A short stored text (a startup line or the build info), upper case as lines arrive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Text {
    len: u8,
    buf: [u8; TEXT_LEN],
}

impl Default for Text {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Text {
    pub const EMPTY: Text = Text { len: 0, buf: [0; TEXT_LEN] };

    /// `None` when longer than [`TEXT_LEN`].
    pub fn new(s: &[u8]) -> Option<Text> {
        let mut t = Text::EMPTY;
        t.set(s).then_some(t)
    }

    /// Sets the text to `s` in place (the rest of the buffer zero, as [`Self::new`] leaves
    /// it); false, and unchanged, when `s` is longer than [`TEXT_LEN`].
    #[inline(never)]
    pub fn set(&mut self, s: &[u8]) -> bool {
        if s.len() > TEXT_LEN {
            return false;
        }
        for (i, b) in self.buf.iter_mut().enumerate() {
            *b = s.get(i).copied().unwrap_or(0);
        }
        self.len = s.len() as u8;
        true
    }

    /// The text's bytes. (Out of line: its bound check was inlined at three sites.)
    #[inline(never)]
    pub fn as_bytes(&self) -> &[u8] {
        &self.buf[..(self.len as usize).min(TEXT_LEN)]
    }
}

/// Everything persistent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stored {
    /// Sequence number of the image (the newer of two valid pages wins).
    pub seq: u32,
    pub settings: Settings,
    pub coords: Coords,
    pub startup: [Text; STARTUP_LINES],
    pub build_info: Text,
}

impl From<Settings> for Stored {
    fn from(settings: Settings) -> Self {
        let mut s = Stored::defaults();
        s.settings = settings;
        s
    }
}

impl Default for Stored {
    fn default() -> Self {
        Self::defaults()
    }
}

impl Stored {
    pub const DEFAULT: Stored = Stored {
        seq: 0,
        settings: Settings::DEFAULT,
        coords: Coords::ZERO,
        startup: [Text::EMPTY; STARTUP_LINES],
        build_info: Text::EMPTY,
    };

    /// [`Self::DEFAULT`] built in place: the constant would be copied from flash whole (its
    /// kilobyte of zeros included), where zeroing takes a few instructions.
    pub fn defaults() -> Stored {
        Stored {
            seq: 0,
            settings: Settings::DEFAULT,
            coords: Coords::ZERO,
            startup: [Text::EMPTY; STARTUP_LINES],
            build_info: Text::EMPTY,
        }
    }

    /// The flash image.
    #[inline(never)]
    pub fn to_bytes(&self) -> [u8; IMAGE_LEN] {
        let mut b = [0u8; IMAGE_LEN];
        put4(&mut b, 0, MAGIC);
        put4(&mut b, 4, self.seq.to_le_bytes());
        if let Some(w) = b.get_mut(SETTINGS_AT..COORDS_AT).and_then(|w| w.try_into().ok()) {
            self.settings.write_image(w);
        }
        self.coords.write_image(&mut b[COORDS_AT..TEXT_AT]);
        let texts = self.startup.iter().chain(core::iter::once(&self.build_info));
        for (w, t) in b[TEXT_AT..].chunks_exact_mut(TEXT_LEN + 1).zip(texts) {
            w[0] = t.len;
            copy_bytes(&mut w[1..], &t.buf);
        }
        let crc = crc32(&b[..IMAGE_LEN - 4]);
        put4(&mut b, IMAGE_LEN - 4, crc.to_le_bytes());
        b
    }

    /// An image read from flash, or `None` (blank, torn by a power cut, other format).
    pub fn decode(b: &[u8]) -> Option<Stored> {
        let b = b.get(..IMAGE_LEN)?;
        let crc = u32::from_le_bytes(b[IMAGE_LEN - 4..].try_into().ok()?);
        if b[..4] != MAGIC || crc32(&b[..IMAGE_LEN - 4]) != crc {
            return None;
        }
        let mut s = Stored::defaults();
        s.seq = u32::from_le_bytes(b[4..8].try_into().ok()?);
        if !s.settings.read_image(&b[SETTINGS_AT..COORDS_AT]) {
            return None;
        }
        if !s.coords.read_image(&b[COORDS_AT..TEXT_AT]) {
            return None;
        }
        let texts = s.startup.iter_mut().chain(core::iter::once(&mut s.build_info));
        for (w, t) in b[TEXT_AT..].chunks_exact(TEXT_LEN + 1).zip(texts) {
            if !t.set(w.get(1..1 + w[0] as usize)?) {
                return None;
            }
        }
        Some(s)
    }

    /// The newest valid image of two pages, and the index of the page to write next (the
    /// other one). Nothing valid: the defaults, and page 0.
    pub fn load(pages: [&[u8]; 2]) -> (Stored, usize) {
        match Self::newest(pages) {
            Some(i) => (Stored::decode(pages[i]).unwrap_or_else(Stored::defaults), 1 - i),
            None => (Stored::defaults(), 0),
        }
    }

    /// Which page holds the newest valid image, if any. One image is decoded at a time (the
    /// firmware calls this on boot and before each save: two images at once would cost the
    /// stack 2 KiB more).
    pub fn newest(pages: [&[u8]; 2]) -> Option<usize> {
        match [seq_of(pages[0]), seq_of(pages[1])] {
            [Some(a), Some(b)] if wrapping_diff(b, a) > 0 => Some(1),
            [Some(_), _] => Some(0),
            [None, Some(_)] => Some(1),
            [None, None] => None,
        }
    }
}

/// The sequence number of a valid image (see [`Stored::decode`]).
#[inline(never)]
fn seq_of(b: &[u8]) -> Option<u32> {
    Stored::decode(b).map(|s| s.seq)
}
