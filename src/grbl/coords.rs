//! Work coordinates: G54–G59, G28/G30 positions (persistent), the G92 offset and the tool
//! length offset (volatile, cleared by a reset as in Grbl 1.1).
//!
//! Who uses it: the G-code interpreter (targets, G10, G92, G28/G30, G43.1), reports (`$#`,
//! `WCO:`) and the persistent store (`crate::grbl::store`).
//!
//! Everything is in machine millimetres. Grbl's relation holds on every axis:
//! `WPos = MPos − WCS[selected] − G92 − TLO` (TLO on Z only), and `WCO` is the sum of the three.
//! Stored values are `f32` (as Grbl's EEPROM floats); the controller keeps the stored copy, so
//! what is reported is what a power cycle brings back.

use crate::MAX_AXES;

/// Stored vectors: G54..G59, then G28 and G30.
pub const SLOTS: usize = 8;
/// Index of the G28 position.
pub const G28: usize = 6;
/// Index of the G30 position.
pub const G30: usize = 7;
/// The axis the tool length offset applies to (Z).
pub const TLO_AXIS: usize = 2;
/// Bytes of the stored image.
pub const COORDS_LEN: usize = SLOTS * MAX_AXES * 4;

/// The persistent part: work coordinate systems and the two predefined positions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coords {
    pub slots: [[f32; MAX_AXES]; SLOTS],
}

impl Default for Coords {
    fn default() -> Self {
        Self::ZERO
    }
}

impl Coords {
    pub const ZERO: Coords = Coords { slots: [[0.0; MAX_AXES]; SLOTS] };

    /// Slot `i` for `N` axes, as `f32`.
    pub fn get<const N: usize>(&self, i: usize) -> [f32; N] {
        let s = self.slots.get(i).copied().unwrap_or([0.0; MAX_AXES]);
        core::array::from_fn(|a| s.get(a).copied().unwrap_or(0.0))
    }

    /// Stores slot `i` (axes beyond `N` keep their value).
    pub fn set<const N: usize>(&mut self, i: usize, v: &[f32; N]) {
        if let Some(s) = self.slots.get_mut(i) {
            for (d, x) in s.iter_mut().zip(v) {
                *d = *x;
            }
        }
    }

    /// Little-endian image.
    pub fn to_bytes(&self) -> [u8; COORDS_LEN] {
        let mut b = [0u8; COORDS_LEN];
        self.write_image(&mut b);
        b
    }

    /// [`Self::to_bytes`] written into the start of `b` (the store's image holds it in place).
    pub fn write_image(&self, b: &mut [u8]) {
        for (w, v) in b.chunks_exact_mut(4).zip(self.slots.iter().flatten()) {
            crate::grbl::settings::put4(w, 0, v.to_le_bytes());
        }
    }

    /// From an image; `None` if a value is not a finite number.
    pub fn from_bytes(b: &[u8]) -> Option<Coords> {
        let mut c = Coords::ZERO;
        c.read_image(b).then_some(c)
    }

    /// [`Self::from_bytes`] into `self` (the store's image decodes in place): false if `b` is
    /// short or a value is not a finite number, leaving `self` partly written.
    pub fn read_image(&mut self, b: &[u8]) -> bool {
        let Some(b) = b.get(..COORDS_LEN) else { return false };
        for (w, v) in b.chunks_exact(4).zip(self.slots.iter_mut().flatten()) {
            *v = f32::from_le_bytes([w[0], w[1], w[2], w[3]]);
            if !v.is_finite() {
                return false;
            }
        }
        true
    }
}

/// Every offset in force for `N` axes: the stored systems plus G92 and the tool length offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Offsets<const N: usize> {
    pub stored: Coords,
    /// G92 offset, mm (not persistent).
    pub g92: [f32; N],
    /// G43.1 tool length offset on Z, mm (not persistent).
    pub tlo: f32,
    /// The last probe cycle's position (machine mm) and whether it made contact (`[PRB:]`).
    pub prb: [f32; N],
    pub prb_ok: bool,
}

impl<const N: usize> Default for Offsets<N> {
    fn default() -> Self {
        Self::new(Coords::ZERO)
    }
}

impl<const N: usize> Offsets<N> {
    /// The stored systems with no G92 and no tool length offset (after a reset).
    pub const fn new(stored: Coords) -> Self {
        Offsets { stored, g92: [0.0; N], tlo: 0.0, prb: [0.0; N], prb_ok: false }
    }

    /// Work coordinate system `sel` (0 = G54).
    pub fn wcs(&self, sel: u8) -> [f32; N] {
        self.stored.get(sel as usize)
    }

    /// The tool length offset's share of axis `i`.
    pub fn tlo_of(&self, i: usize) -> f32 {
        if i == TLO_AXIS {
            self.tlo
        } else {
            0.0
        }
    }

    /// Work coordinate offset with system `sel`: WCS + G92 + TLO.
    pub fn wco(&self, sel: u8) -> [f32; N] {
        let w = self.wcs(sel);
        core::array::from_fn(|i| w[i] + self.g92[i] + self.tlo_of(i))
    }

    /// Work coordinate system `sel`'s offset on axis `i` (0 beyond the stored axes).
    pub fn wcs_of(&self, sel: u8, i: usize) -> f32 {
        self.stored.slots.get(sel as usize).and_then(|s| s.get(i)).copied().unwrap_or(0.0)
    }

    /// Machine position of program coordinate `w` on axis `i` in system `sel` (G90).
    pub fn to_machine(&self, sel: u8, i: usize, w: f32) -> f32 {
        w + self.wcs_of(sel, i) + self.g92[i] + self.tlo_of(i)
    }

    /// G92: the offset that makes the machine position `pos` read `words` in system `sel`
    /// (`G92 = MPos − WCS − TLO − WPos`; axes without a word keep theirs).
    pub fn g92_for(&self, sel: u8, pos: &[f32; N], words: &[Option<f32>; N]) -> [f32; N] {
        let wcs = self.wcs(sel);
        core::array::from_fn(|i| match words[i] {
            Some(w) => pos[i] - wcs[i] - self.tlo_of(i) - w,
            None => self.g92[i],
        })
    }

    /// G10 L2 (`l20` false: the words are the offsets) or L20 (the position `pos` reads the
    /// words: `WCS = MPos − G92 − TLO − WPos`): stored slot `slot` with the named axes changed.
    pub fn g10(&self, slot: usize, l20: bool, pos: &[f32; N], words: &[Option<f32>; N]) -> [f32; N] {
        let mut v = self.stored.get::<N>(slot);
        for (i, x) in v.iter_mut().enumerate() {
            if let Some(w) = words[i] {
                *x = if l20 { pos[i] - self.g92[i] - self.tlo_of(i) - w } else { w };
            }
        }
        v
    }

    /// G28 (`k` 0) / G30 (1): after the intermediate point, the named axes (all of them when
    /// none is named) go to the stored position; the others stay at `pos`.
    pub fn home(&self, k: u8, pos: &[f32; N], words: &[Option<f32>; N]) -> [f32; N] {
        let stored = self.stored.get::<N>(G28 + k as usize);
        let any = words.iter().any(Option::is_some);
        core::array::from_fn(|i| if any && words[i].is_none() { pos[i] } else { stored[i] })
    }
}
