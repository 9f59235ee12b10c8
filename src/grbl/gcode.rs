//! G-code: numbers, blocks and the modal state, for Grbl 1.1's lines, arcs, offsets and feed modes.
//!
//! Who uses it: the controller, on each line from [`crate::grbl::protocol::LineBuf`] (upper case, no
//! whitespace, no comments).
//!
//! A block is checked in full before anything happens (Grbl's rule): [`parse`] reads the words
//! and catches word-level errors in line order; [`Modal::interpret`] applies the block to a copy
//! of the modal state and yields the [`Effects`] to carry out, so a refused line changes nothing.
//! Numbers are read exactly: up to 15 significant digits as an integer, then the nearest `f32`
//! to the decimal (as `str::parse` gives; [`decimal_f32`]).

use crate::planning::arc::{Arc, Center};
use crate::planning::planner::MAX_MM;
use crate::grbl::coords::{Offsets, G28};
use crate::num::{round_u32, u32_of};
use crate::error::Error;
use crate::grbl::spindle::{SpindleDir, FLOOD, MIST};
use crate::AXIS_NAMES;

/// Largest line number (Grbl's MAX_LINE_NUMBER).
pub const MAX_LINE_NUMBER: f32 = 10_000_000.0;
/// Longest dwell, s (keeps the wrapping millisecond clock unambiguous).
pub const MAX_DWELL_S: f32 = 1_000_000.0;
/// Largest significand read: 15 decimal digits (below 2^50, as [`decimal_f32`] needs).
const MAX_SIGNIFICAND: u64 = 999_999_999_999_999;
/// Most digits after the point (5^22 < 2^52, as [`decimal_f32`] needs).
const MAX_FRAC: usize = 22;

/// Reads a decimal number at `s[*i..]` (optional sign, digits, at most one point) and moves
/// `*i` past it. No exponent, no `inf`/`nan`: anything else is [`Error::BadNumberFormat`].
pub fn parse_number(s: &[u8], i: &mut usize) -> Result<f32, Error> {
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
    Ok(if neg { -v } else { v })
}

/// The nearest `f32` to `sig / 10^frac` (`sig` < 2^50, `frac` ≤ 22), as `str::parse` gives.
///
/// A significand of 24 bits over 10^frac ≤ 10^10 (both exact in `f32`) is one correctly rounded
/// division. Otherwise in integers: 10^frac = 5^frac · 2^frac (5^22 < 2^52), so the quotient
/// by 5^frac is taken to 26 bits with a sticky bit (which the one rounding of the `u32`
/// conversion then rounds correctly), and the powers of two are exact.
fn decimal_f32(sig: u64, frac: u32) -> f32 {
    if sig < 1 << 24 && frac <= 10 {
        // 10^frac by repeated ×10: every product up to 10^10 is exact in f32.
        let mut pow10 = 1.0f32;
        for _ in 0..frac {
            pow10 *= 10.0;
        }
        return sig as u32 as f32 / pow10;
    }
    if sig == 0 {
        return 0.0;
    }
    let d = 5u64.pow(frac);
    // sig / d = (q + r/d) · 2^-shift, q brought to 26 bits (r < d < 2^52: 2r fits).
    let (mut q, mut r, mut shift) = (sig / d, sig % d, 0i32);
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

/// Motion mode (group 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Motion {
    /// G0: at the axes' max rates.
    Rapid,
    /// G1: at the feed rate.
    Linear,
    /// G2: clockwise arc.
    CwArc,
    /// G3: counter-clockwise arc.
    CcwArc,
    /// G80: no motion mode (axis words are an error).
    Cancel,
    /// G38.2–G38.5 (the digit after the point): probe toward (2, 3) or away (4, 5) at the feed
    /// rate; 2 and 4 alarm when the move ends without the probe changing.
    Probe(u8),
}

