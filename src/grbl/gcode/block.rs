//! G-code blocks: a cleaned line's words into a [`Block`] (commands by modal group, value
//! words), with Grbl's word-level errors in line order.
//!
//! Who uses it: the controller ([`parse`]), then [`crate::grbl::gcode::Modal::interpret`].

use crate::error::Error;
use crate::grbl::gcode::number::parse_word;
use crate::planning::exact::Decimal;
use crate::grbl::spindle::SpindleDir;
use crate::num::{round_u32, u32_of};
use crate::AXIS_NAMES;

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
    /// G4 `P<seconds>`.
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
    /// Each axis word as written (where `axes` has it): exact step targets.
    pub exact: [Decimal; N],
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
    #[inline(never)]
    pub fn empty() -> Self {
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
            exact: [Decimal::ZERO; N],
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
    parse_into(line, &mut b)?;
    Ok(b)
}

/// [`parse`] into `b`, an empty block ([`Block::empty`]): the controller's form, where the
/// block is not moved out of a `Result` (a ~270-byte copy a line).
pub fn parse_into<const N: usize>(line: &[u8], b: &mut Block<N>) -> Result<(), Error> {
    let mut i = 0;
    while i < line.len() {
        let letter = line[i];
        if !letter.is_ascii_uppercase() {
            return Err(Error::ExpectedCommandLetter);
        }
        i += 1;
        let (v, d) = parse_word(line, &mut i)?;
        match letter {
            b'G' => g_word(b, v)?,
            b'M' => m_word(b, v)?,
            _ => value_word(b, letter, v, d)?,
        }
    }
    Ok(())
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
fn value_word<const N: usize>(b: &mut Block<N>, letter: u8, v: f32, d: Decimal) -> Result<(), Error> {
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
            Some(i) => {
                if let Some(e) = b.exact.get_mut(i) {
                    *e = d;
                }
                &mut b.axes[i]
            }
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
