//! Streaming as stream.py / UGS do: character counting against a 128-byte RX ring, and long
//! listings through a small TX ring.

mod protocol_rig;

use std::collections::VecDeque;

use ddastep::grbl::protocol::RX_BUFFER_LEN;
use ddastep::grbl::settings::Settings;
use protocol_rig::Bench;

/// Streams `lines` with Grbl's character-counting rule; returns every reply line in order.
fn stream(b: &mut Bench<3>, lines: &[String]) -> Vec<String> {
    let mut rx: VecDeque<u8> = VecDeque::new();
    let mut in_flight: VecDeque<usize> = VecDeque::new();
    let mut replies = Vec::new();
    let mut next = 0;
    let mut ms = 0;
    while replies.len() < lines.len() {
        // Sender: whole lines while the unacknowledged bytes fit in the RX buffer.
        while next < lines.len() && in_flight.iter().sum::<usize>() + lines[next].len() < RX_BUFFER_LEN {
            rx.extend(lines[next].bytes());
            rx.push_back(b'\n');
            in_flight.push_back(lines[next].len() + 1);
            next += 1;
        }
        assert!(rx.len() <= RX_BUFFER_LEN, "the RX ring would overflow");
        // Serial task: drain the ring while the controller takes bytes.
        while let Some(&c) = rx.front() {
            if !b.ctl.byte(c, &mut b.tx) {
                break;
            }
            rx.pop_front();
        }
        b.tick_ms();
        for l in b.take().lines() {
            if l == "ok" || l.starts_with("error:") {
                in_flight.pop_front().expect("a reply for a line never sent");
                replies.push(l.to_string());
            }
        }
        ms += 1;
        assert!(ms < 200_000, "stream stalled after {} replies", replies.len());
    }
    replies
}

#[test]
fn character_counting_stream_loses_nothing() {
    let mut b = Bench::<3>::new(Settings::BENCH);
    b.take();
    let mut lines = vec!["G91 G1 F20000".to_string()];
    let mut want = [0i64; 3];
    for i in 0..120i64 {
        let d = [(i % 7) - 3, 2 - (i % 5), (i % 3) - 1];
        lines.push(format!("X{}.{:02} Y{} Z{}.5 (move {i})", d[0], i % 100, d[1], d[2]));
        want[0] += d[0] * 100 + if d[0] < 0 { -(i % 100) } else { i % 100 };
        want[1] += d[1] * 100;
        want[2] += d[2] * 100 + if d[2] < 0 { -50 } else { 50 };
    }
    lines.push("G4 P0.01".into());
    lines.push("$G".into());
    let replies = stream(&mut b, &lines);
    assert_eq!(replies.len(), lines.len());
    assert!(replies.iter().all(|r| r == "ok"), "{replies:?}");
    b.run_to_idle(10_000);
    assert_eq!(b.shared.positions().map(i64::from), want);
    assert_eq!(b.ctl.planned_steps(), want);
}

#[test]
fn errors_in_a_stream_answer_their_own_line() {
    let mut b = Bench::<3>::new(Settings::BENCH);
    b.take();
    let lines: Vec<String> =
        ["G91 G0 X1", "G1 X1", "G0 X1", "X--1", "Y2", "M6", "G1 Z1 F100"].iter().map(|s| s.to_string()).collect();
    let replies = stream(&mut b, &lines);
    assert_eq!(replies, ["ok", "error:22", "ok", "error:2", "ok", "error:20", "ok"]);
    b.run_to_idle(10_000);
    assert_eq!(b.shared.positions(), [200, 200, 100]);
}

#[test]
fn listings_wait_for_tx_room_instead_of_being_cut() {
    let mut big = Bench::<3>::new(Settings::BENCH);
    big.take();
    let full = big.line("$$");
    let mut b = Bench::<3>::new(Settings::BENCH);
    b.take();
    b.tx.cap = ddastep::grbl::reply::REPLY_ROOM + 20;
    // The UART sends 20 bytes per millisecond here.
    for &c in b"$$\n" {
        assert!(b.ctl.byte(c, &mut b.tx));
    }
    let mut out = Vec::new();
    for _ in 0..1000 {
        let n = b.tx.buf.len().min(20);
        out.extend(b.tx.buf.drain(..n));
        b.ctl.poll(b.now_ms, &mut b.tx);
        if !b.ctl.busy() && b.tx.buf.is_empty() {
            break;
        }
    }
    assert_eq!(String::from_utf8(out).unwrap(), full);
    assert!(full.len() > b.tx.cap, "{}", full.len()); // more than the TX ring holds
    // Line bytes wait while the TX ring is nearly full, so a reply is never dropped.
    b.tx.buf = vec![b' '; 100];
    assert!(!b.ctl.byte(b'\n', &mut b.tx));
}

/// `Bf:blocks,rx` and `FS:feed,speed` of a status line.
fn bf_fs(status: &str) -> ((u32, u32), (f64, f64)) {
    let field = |name: &str| -> (String, String) {
        let f = status.split(['|', '>']).find_map(|f| f.strip_prefix(name)).unwrap_or_else(|| panic!("no {name} in {status:?}"));
        let (a, b) = f.split_once(',').unwrap();
        (a.to_string(), b.to_string())
    };
    let (b0, b1) = field("Bf:");
    let (f0, f1) = field("FS:");
    ((b0.parse().unwrap(), b1.parse().unwrap()), (f0.parse().unwrap(), f1.parse().unwrap()))
}

