//! Properties of the USB receive path (`grbl::packet`): over random packet splits and RX-ring
//! states no line byte is lost, duplicated or reordered; realtime bytes act when their packet
//! is read, also with the ring full; a packet's line bytes enter the ring all at once or not at
//! all (the endpoint NAKs meanwhile).

use ddastep::grbl::packet::{Held, PACKET_LEN};
use ddastep::grbl::protocol::realtime;
use heapless::spsc::Queue;
use proptest::prelude::*;

/// A byte stream of G-code-like line bytes with realtime bytes mixed in.
fn stream() -> impl Strategy<Value = Vec<u8>> {
    let byte = prop_oneof![
        8 => prop::sample::select(b"G1X0.5Y-2F100\r\n$ ".to_vec()),
        1 => prop::sample::select(vec![b'?', b'!', b'~', 0x18, 0x85, 0x84, 0x90, 0x9F, 0xA0, 0xFF]),
        1 => any::<u8>(),
    ];
    prop::collection::vec(byte, 0..1500)
}

/// What the rig does next: the host offers a packet (the device reads it if nothing is held),
/// or the idle loop takes some bytes out of the ring.
#[derive(Clone, Debug)]
enum Step {
    Usb,
    Idle(usize),
}

fn steps() -> impl Strategy<Value = Vec<Step>> {
    let step = prop_oneof![Just(Step::Usb), (0usize..300).prop_map(Step::Idle)];
    prop::collection::vec(step, 0..400)
}

/// Splits `bytes` into packets of 1..=64 bytes at the given cut lengths.
fn packets(bytes: &[u8], cuts: &[usize]) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut at = 0;
    let mut i = 0;
    while at < bytes.len() {
        let n = (cuts[i % cuts.len()] % PACKET_LEN + 1).min(bytes.len() - at);
        out.push(bytes[at..at + n].to_vec());
        at += n;
        i += 1;
    }
    out
}

proptest! {
    #[test]
    fn no_line_byte_lost_duplicated_or_reordered(
        bytes in stream(),
        cuts in prop::collection::vec(0usize..200, 1..40),
        steps in steps(),
    ) {
        let packets = packets(&bytes, &cuts);
        // A small ring (the firmware's holds 256) so that it is often full.
        let mut ring: Queue<u8, 100> = Queue::new();
        let (mut rx_in, mut rx_out) = ring.split();
        let mut held = Held::new();
        let mut acted = Vec::new();
        let mut consumed = Vec::new();
        let mut next = 0;
        let mut naks = 0;
        // The random steps, then the host keeps sending and the idle loop keeps reading until
        // everything is through.
        let drain = (0..4 * packets.len() + 8).flat_map(|_| [Step::Usb, Step::Idle(1000)]);
        for step in steps.into_iter().chain(drain) {
            match step {
                Step::Usb => {
                    let before = rx_in.len();
                    if !held.flush(&mut rx_in) {
                        // All or nothing: a refused flush leaves the ring as it was.
                        prop_assert_eq!(rx_in.len(), before);
                    }
                    if next < packets.len() {
                        if held.is_empty() {
                            let packet = &packets[next];
                            held.take(packet, |b| match realtime(b) {
                                Some(_) => { acted.push(b); None }
                                None => Some(b),
                            });
                            next += 1;
                            // Every realtime byte of the packets read so far has acted, whatever
                            // the ring's state.
                            let sent_rt = packets[..next].concat().into_iter().filter(|&b| realtime(b).is_some()).count();
                            prop_assert_eq!(acted.len(), sent_rt);
                            let _ = held.flush(&mut rx_in);
                        } else {
                            naks += 1;
                        }
                    }
                }
                Step::Idle(n) => {
                    for _ in 0..n {
                        match rx_out.dequeue() {
                            Some(b) => consumed.push(b),
                            None => break,
                        }
                    }
                }
            }
        }
        prop_assert_eq!(next, packets.len());
        prop_assert!(held.is_empty());
        let lines: Vec<u8> = bytes.iter().copied().filter(|&b| realtime(b).is_none()).collect();
        let rt: Vec<u8> = bytes.iter().copied().filter(|&b| realtime(b).is_some()).collect();
        prop_assert_eq!(consumed, lines);
        prop_assert_eq!(acted, rt);
        let _ = naks;
    }
}

/// With the RX ring full, a packet's realtime bytes still act when it is read; its line bytes
/// wait (held, the endpoint NAKing) and enter the ring in order once there is room for all.
#[test]
fn realtime_bytes_act_with_the_ring_full() {
    // (heapless 0.9: a `Queue<_, N>` holds N - 1.)
    let mut ring: Queue<u8, 9> = Queue::new();
    let (mut rx_in, mut rx_out) = ring.split();
    for b in b"G1X1\nG1X" {
        rx_in.enqueue(*b).unwrap();
    }
    let mut held = Held::new();
    let mut acted = Vec::new();
    held.take(b"2!\n?", |b| if realtime(b).is_some() { acted.push(b); None } else { Some(b) });
    assert_eq!(acted, b"!?");
    assert!(!held.flush(&mut rx_in), "no room: held");
    assert!(!held.is_empty());
    // One byte of room is not room for both.
    rx_out.dequeue();
    assert!(!held.flush(&mut rx_in));
    assert_eq!(rx_in.len(), 7);
    rx_out.dequeue();
    assert!(held.flush(&mut rx_in));
    let rest: Vec<u8> = core::iter::from_fn(|| rx_out.dequeue()).collect();
    assert_eq!(rest, b"X1\nG1X2\n");
}
