//! Streaming G-code as senders do, over USART1 or the modeled USB: one line and then its
//! `ok` (stream.py's simple mode), or Grbl's character counting (UGS, bCNC, CNCjs, LaserGRBL,
//! stream.py `-s`): lines go out while the unacknowledged ones fit the 128-byte RX buffer, and
//! each `ok`/`error` frees the oldest. For the `sim` CLI and the tests.

use std::collections::VecDeque;

use anyhow::{bail, Result};

use super::Board;

/// Grbl's RX buffer that character counting fills (`$I`'s announced 128).
pub const RX_BUFFER: usize = 128;

/// The serial link a sender uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Link {
    Usart,
    Usb,
}

impl Link {
    // one write from the sender
    pub fn send(self, board: &mut Board, bytes: &[u8]) {
        match self {
            Link::Usart => board.serial_send(bytes),
            Link::Usb => board.usb_send(bytes),
        }
    }

    // everything the board sent on this link
    pub fn output(self, board: &Board) -> &[u8] {
        match self {
            Link::Usart => board.serial_bytes().0,
            Link::Usb => board.usb_bytes().0,
        }
    }
}

/// Reply lines (`ok`, `error:N`) and status reports (`<...>`) in `out[*cursor..]` that are
/// complete; moves the cursor past every complete line.
fn take_lines(out: &[u8], cursor: &mut usize) -> (Vec<String>, Vec<String>) {
    let (mut replies, mut statuses) = (Vec::new(), Vec::new());
    while let Some(n) = out[*cursor..].iter().position(|&b| b == b'\n') {
        let line = String::from_utf8_lossy(&out[*cursor..*cursor + n]).trim_end().to_string();
        *cursor += n + 1;
        if line.starts_with("ok") || line.starts_with("error") {
            replies.push(line);
        } else if line.starts_with('<') {
            statuses.push(line);
        }
    }
    (replies, statuses)
}

/// Reply lines (`ok`, `error:N`) in `out[*cursor..]` that are complete; moves the cursor past
/// every complete line.
fn take_replies(out: &[u8], cursor: &mut usize) -> Vec<String> {
    take_lines(out, cursor).0
}

/// Streams `lines` with character counting over `link`; returns the reply to each line, in
/// order. Fails if a reply takes longer than `max_wait` modeled cycles.
pub fn stream_char_count(board: &mut Board, link: Link, lines: &[String], max_wait: u64) -> Result<Vec<String>> {
    Ok(stream_char_count_polled(board, link, lines, max_wait, None)?.replies)
}

/// What a character-counted stream got back.
#[derive(Clone, Debug, Default)]
pub struct Streamed {
    /// The reply to each line, in order.
    pub replies: Vec<String>,
    /// Status reports (`<...>`) with the modeled cycle each was read at.
    pub statuses: Vec<(u64, String)>,
    /// The modeled cycle the last line was written at.
    pub last_sent: u64,
}

/// [`stream_char_count`], also sending `?` every `poll` modeled cycles (as senders poll the
/// status while streaming) if given; the status reports come back in [`Streamed::statuses`].
pub fn stream_char_count_polled(board: &mut Board, link: Link, lines: &[String], max_wait: u64, poll: Option<u64>) -> Result<Streamed> {
    let mut cursor = link.output(board).len();
    let mut in_flight: VecDeque<usize> = VecDeque::new();
    let mut queued = 0;
    let mut got = Streamed { replies: Vec::with_capacity(lines.len()), ..Streamed::default() };
    let mut next = 0;
    let mut next_poll = poll.map(|p| board.cycles() + p);
    let mut last_reply = board.cycles();
    while got.replies.len() < lines.len() {
        while next < lines.len() && queued + lines[next].len() < RX_BUFFER {
            let line = format!("{}\n", lines[next]);
            link.send(board, line.as_bytes());
            in_flight.push_back(line.len());
            queued += line.len();
            next += 1;
            got.last_sent = board.cycles();
        }
        let start = cursor;
        let until = next_poll.unwrap_or(u64::MAX).min(last_reply + max_wait);
        board.run_until(until.saturating_sub(board.cycles()), |b| link.output(b)[start..].contains(&b'\n'))?;
        let (new, statuses) = take_lines(link.output(board), &mut cursor);
        let now = board.cycles();
        got.statuses.extend(statuses.into_iter().map(|l| (now, l)));
        if !new.is_empty() {
            last_reply = now;
        }
        for r in new {
            let Some(n) = in_flight.pop_front() else { bail!("a reply with no line in flight: {r:?}") };
            queued -= n;
            got.replies.push(r);
        }
        if let (Some(t), Some(p)) = (next_poll, poll) {
            if now >= t {
                link.send(board, b"?");
                next_poll = Some(now + p);
            }
        }
        if now >= last_reply + max_wait && got.replies.len() < lines.len() {
            bail!("no reply within {max_wait} modeled cycles after {} of {} lines", got.replies.len(), lines.len());
        }
    }
    Ok(got)
}

/// Streams `lines` one at a time, each after the previous one's reply.
pub fn stream_wait_ok(board: &mut Board, link: Link, lines: &[String], max_wait: u64) -> Result<Vec<String>> {
    let mut cursor = link.output(board).len();
    let mut replies = Vec::with_capacity(lines.len());
    for line in lines {
        link.send(board, format!("{line}\n").as_bytes());
        loop {
            let start = cursor;
            let got = board.run_until(max_wait, |b| link.output(b)[start..].contains(&b'\n'))?;
            let new = take_replies(link.output(board), &mut cursor);
            if let Some(r) = new.into_iter().next() {
                replies.push(r);
                break;
            }
            if !got {
                bail!("no reply to {line:?} within {max_wait} modeled cycles");
            }
        }
    }
    Ok(replies)
}