/// Non-modal command (group 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NonModal {
    /// G4 P<seconds>.
    Dwell,
    /// G92: offset the work coordinates so the current position reads the given values.
    SetPosition,
    /// G92.1: clear the G92 offset.
    ResetOffset,
    /// G10 L2 / L20 Pn: set coordinate system n (0: the active one).
    SetCoordData,
    /// G28 (0) / G30 (1): rapid, through the axis words if any, to the stored position.
    GoHome(u8),
    /// G28.1 (0) / G30.1 (1): store the current machine position.
    SetHome(u8),
    /// G53: axis words are machine coordinates for this block.
    Absolute,
}

/// Program flow (group 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// M0: feed hold once the queue has run out; `~` resumes.
    Pause,
    /// M1: optional stop, ignored (as in Grbl without the option).
    Optional,
    /// M2 / M30: program end, modal state back to Grbl's program-end defaults.
    End,
}

/// Modal group bits, for the one-command-per-group rule.
pub mod group {
    pub const MOTION: u16 = 1 << 0;
    pub const NON_MODAL: u16 = 1 << 1;
    pub const PLANE: u16 = 1 << 2;
    pub const DISTANCE: u16 = 1 << 3;
    pub const ARC_DISTANCE: u16 = 1 << 4;
    pub const FEED_MODE: u16 = 1 << 5;
    pub const UNITS: u16 = 1 << 6;
    pub const CUTTER: u16 = 1 << 7;
    pub const TOOL_LENGTH: u16 = 1 << 8;
    pub const COORD: u16 = 1 << 9;
    pub const PATH: u16 = 1 << 10;
    pub const STOP: u16 = 1 << 11;
    pub const SPINDLE: u16 = 1 << 12;
    pub const COOLANT: u16 = 1 << 13;
    pub const DRIVERS: u16 = 1 << 14;
}

/// One parsed line: commands by group and value words.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block<const N: usize> {
    groups: u16,
    axis_cmd: bool,
    pub motion: Option<Motion>,
    pub non_modal: Option<NonModal>,
    pub plane: Option<u8>,
    pub relative: Option<bool>,
    pub inches: Option<bool>,
    pub stop: Option<Stop>,
    /// M17 (`true`) / M18, M84 (`false`): drivers on or off.
    pub drivers: Option<bool>,
    /// G54..G59 as 0..5.
    pub coord: Option<u8>,
    /// G43.1 (`true`) / G49 (`false`).
    pub tool_length: Option<bool>,
    /// G93 (`true`) / G94.
    pub inverse_time: Option<bool>,
    /// M3 / M4 / M5.
    pub spindle: Option<SpindleDir>,
    /// M7 / M8 / M9 (the code).
    pub coolant: Option<u8>,
    pub axes: [Option<f32>; N],
    /// I J K arc offsets.
    pub ijk: [Option<f32>; 3],
    pub r: Option<f32>,
    pub f: Option<f32>,
    pub l: Option<f32>,
    pub p: Option<f32>,
    pub s: Option<f32>,
    pub t: Option<f32>,
    pub n: Option<f32>,
}

impl<const N: usize> Block<N> {
    /// No words. (A function, not a constant: see `Job::none` in the controller.)
    fn empty() -> Self {
        Block {
            groups: 0,
            axis_cmd: false,
            motion: None,
            non_modal: None,
            plane: None,
            relative: None,
            inches: None,
            stop: None,
            drivers: None,
            coord: None,
            tool_length: None,
            inverse_time: None,
            spindle: None,
            coolant: None,
            axes: [None; N],
            ijk: [None; 3],
            r: None,
            f: None,
            l: None,
            p: None,
            s: None,
            t: None,
            n: None,
        }
    }

    /// Claims a modal group: a second command of one group is an error.
    fn claim(&mut self, g: u16) -> Result<(), Error> {
        if self.groups & g != 0 {
            return Err(Error::ModalGroupViolation);
        }
        self.groups |= g;
        Ok(())
    }

    /// Claims the axis words for a command (G0/G1 or G92): only one may use them.
    fn axis_command(&mut self) -> Result<(), Error> {
        if self.axis_cmd {
            return Err(Error::AxisCommandConflict);
        }
        self.axis_cmd = true;
        Ok(())
    }

