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
