//! The bulk IN packet rule (`ddastep::usb::bulk_in`) over random replies and host reads: every
//! byte once and in order, packets of at most 64 bytes, one packet in flight at a time, and a
//! transfer that ends on a full packet closed by a zero-length one (a zero-length packet only
//! there).

use ddastep::usb::bulk_in::InPacket;
use ddastep::usb::descriptors::BULK_LEN;
use heapless::spsc::Queue;
use proptest::prelude::*;

#[derive(Clone, Debug)]
enum Step {
    /// The firmware queues a reply of this many bytes (as room allows).
    Reply(usize),
    /// The USB task runs (and loads a packet if it may).
    Usb,
    /// The host's IN token takes the packet in flight; the device sees the completion.
    HostReads,
}

fn steps() -> impl Strategy<Value = Vec<Step>> {
    let step = prop_oneof![
        (prop_oneof![1usize..8, Just(63), Just(64), Just(65), Just(128), 1usize..300]).prop_map(Step::Reply),
        Just(Step::Usb),
        Just(Step::HostReads),
    ];
    prop::collection::vec(step, 0..300)
}

/// The endpoint: the packet loaded, if any.
struct Endpoint(Option<Vec<u8>>);

impl Endpoint {
    // the USB task: load the next packet if there is one
    fn usb(&mut self, p: &mut InPacket, tx: &mut heapless::spsc::Consumer<'_, u8>) -> bool {
        let mut buf = [0u8; BULK_LEN];
        match p.next(tx, &mut buf) {
            Some(n) => {
                assert!(self.0.is_none(), "a packet loaded over one in flight");
                self.0 = Some(buf[..n].to_vec());
                true
            }
            None => false,
        }
    }

    // the host takes the packet in flight
    fn read(&mut self, p: &mut InPacket, packets: &mut Vec<Vec<u8>>) {
        if let Some(d) = self.0.take() {
            packets.push(d);
            p.complete();
        }
    }
}

proptest! {
    #[test]
    fn packets_carry_every_byte_once_and_end_transfers(steps in steps()) {
        let mut q: Queue<u8, 512> = Queue::new();
        let (mut tx_in, mut tx) = q.split();
        let mut p = InPacket::new();
        let mut ep = Endpoint(None);
        let mut queued = Vec::new();
        let mut packets: Vec<Vec<u8>> = Vec::new();
        let mut next = 0u8;
        for s in &steps {
            match *s {
                Step::Reply(n) => {
                    for _ in 0..n {
                        if tx_in.enqueue(next).is_err() {
                            break;
                        }
                        queued.push(next);
                        next = next.wrapping_add(1);
                    }
                }
                Step::Usb => {
                    ep.usb(&mut p, &mut tx);
                }
                Step::HostReads => ep.read(&mut p, &mut packets),
            }
        }
        // The host reads until the device has nothing more.
        let mut rounds = 0;
        ep.read(&mut p, &mut packets);
        while ep.usb(&mut p, &mut tx) {
            ep.read(&mut p, &mut packets);
            rounds += 1;
            prop_assert!(rounds < 100);
        }
        prop_assert_eq!(packets.concat(), queued);
        prop_assert!(packets.iter().all(|d| d.len() <= BULK_LEN));
        if let Some(last) = packets.last() {
            prop_assert!(last.len() < BULK_LEN, "the last transfer ends on a full packet");
        }
        for w in packets.windows(2) {
            prop_assert!(!w[1].is_empty() || w[0].len() == BULK_LEN, "a zero-length packet after a short one");
        }
        prop_assert!(packets.first().is_none_or(|f| !f.is_empty()), "a zero-length packet first");
    }
}