    pub fn has_axes(&self) -> bool {
        self.axes.iter().any(Option::is_some)
    }

    /// Modal groups of the block's G/M commands, as bits of [`group`].
    pub fn groups(&self) -> u16 {
        self.groups
    }
}

/// Parses a cleaned line (upper case, no whitespace or comments) into a block.
pub fn parse<const N: usize>(line: &[u8]) -> Result<Block<N>, Error> {
    let mut b = Block::<N>::empty();
    let mut i = 0;
    while i < line.len() {
        let letter = line[i];
        if !letter.is_ascii_uppercase() {
            return Err(Error::ExpectedCommandLetter);
        }
        i += 1;
        let v = parse_number(line, &mut i)?;
        match letter {
            b'G' => g_word(&mut b, v)?,
            b'M' => m_word(&mut b, v)?,
            _ => value_word(&mut b, letter, v)?,
        }
    }
    Ok(b)
}

/// Splits a command number into its integer part and Grbl's two-digit mantissa (G91.1 → 91, 10).
fn split_code(v: f32) -> Result<(u32, u32), Error> {
    if !(0.0..1000.0).contains(&v) {
        return Err(Error::UnsupportedCommand);
    }
    let int = libm::truncf(v);
    Ok((u32_of(int), round_u32(100.0 * (v - int))))
}

#[inline(never)]
fn g_word<const N: usize>(b: &mut Block<N>, v: f32) -> Result<(), Error> {
    use group::*;
    let (code, mut mantissa) = split_code(v)?;
    let g = match code {
        0..=3 | 80 => {
            if code != 80 {
                b.axis_command()?;
            }
            b.motion = Some(match code {
                0 => Motion::Rapid,
                1 => Motion::Linear,
                2 => Motion::CwArc,
                3 => Motion::CcwArc,
                _ => Motion::Cancel,
            });
            MOTION
        }
        38 => {
            b.axis_command()?;
            if !(20..=50).contains(&mantissa) || mantissa % 10 != 0 {
                return Err(Error::UnsupportedCommand);
            }
            b.motion = Some(Motion::Probe((mantissa / 10) as u8));
            mantissa = 0;
            MOTION
        }
        4 | 10 | 28 | 30 | 53 | 92 => {
            non_modal(b, code, &mut mantissa)?;
            NON_MODAL
        }
        43 | 49 => {
            // G43.1 and G49 are axis commands (Grbl, after NIST): no motion in their block.
            b.axis_command()?;
            b.tool_length = Some(match (code, mantissa) {
                (49, _) => false,
                (_, 10) => true,
                _ => return Err(Error::UnsupportedCommand),
            });
            mantissa = 0;
            TOOL_LENGTH
        }
        54..=59 => {
            b.coord = Some((code - 54) as u8);
            COORD
        }
        17..=19 => {
            b.plane = Some(code as u8);
            PLANE
        }
        20 | 21 => {
            b.inches = Some(code == 20);
            UNITS
        }
        90 | 91 if mantissa == 0 => {
            b.relative = Some(code == 91);
            DISTANCE
        }
        91 if mantissa == 10 => {
            mantissa = 0;
            ARC_DISTANCE
        }
        93 | 94 => {
            b.inverse_time = Some(code == 93);
            FEED_MODE
        }
        40 => CUTTER,
        61 => PATH,
        // Probing.
        _ => return Err(Error::UnsupportedCommand),
    };
    if mantissa != 0 {
        return Err(Error::CommandValueNotInteger);
    }
    b.claim(g)
}

