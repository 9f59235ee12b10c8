//! The bulk IN packet rule (`ddastep::usb::bulk_in`) over random replies and endpoint
//! refusals: every byte once and in order, packets of at most 64 bytes, a refused packet
//! offered again unchanged, and a transfer that ends on a full packet closed by a zero-length
//! one (a zero-length packet only there).

use ddastep::usb::bulk_in::InPacket;
use ddastep::usb::descriptors::BULK_LEN;
use heapless::spsc::Queue;
use proptest::prelude::*;

#[derive(Clone, Debug)]
enum Step {
    /// The firmware queues a reply of this many bytes (as room allows).
    Reply(usize),
    /// The USB task runs: the endpoint takes the packet or is still busy.
    Usb { free: bool },
}

fn steps() -> impl Strategy<Value = Vec<Step>> {
    let step = prop_oneof![
        (prop_oneof![1usize..8, Just(63), Just(64), Just(65), Just(128), 1usize..300]).prop_map(Step::Reply),
        any::<bool>().prop_map(|free| Step::Usb { free }),
    ];
    prop::collection::vec(step, 0..300)
}

proptest! {
    #[test]
    fn packets_carry_every_byte_once_and_end_transfers(steps in steps()) {
        let mut q: Queue<u8, 512> = Queue::new();
        let (mut tx_in, mut tx) = q.split();
        let mut p = InPacket::new();
        let mut queued = Vec::new();
        let mut packets: Vec<Vec<u8>> = Vec::new();
        let mut offered: Option<Vec<u8>> = None;
        let mut next = 0u8;
        let run = |free: bool, p: &mut InPacket, tx: &mut heapless::spsc::Consumer<'_, u8>,
                       packets: &mut Vec<Vec<u8>>, offered: &mut Option<Vec<u8>>| -> bool {
            let Some(pkt) = p.next(tx) else { return false };
            let pkt = pkt.to_vec();
            assert!(pkt.len() <= BULK_LEN);
            if let Some(o) = offered.take() {
                assert_eq!(&o, &pkt, "a refused packet changed");
            }
            if free {
                p.taken();
                packets.push(pkt);
            } else {
                *offered = Some(pkt);
            }
            true
        };
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
                Step::Usb { free } => {
                    run(free, &mut p, &mut tx, &mut packets, &mut offered);
                }
            }
        }
        // The host reads until the device has nothing more.
        let mut rounds = 0;
        while run(true, &mut p, &mut tx, &mut packets, &mut offered) {
            rounds += 1;
            prop_assert!(rounds < 100);
        }
        prop_assert_eq!(packets.concat(), queued);
        if let Some(last) = packets.last() {
            prop_assert!(last.len() < BULK_LEN, "the last transfer ends on a full packet");
        }
        for w in packets.windows(2) {
            prop_assert!(!w[1].is_empty() || w[0].len() == BULK_LEN, "a zero-length packet after a short one");
        }
        prop_assert!(packets.first().is_none_or(|f| !f.is_empty()), "a zero-length packet first");
    }
}