/// A character-counting sender (grbl-streamer, bCNC): whole lines while the unacknowledged
/// bytes, newlines included, stay within Grbl's 128-byte RX buffer.
struct Counting {
    lines: Vec<String>,
    next: usize,
    in_flight: VecDeque<usize>,
}

impl Counting {
    fn unacked(&self) -> usize {
        self.in_flight.iter().sum()
    }

    /// The lines that fit now.
    fn due(&mut self) -> Vec<String> {
        let mut v = Vec::new();
        while self.next < self.lines.len() && self.unacked() + self.lines[self.next].len() + 1 <= RX_BUFFER_LEN {
            self.in_flight.push_back(self.lines[self.next].len() + 1);
            v.push(format!("{}\n", self.lines[self.next]));
            self.next += 1;
        }
        v
    }

    /// Takes the replies in `text` up to (not including) the first status line; returns it.
    fn read<'t>(&mut self, text: &'t str) -> Option<&'t str> {
        let mut status = None;
        for l in text.lines() {
            if l.starts_with('<') {
                status = status.or(Some(l));
            } else if l == "ok" && status.is_none() {
                self.in_flight.pop_front().expect("an ok for a line never sent");
            } else {
                assert!(l == "ok" || l.is_empty(), "{l:?}");
            }
        }
        status
    }

    /// Takes the replies after the status line.
    fn read_after_status(&mut self, text: &str) {
        for l in text.lines().skip_while(|l| !l.starts_with('<')).skip(1) {
            if l == "ok" {
                self.in_flight.pop_front().expect("an ok for a line never sent");
            }
        }
    }

    fn longest(&self) -> usize {
        self.lines.iter().map(|l| l.len() + 1).max().unwrap()
    }
}

/// Checks a report's `Bf:` RX field against what the sender knows: at the report, the line
/// bytes it had not seen acknowledged (`unacked`) are in the RX ring, but for at most the one
/// line the controller is carrying out, so 128 - unacked <= rx <= 128 - unacked + longest line.
fn check_rx(status: &str, unacked: usize, longest: usize) -> u32 {
    let ((_, rx), _) = bf_fs(status);
    let lo = RX_BUFFER_LEN.saturating_sub(unacked);
    let hi = (RX_BUFFER_LEN + longest).saturating_sub(unacked).min(RX_BUFFER_LEN);
    assert!((lo..=hi).contains(&(rx as usize)), "{status}: {unacked} bytes unacknowledged, want {lo}..={hi}");
    rx
}

#[test]
fn bf_counts_the_bytes_waiting_and_fs_is_zero_once_held() {
    // 200 mm/s² on every axis: a hold from 20 mm/s decelerates for 100 ms.
    let mut b = Bench::<3>::new(Settings { accel: [200.0; 7], ..Settings::BENCH });
    b.take();
    // Bf: on.
    for l in ["$10=3", "G91 G1 F1200"] {
        assert_eq!(b.line(l), "ok\r\n");
    }
    let mut c = Counting { lines: (0..70).map(|i| format!("X1 (move {i}{})", "#".repeat(i % 9))).collect(), next: 0, in_flight: VecDeque::new() };
    let longest = c.longest();
    let (mut waiting, mut hold1, mut hold0) = (0, 0, 0);
    let mut held_since = None;
    let mut ms = 0;
    while c.in_flight.len() + c.lines.len() - c.next > 0 {
        for l in c.due() {
            b.send(&l);
        }
        b.tick_ms();
        ms += 1;
        assert!(ms < 60_000, "stalled");
        let text = b.take();
        assert!(c.read(&text).is_none());
        // Feed hold in the middle of the stream, resumed 300 ms after it came to rest.
        if c.next == 50 && held_since.is_none() && !b.shared.hold_requested() {
            b.byte(b'!');
        }
        if ms % 5 != 0 {
            continue;
        }
        b.byte(b'?');
        let text = b.take();
        let s = c.read(&text).expect("a status report").to_string();
        let rx = check_rx(&s, c.unacked(), longest);
        assert_eq!(rx as usize, RX_BUFFER_LEN - b.rx_waiting(), "{s}");
        c.read_after_status(&text);
        if b.rx_waiting() > longest {
            waiting += 1;
        }
        let (_, (feed, _)) = bf_fs(&s);
        if s.starts_with("<Hold:1") {
            assert!(feed > 0.0, "decelerating: {s}");
            hold1 += 1;
        } else if s.starts_with("<Hold:0") {
            assert_eq!(feed, 0.0, "held: {s}");
            hold0 += 1;
            let t = *held_since.get_or_insert(ms);
            if ms - t >= 300 {
                b.byte(b'~');
            }
        } else if s.starts_with("<Idle") {
            assert_eq!(feed, 0.0, "{s}");
        } else {
            assert!(s.starts_with("<Run"), "{s}");
            assert!(held_since.is_none() || hold0 > 0, "{s}");
        }
    }
    assert!(waiting >= 20, "{waiting} reports with more than a line waiting");
    assert!(hold1 >= 5 && hold0 >= 50, "{hold1} Hold:1, {hold0} Hold:0 reports");
    b.run_to_idle(10_000);
    let s = b.status();
    assert!(s.starts_with("<Idle|"), "{s}");
    assert_eq!(bf_fs(&s), ((protocol_rig::BLOCKS as u32, RX_BUFFER_LEN as u32), (0.0, 0.0)), "{s}");
    assert_eq!(b.shared.positions(), [7000, 0, 0]);
}
