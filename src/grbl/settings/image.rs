//! The settings' flash image: [`Settings::to_bytes`] and [`Settings::decode`].
//!
//! Who uses it: the store ([`crate::grbl::store`]) and the firmware shell (flash load/save).

use super::layout::{copy_bytes, crc32, put4, MAGIC, SETTINGS_LEN, TAIL, VERSION};
use super::table::{Slot, WHOLE};
use super::values::Settings;
use crate::encoder::EncoderSettings;
use crate::motion::ramp::Shape;
use crate::MAX_AXES;

impl Settings {
    /// The flash image: magic, version, fields (little-endian, where the `$N` table
    /// (`table.rs`) puts them), CRC-32.
    pub fn to_bytes(&self) -> [u8; SETTINGS_LEN] {
        let mut b = [0u8; SETTINGS_LEN];
        self.write_image(&mut b);
        b
    }

    /// [`Self::to_bytes`] written into `b` (zeroed; the store's image holds it in place).
    pub(crate) fn write_image(&self, b: &mut [u8; SETTINGS_LEN]) {
        copy_bytes(b, &[MAGIC, VERSION, SETTINGS_LEN as u8, (SETTINGS_LEN >> 8) as u8]);
        let mut s = *self;
        for id in Self::ids(MAX_AXES) {
            let (Some(spec), Some(slot)) = (Self::spec(id, MAX_AXES), s.slot(id)) else { continue };
            let at = spec.at as usize;
            // Bytes and flags share their word with their neighbours: OR them in.
            let (word, own) = match slot {
                Slot::Real(v) => (v.to_bits(), true),
                Slot::Whole(v) => (*v, true),
                Slot::Byte(v) => (*v as u32, false),
                Slot::Flag(v) => ((*v as u32) << (spec.bit & 7), false),
                Slot::Shape(v) => ((*v == Shape::SCurve) as u32, false),
            };
            if let Some(w) = b.get_mut(at..at + 4) {
                let old = u32::from_le_bytes([w[0], w[1], w[2], w[3]]);
                w.copy_from_slice(&(if own { word } else { old | word }).to_le_bytes());
            }
        }
        for (k, v) in self.encoder.0.into_iter().enumerate() {
            put4(b, TAIL + 20 + 4 * k, v.to_le_bytes());
        }
        let crc = crc32(&b[..SETTINGS_LEN - 4]);
        put4(b, SETTINGS_LEN - 4, crc.to_le_bytes());
    }

    /// Settings from a flash image, or `None` if it is not one (erased, other version, bad
    /// checksum, a value out of range).
    pub fn decode(b: &[u8]) -> Option<Settings> {
        let mut s = Settings::DEFAULT;
        s.read_image(b).then_some(s)
    }

    /// [`Self::decode`] into `self` (the store's image decodes in place): true for a valid
    /// image; false leaves `self` partly written.
    pub(crate) fn read_image(&mut self, b: &[u8]) -> bool {
        let Some(b) = b.get(..SETTINGS_LEN).and_then(|b| <&[u8; SETTINGS_LEN]>::try_from(b).ok()) else { return false };
        let word = |at: usize| u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
        if word(0) != u32::from_le_bytes([MAGIC, VERSION, SETTINGS_LEN as u8, (SETTINGS_LEN >> 8) as u8]) {
            return false;
        }
        if crc32(&b[..SETTINGS_LEN - 4]) != word(SETTINGS_LEN - 4) {
            return false;
        }
        *self = Settings::DEFAULT;
        for id in Self::ids(MAX_AXES) {
            let (Some(spec), Some(slot)) = (Self::spec(id, MAX_AXES), self.slot(id)) else { continue };
            let at = (spec.at as usize).min(SETTINGS_LEN - 8);
            let byte = b[at];
            let flag = match spec.bit {
                WHOLE if byte > 1 => return false,
                WHOLE => byte != 0,
                bit => byte >> (bit & 7) & 1 != 0,
            };
            match slot {
                Slot::Real(v) => *v = f32::from_bits(word(at)),
                Slot::Whole(v) => *v = word(at),
                Slot::Byte(v) => *v = byte,
                Slot::Flag(v) => *v = flag,
                Slot::Shape(v) => *v = if flag { Shape::SCurve } else { Shape::Trapezoid },
            }
        }
        self.encoder = EncoderSettings::from_bytes(&b[TAIL + 20..]);
        // An image from before `$582` has its byte clear: the default.
        if self.flexible == 0 {
            self.flexible = crate::motion::ramp::FLEX_DEFAULT;
        }
        self.is_valid()
    }

    /// Settings from a flash image, or the defaults if it is not a valid one.
    pub fn from_bytes(b: &[u8]) -> Settings {
        Self::decode(b).unwrap_or(Settings::DEFAULT)
    }
}