/// Group 0: G4, G10, G28(.1), G30(.1), G53, G92(.1); clears the mantissa it accepts.
fn non_modal<const N: usize>(b: &mut Block<N>, code: u32, mantissa: &mut u32) -> Result<(), Error> {
    // G10/G28/G30/G92 use the axis words (their .1 forms do not).
    if matches!(code, 10 | 28 | 30 | 92) && *mantissa == 0 {
        b.axis_command()?;
    }
    let k = (code == 30) as u8;
    b.non_modal = Some(match (code, *mantissa) {
        (4, _) => NonModal::Dwell,
        (10, _) => NonModal::SetCoordData,
        (53, _) => NonModal::Absolute,
        (28 | 30, 0) => NonModal::GoHome(k),
        (28 | 30, 10) => NonModal::SetHome(k),
        (92, 0) => NonModal::SetPosition,
        (92, 10) => NonModal::ResetOffset,
        _ => return Err(Error::UnsupportedCommand),
    });
    if matches!(code, 28 | 30 | 92) {
        *mantissa = 0;
    }
    Ok(())
}

fn m_word<const N: usize>(b: &mut Block<N>, v: f32) -> Result<(), Error> {
    use group::*;
    let (code, mantissa) = split_code(v)?;
    if mantissa != 0 {
        return Err(Error::CommandValueNotInteger);
    }
    let g = match code {
        0 | 1 | 2 | 30 => {
            b.stop = Some(match code {
                0 => Stop::Pause,
                1 => Stop::Optional,
                _ => Stop::End,
            });
            STOP
        }
        3..=5 => {
            b.spindle = Some(match code {
                3 => SpindleDir::Cw,
                4 => SpindleDir::Ccw,
                _ => SpindleDir::Off,
            });
            SPINDLE
        }
        7..=9 => {
            b.coolant = Some(code as u8);
            COOLANT
        }
        17 | 18 | 84 => {
            b.drivers = Some(code == 17);
            DRIVERS
        }
        // Tool change and the rest: nothing here could do them.
        _ => return Err(Error::UnsupportedCommand),
    };
    b.claim(g)
}

#[inline(never)]
fn value_word<const N: usize>(b: &mut Block<N>, letter: u8, v: f32) -> Result<(), Error> {
    let slot = match letter {
        b'F' => &mut b.f,
        b'L' => &mut b.l,
        b'N' => &mut b.n,
        b'P' => &mut b.p,
        b'S' => &mut b.s,
        b'T' => &mut b.t,
        b'I' | b'J' | b'K' => &mut b.ijk[(letter - b'I') as usize],
        b'R' => &mut b.r,
        _ => match AXIS_NAMES[..N].iter().position(|&a| a as u8 == letter) {
            Some(i) => &mut b.axes[i],
            None => return Err(Error::UnsupportedCommand),
        },
    };
    if slot.is_some() {
        return Err(Error::WordRepeated);
    }
    if v < 0.0 && matches!(letter, b'F' | b'N' | b'P' | b'S' | b'T') {
        return Err(Error::NegativeValue);
    }
    *slot = Some(v);
    Ok(())
}

/// What a block asks for, in Grbl's execution order: dwell, offsets, motion, then
/// drivers off / pause / end. Positions are machine millimetres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Effects<const N: usize> {
    /// M17 (before the motion) / M18, M84 (after it).
    pub drivers: Option<bool>,
    /// G4: dwell this many ms once the queue has run out.
    pub dwell_ms: Option<u32>,
    /// G10 / G28.1 / G30.1: stored slot (0..=5 G54..G59, 6 G28, 7 G30) and its new value.
    pub coord_write: Option<(usize, [f32; N])>,
    /// G92 / G92.1: the new G92 offset.
    pub g92: Option<[f32; N]>,
    /// G43.1 / G49: the new tool length offset.
    pub tlo: Option<f32>,
    /// G0/G1 (or G28/G30's intermediate point): machine target of every axis, and whether it
    /// is a rapid.
    pub motion: Option<([f32; N], bool)>,
    /// G2/G3, checked (machine mm).
    pub arc: Option<Arc<N>>,
    /// G28/G30: the rapid to the stored position that follows.
    pub home: Option<[f32; N]>,
    pub stop: Option<Stop>,
    /// G38.2–G38.5 (2–5): `motion` is a probe move; 0 when not.
    pub probe: u8,
}

