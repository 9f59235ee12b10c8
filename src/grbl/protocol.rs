//! Grbl 1.1 wire format, the receiving half: realtime bytes and the line assembler (replies:
//! [`crate::grbl::reply`]).
//!
//! Who uses it: the firmware's USART RX interrupt calls [`realtime`] on every byte and keeps the
//! others for [`crate::grbl::controller::Controller::byte`]; the controller uses the rest.
//!
//! Flow control is Grbl's character counting: a sender keeps at most 128 unacknowledged bytes in
//! flight and counts one `ok`/`error:N` per line, so every line (also an empty one, and `\r\n`
//! counted as one ending) gets exactly one reply, sent only once the line has been acted on.

use crate::error::Error;

/// Longest line kept (after whitespace and comments are stripped); Grbl keeps 80.
pub const LINE_LEN: usize = 128;
/// RX buffer size we announce in `$I` (the firmware's ring must hold at least this many bytes).
pub const RX_BUFFER_LEN: usize = 128;

/// A realtime command: acted on in the RX interrupt, never part of a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Realtime {
    /// `?`: status report ([`crate::grbl::controller::Controller::status_request`]).
    Status,
    /// `!`: feed hold (`Shared::set_hold(true)`).
    Hold,
    /// `~`: cycle start / resume (`Shared::set_hold(false)`).
    Resume,
    /// Ctrl-X (0x18): soft reset ([`crate::grbl::controller::Controller::soft_reset`]).
    Reset,
    /// 0x85: cancel the running and queued jogs
    /// ([`crate::grbl::controller::Controller::jog_cancel`]).
    JogCancel,
    /// 0x84: the safety door opened ([`crate::grbl::controller::Controller::door_command`]).
    Door,
    /// Grbl's other extended realtime bytes (0x80..=0xFF): overrides 0x90–0x9D act
    /// ([`crate::grbl::overrides::apply`]), the others are ignored.
    Extended(u8),
}

/// Classifies one received byte: `Some` for a realtime command, `None` for a line byte.
pub const fn realtime(b: u8) -> Option<Realtime> {
    match b {
        b'?' => Some(Realtime::Status),
        b'!' => Some(Realtime::Hold),
        b'~' => Some(Realtime::Resume),
        0x18 => Some(Realtime::Reset),
        0x85 => Some(Realtime::JogCancel),
        0x84 => Some(Realtime::Door),
        0x80..=0xFF => Some(Realtime::Extended(b)),
        _ => None,
    }
}

/// What one received byte completed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineEvent {
    /// Nothing yet.
    More,
    /// A line of this many bytes is ready in [`LineBuf::line`] (0: empty line).
    Line(usize),
    /// The line ended but cannot run (too long, or a byte that is not printable ASCII).
    Bad(Error),
}

/// Assembles lines the way Grbl does: whitespace and control bytes dropped, `( … )` and
/// `; …` comments stripped, `/` (block delete) ignored, letters upper-cased; `\r`, `\n` and
/// `\r\n` each end one line.
pub struct LineBuf {
    buf: [u8; LINE_LEN],
    len: usize,
    overflow: bool,
    bad: bool,
    paren: bool,
    semicolon: bool,
    after_cr: bool,
    ended: bool,
}

impl Default for LineBuf {
    fn default() -> Self {
        Self::new()
    }
}

impl LineBuf {
    pub const fn new() -> Self {
        LineBuf {
            buf: [0; LINE_LEN],
            len: 0,
            overflow: false,
            bad: false,
            paren: false,
            semicolon: false,
            after_cr: false,
            ended: false,
        }
    }

    /// Takes one byte (not a realtime one).
    pub fn push(&mut self, b: u8) -> LineEvent {
        if self.ended {
            self.reset_flags();
        }
        let after_cr = core::mem::replace(&mut self.after_cr, b == b'\r');
        if b == b'\n' && after_cr {
            return LineEvent::More; // second half of "\r\n"
        }
        if b == b'\n' || b == b'\r' {
            let ev = if self.overflow {
                LineEvent::Bad(Error::LineOverflow)
            } else if self.bad {
                LineEvent::Bad(Error::ExpectedCommandLetter)
            } else {
                LineEvent::Line(self.len)
            };
            self.ended = true;
            return ev;
        }
        if self.semicolon {
            return LineEvent::More;
        }
        if self.paren {
            self.paren = b != b')';
            return LineEvent::More;
        }
        match b {
            0..=b' ' | b'/' => {}
            b'(' => self.paren = true,
            b';' => self.semicolon = true,
            0x7F..=0xFF => self.bad = true,
            // (`get_mut`: the full buffer is the overflow, with no panic path to link.)
            _ => match self.buf.get_mut(self.len) {
                Some(c) => {
                    *c = b.to_ascii_uppercase();
                    self.len += 1;
                }
                None => self.overflow = true,
            },
        }
        LineEvent::More
    }

    /// The line just completed (valid until the next [`Self::push`]).
    pub fn line(&self) -> &[u8] {
        &self.buf[..self.len]
    }

    /// Drops any partial line (soft reset). A `\n` right after is still one empty line.
    pub fn clear(&mut self) {
        self.reset_flags();
        self.after_cr = false;
    }

    fn reset_flags(&mut self) {
        self.len = 0;
        self.overflow = false;
        self.bad = false;
        self.paren = false;
        self.semicolon = false;
        self.ended = false;
    }
}
