//! `$J=` jogging: Grbl 1.1's rules for a jog line, and its target.
//!
//! Who uses it: the controller, for `$J=` lines (idle or already jogging). A jog is a G1 at the
//! line's own F; only G20/G21, G90/G91 and G53 may appear with the axis words, N is allowed,
//! and the parser state is left alone (only the planner's position follows the jog). A jog is
//! planned like any move, so queued jogs run through the same path as G-code motion; 0x85 (or
//! `!` while jogging) cancels them (see the controller).

use crate::grbl::coords::Offsets;
use crate::grbl::gcode::{group, parse_into, Block, Modal, Motion, NonModal};
use crate::error::Error;
use crate::planning::exact::Decimal;

/// A checked jog: machine target (mm), exactly where it is a decimal
/// ([`crate::grbl::gcode::Effects::exact`]), and feed (mm/min).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jog<const N: usize> {
    pub target: [f32; N],
    pub exact: [Option<Decimal>; N],
    pub feed: f32,
}

/// Parses the text after `$J=` against the modal state, the machine position and the offsets,
/// for a machine with `axes` axes. (Not inlined: its block and effects stay off the idle
/// loop's stack frame, which is live under every G-code line.)
#[inline(never)]
pub fn plan<const N: usize>(
    line: &[u8],
    axes: usize,
    modal: &Modal,
    pos: &[f32; N],
    off: &Offsets<N>,
) -> Result<Jog<N>, Error> {
    let mut b = Block::<N>::empty();
    parse_into(line, &mut b)?;
    if b.axes.get(axes..).is_some_and(|a| a.iter().any(Option::is_some)) {
        return Err(Error::UnsupportedCommand);
    }
    if b.groups() & !(group::DISTANCE | group::UNITS | group::NON_MODAL) != 0 {
        return Err(Error::InvalidJogCommand);
    }
    if !matches!(b.non_modal, None | Some(NonModal::Absolute)) {
        return Err(Error::InvalidJogCommand);
    }
    if b.f.is_none() {
        return Err(Error::UndefinedFeedRate);
    }
    if b.s.is_some() || b.t.is_some() {
        return Err(Error::UnusedWords);
    }
    // G1 at the jog's own feed; the modal state itself is not kept.
    let jog_modal = Modal { motion: Motion::Linear, feed: 0.0, ..*modal };
    let mut fx = crate::grbl::gcode::Effects::none();
    let m = jog_modal.interpret_into(&b, pos, off, &mut fx)?;
    Ok(Jog { target: fx.motion.map_or(*pos, |(t, _)| t), exact: fx.exact, feed: m.feed })
}