impl<const N: usize> Effects<N> {
    /// Nothing to do.
    #[inline(never)]
    pub fn none() -> Self {
        Effects { drivers: None, dwell_ms: None, coord_write: None, g92: None, tlo: None, motion: None, arc: None, home: None, stop: None, probe: 0 }
    }
}

/// The parser state that outlives a line (Grbl's `gc_state.modal` plus F, S, T).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Modal {
    pub motion: Motion,
    pub plane: u8,
    pub relative: bool,
    pub inches: bool,
    /// Work coordinate system, 0..=5 for G54..G59.
    pub coord: u8,
    /// G43.1 in force (else G49).
    pub tlo: bool,
    /// G93: F is the inverse of each move's time in minutes, given on every motion line.
    pub inverse_time: bool,
    /// Feed rate, mm/min, or 1/min under G93 (0: none yet).
    pub feed: f32,
    /// S.
    pub spindle: f32,
    /// M3 / M4 / M5.
    pub spindle_dir: SpindleDir,
    /// M7 / M8 bits ([`MIST`], [`FLOOD`]); M9 clears both.
    pub coolant: u8,
    pub tool: u32,
}

impl Default for Modal {
    fn default() -> Self {
        Self::RESET
    }
}

impl Modal {
    /// After power-up or soft reset: G0 G54 G17 G90 G21 G94 G49, no feed.
    pub const RESET: Modal = Modal {
        motion: Motion::Rapid,
        plane: 17,
        relative: false,
        inches: false,
        coord: 0,
        tlo: false,
        inverse_time: false,
        feed: 0.0,
        spindle: 0.0,
        spindle_dir: SpindleDir::Off,
        coolant: 0,
        tool: 0,
    };

    /// [`Self::interpret_with`] with no work offsets.
    pub fn interpret<const N: usize>(&self, b: &Block<N>, pos: &[f32; N]) -> Result<(Modal, Effects<N>), Error> {
        self.interpret_with(b, pos, &Offsets::default())
    }

    /// Applies `b` to a copy of the state, given the current machine position (mm) and the
    /// offsets in force: the new state and what to do. Nothing changes on error.
    pub fn interpret_with<const N: usize>(
        &self,
        b: &Block<N>,
        pos: &[f32; N],
        off: &Offsets<N>,
    ) -> Result<(Modal, Effects<N>), Error> {
        let mut fx = Effects::none();
        let m = self.interpret_into(b, pos, off, &mut fx)?;
        Ok((m, fx))
    }

