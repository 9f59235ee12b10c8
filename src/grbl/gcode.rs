//! G-code: numbers, blocks and the modal state, for Grbl 1.1's lines, arcs, offsets and feed modes.
//!
//! Who uses it: the controller, on each line from [`crate::grbl::protocol::LineBuf`] (upper case, no
//! whitespace, no comments).
//!
//! A block is checked in full before anything happens (Grbl's rule): [`parse`] reads the words
//! and catches word-level errors in line order; [`Modal::interpret`] applies the block to a copy
//! of the modal state and yields the [`Effects`] to carry out, so a refused line changes nothing.
//! Numbers are read exactly: up to 15 significant digits as an integer, then the nearest `f32`
//! to the decimal (as `str::parse` gives). Axis words also keep the decimal itself: where the
//! machine target is the word plus whole-millimetre offsets, [`Effects::exact`] carries it
//! exactly and the planner rounds it to steps in integers (see `target_exact`).
//!
//! Files: [`number`] reads numbers, [`block`] reads a line's words into a [`Block`], this file
//! interprets a block against the modal state. The parent re-exports the children's public
//! items (`gcode::parse`, `gcode::Block`, …); the children name nothing of this file.

pub mod block;
pub mod number;

pub use block::{group, parse, parse_into, Block, Motion, NonModal, Stop};
pub use number::parse_number;

use crate::planning::arc::{Arc, Center};
use crate::planning::exact::Decimal;
use crate::planning::planner::MAX_MM;
use crate::grbl::coords::{Offsets, G28};
use crate::error::Error;
use crate::grbl::spindle::{SpindleDir, FLOOD, MIST};
use crate::num::{round_u32, u32_of};

/// Largest line number (Grbl's MAX_LINE_NUMBER).
pub const MAX_LINE_NUMBER: f32 = 10_000_000.0;
/// Longest dwell, s (keeps the wrapping millisecond clock unambiguous).
pub const MAX_DWELL_S: f32 = 1_000_000.0;

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
    /// The motion target of each axis named, exactly, where it is an exact decimal
    /// (`target_exact`); the planner rounds it to steps in integers.
    pub exact: [Option<Decimal>; N],
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
        Effects {
            drivers: None,
            dwell_ms: None,
            coord_write: None,
            g92: None,
            tlo: None,
            motion: None,
            exact: [None; N],
            arc: None,
            home: None,
            stop: None,
            probe: 0,
        }
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
            // (× 1.0 in mm is the same value: skipped.)
            *w = a.map(|v| in_range(if m.inches { v * unit } else { v })).transpose()?;
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
                    fx.exact[i] = b.exact.get(i).and_then(|d| target_exact(*d, &m, nm, pos, off, i));
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

/// The machine target of axis `i` exactly, from its word `d` as written: the word (G53; G90 with
/// no offset on the axis), times 25.4 exactly under G20, plus each offset (G90: work system,
/// G92, tool length; G91: the programmed position) whose `f32` value is a whole number or has
/// at most 12 fraction bits ([`Decimal::plus`]); `None` where an offset is not such a value
/// (G92 set at an arbitrary position, `G10 L2 X10.005` stored as 10.0050001…, G91 from a
/// position that was not one) or the sum has more than 12 significant digits (beyond
/// [`crate::planning::exact::MAX_EXACT_SIG`]): that axis is then rounded from its `f32`
/// target, as Grbl does.
#[inline(never)]
fn target_exact<const N: usize>(d: Decimal, m: &Modal, nm: Option<NonModal>, pos: &[f32; N], off: &Offsets<N>, i: usize) -> Option<Decimal> {
    let d = if m.inches { d.inches()? } else { d };
    match nm {
        Some(NonModal::Absolute) => Some(d),
        _ if m.relative => d.plus(*pos.get(i)?),
        _ => d.plus(off.wcs_of(m.coord, i))?.plus(*off.g92.get(i)?)?.plus(off.tlo_of(i)),
    }
    .filter(|d| d.exact_steps())
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