    /// [`Self::interpret_with`] writing what to do into `fx` (given as [`Effects::none`]), so
    /// the effects, half a kilobyte on seven axes, are not copied on the way out.
    pub fn interpret_into<const N: usize>(
        &self,
        b: &Block<N>,
        pos: &[f32; N],
        off: &Offsets<N>,
        fx: &mut Effects<N>,
    ) -> Result<Modal, Error> {
        let mut m = *self;
        if b.n.is_some_and(|n| n > MAX_LINE_NUMBER) {
            return Err(Error::InvalidLineNumber);
        }
        m.inches = b.inches.unwrap_or(m.inches);
        m.relative = b.relative.unwrap_or(m.relative);
        m.plane = b.plane.unwrap_or(m.plane);
        m.motion = b.motion.unwrap_or(m.motion);
        m.coord = b.coord.unwrap_or(m.coord);
        m.tlo = b.tool_length.unwrap_or(m.tlo);
        let unit = if m.inches { 25.4 } else { 1.0 };
        m.inverse_time = b.inverse_time.unwrap_or(m.inverse_time);
        let arc_mode = matches!(m.motion, Motion::CwArc | Motion::CcwArc);
        let probe = matches!(m.motion, Motion::Probe(_));
        let feed_motion = arc_mode || probe || m.motion == Motion::Linear;
        // A motion command: axis words no non-modal command takes, or an explicit G0-G3.
        let axis_nonmodal = b.tool_length.is_some()
            || matches!(b.non_modal, Some(NonModal::SetCoordData | NonModal::SetPosition | NonModal::GoHome(_)));
        let moves = !axis_nonmodal && (b.has_axes() || b.motion.is_some_and(|mo| mo != Motion::Cancel));
        if m.inverse_time {
            // G93 (Grbl): every motion line carries its own F; nothing carries over.
            if feed_motion && moves && b.f.is_none() {
                return Err(Error::UndefinedFeedRate);
            }
            m.feed = b.f.unwrap_or(0.0);
        } else if let Some(f) = b.f {
            m.feed = f * unit;
        } else if self.inverse_time {
            m.feed = 0.0; // G93 to G94 without F: no feed rate (Grbl)
        }
        if let Some(s) = b.s {
            m.spindle = s;
        }
        m.spindle_dir = b.spindle.unwrap_or(m.spindle_dir);
        m.coolant = match b.coolant {
            Some(7) => m.coolant | MIST,
            Some(8) => m.coolant | FLOOD,
            Some(_) => 0,
            None => m.coolant,
        };
        if let Some(t) = b.t {
            if t > 255.0 {
                return Err(Error::MaxValueExceeded);
            }
            m.tool = u32_of(t);
        }
        fx.drivers = b.drivers;
        fx.stop = b.stop;
        let nm = b.non_modal;
        if b.l.is_some() && nm != Some(NonModal::SetCoordData) {
            return Err(Error::UnusedWords);
        }
        match (nm, b.p) {
            (Some(NonModal::Dwell), None) => return Err(Error::ValueWordMissing),
            (Some(NonModal::Dwell), Some(p)) if p > MAX_DWELL_S => return Err(Error::BadNumberFormat),
            (Some(NonModal::Dwell), Some(p)) => fx.dwell_ms = Some(round_u32(p * 1000.0)),
            (Some(NonModal::SetCoordData), _) => {}
            (_, Some(_)) => return Err(Error::UnusedWords),
            _ => {}
        }
        let in_range = |v: f32| if libm::fabsf(v) <= MAX_MM { Ok(v) } else { Err(Error::InvalidTarget) };
        let mut words = [None; N];
        for (w, a) in words.iter_mut().zip(&b.axes) {
            *w = a.map(|v| in_range(v * unit)).transpose()?;
        }
        if let Some(on) = b.tool_length {
            // G43.1 takes exactly the tool length axis.
            let only_z = words.iter().enumerate().all(|(i, w)| w.is_some() == (i == crate::grbl::coords::TLO_AXIS));
            if on && !only_z {
                return Err(Error::G43DynamicAxisError);
            }
            fx.tlo = Some(if on { words.get(crate::grbl::coords::TLO_AXIS).copied().flatten().unwrap_or(0.0) } else { 0.0 });
        }
        match nm {
            Some(NonModal::SetCoordData) => fx.coord_write = Some(set_coord_data(b, &words, pos, off, m.coord)?),
            Some(NonModal::SetPosition) => {
                if !b.has_axes() {
                    return Err(Error::NoAxisWords);
                }
                fx.g92 = Some(off.g92_for(m.coord, pos, &words));
            }
            Some(NonModal::ResetOffset) => fx.g92 = Some([0.0; N]),
            Some(NonModal::SetHome(k)) => fx.coord_write = Some((G28 + k as usize, *pos)),
            Some(NonModal::Absolute) if !matches!(m.motion, Motion::Rapid | Motion::Linear) => {
                return Err(Error::G53InvalidMotionMode)
            }
            _ => {}
        }
        if b.has_axes() && m.motion == Motion::Cancel {
            return Err(Error::AxisWordsExist);
        }
        let uses_axes = b.tool_length.is_some() || matches!(nm, Some(NonModal::SetCoordData | NonModal::SetPosition));
        if probe && moves && !uses_axes && !b.has_axes() {
            return Err(Error::NoAxisWords);
        }
        if (b.has_axes() || (moves && arc_mode)) && !uses_axes {
            let mut target = *pos;
            for (i, t) in target.iter_mut().enumerate() {
                if let Some(w) = words[i] {
                    *t = in_range(match nm {
                        Some(NonModal::Absolute) => w,
                        _ if m.relative => pos[i] + w,
                        _ => off.to_machine(m.coord, i, w),
                    })?;
                }
            }
            let home = matches!(nm, Some(NonModal::GoHome(_)));
            if feed_motion && !home && m.feed <= 0.0 {
                return Err(Error::UndefinedFeedRate);
            }
            if let (Motion::Probe(k), false) = (m.motion, home) {
                // Grbl: a probe to where the machine already is (error:33).
                if target == *pos {
                    return Err(Error::InvalidTarget);
                }
                fx.probe = k;
            }
            if arc_mode && !home {
                fx.arc = Some(arc(b, &m, pos, target, unit)?);
            } else {
                fx.motion = Some((target, home || m.motion == Motion::Rapid));
            }
        }
        // I J K R that no arc used (also I J K beside R): Grbl's unused words.
        let arc_words = b.ijk.iter().any(Option::is_some) as u8 + b.r.is_some() as u8;
        if arc_words > fx.arc.is_some() as u8 {
            return Err(Error::UnusedWords);
        }
        if let Some(NonModal::GoHome(k)) = nm {
            fx.home = Some(off.home(k, pos, &words));
        }
        if b.stop == Some(Stop::End) {
            m = Modal {
                motion: Motion::Linear,
                plane: 17,
                relative: false,
                coord: 0,
                inverse_time: false,
                spindle_dir: SpindleDir::Off,
                coolant: 0,
                ..m
            };
        }
        Ok(m)
    }
}

/// G10 L2/L20 P: the slot it writes and the slot's new value (Grbl's checks and order).
fn set_coord_data<const N: usize>(
    b: &Block<N>,
    words: &[Option<f32>; N],
    pos: &[f32; N],
    off: &Offsets<N>,
    active: u8,
) -> Result<(usize, [f32; N]), Error> {
    if !b.has_axes() {
        return Err(Error::NoAxisWords);
    }
    if b.p.is_none() && b.l.is_none() {
        return Err(Error::ValueWordMissing);
    }
    let p = libm::truncf(b.p.unwrap_or(0.0));
    if p > 6.0 {
        return Err(Error::UnsupportedCoordSys);
    }
    let l20 = match b.l.map(libm::truncf) {
        Some(20.0) => true,
        Some(2.0) => false,
        _ => return Err(Error::UnsupportedCommand),
    };
    let slot = if p > 0.0 { u32_of(p) as usize - 1 } else { active as usize };
    Ok((slot, off.g10(slot, l20, pos, words)))
}

/// G2/G3 words to a checked arc, in Grbl's order: axis words (`error:26`), axis words in the
/// plane (`error:32`), then the geometry ([`Arc::new`]).
fn arc<const N: usize>(b: &Block<N>, m: &Modal, pos: &[f32; N], target: [f32; N], unit: f32) -> Result<Arc<N>, Error> {
    if !b.has_axes() {
        return Err(Error::NoAxisWords);
    }
    let (p, q) = crate::planning::arc::plane_axes(m.plane);
    if b.axes.get(p).copied().flatten().is_none() && b.axes.get(q).copied().flatten().is_none() {
        return Err(Error::NoAxisWordsInPlane);
    }
    let center = match b.r {
        Some(r) => Center::Radius(r * unit),
        None => Center::Offsets(b.ijk.map(|o| o.map(|v| v * unit))),
    };
    Arc::new(m.plane, *pos, target, m.motion == Motion::CwArc, center)
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
        let mut r = 0x2545_F491_4F6C_DD1Du64;
        let mut next = |n: u64| {
            r ^= r << 13;
            r ^= r >> 7;
            r ^= r << 17;
            r % n
        };
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
