//! Endpoint 0 as a host drives it (`ddastep::usb::control`): the descriptors parse as Linux's
//! and Windows' drivers parse them and follow the chapter 9 / CDC 1.1 rules they rely on;
//! control reads of any wLength split into 64-byte packets with a zero-length one only where
//! needed; SET_ADDRESS takes effect after its status stage; the CDC requests; anything else
//! STALLs; garbage never panics and the next good request is answered.

use std::collections::VecDeque;

use ddastep::usb::control::{Control, Ep0, Split};
use ddastep::usb::descriptors::{BULK_IN_EP, BULK_OUT_EP, CONFIG, DEVICE, EP0_LEN, LANGIDS, MANUFACTURER, NOTIFY_EP, PRODUCT};
use proptest::prelude::*;

/// Endpoint 0 as the test sees it: the IN packets loaded, STALL, the address set.
#[derive(Default)]
struct Rec {
    loaded: VecDeque<Vec<u8>>,
    stalled: bool,
    address: Option<u8>,
    /// Endpoints whose data toggle was restarted at DATA0, in order.
    toggles: Vec<u8>,
}

impl Ep0 for Rec {
    fn write(&mut self, data: &[u8]) {
        assert!(data.len() <= EP0_LEN, "IN packet of {} bytes", data.len());
        self.loaded.push_back(data.to_vec());
    }
    fn stall(&mut self) {
        self.stalled = true;
    }
    fn set_address(&mut self, addr: u8) {
        self.address = Some(addr);
    }
    fn clear_toggle(&mut self, addr: u8) {
        self.toggles.push(addr);
    }
}

fn setup(request_type: u8, request: u8, value: u16, index: u16, length: u16) -> [u8; 8] {
    let [v0, v1] = value.to_le_bytes();
    let [i0, i1] = index.to_le_bytes();
    let [l0, l1] = length.to_le_bytes();
    [request_type, request, v0, v1, i0, i1, l0, l1]
}

#[derive(Debug, PartialEq, Eq)]
struct Stalled;

/// One control read as a host runs it: SETUP, IN packets until a short one or wLength bytes,
/// then the zero-length status OUT. The packets as received.
fn read_packets(ctl: &mut Control, ep: &mut Rec, s: [u8; 8]) -> Result<Vec<Vec<u8>>, Stalled> {
    let length = u16::from_le_bytes([s[6], s[7]]) as usize;
    ctl.setup(ep, &s);
    let mut packets = Vec::new();
    let mut got = 0;
    loop {
        if ep.stalled {
            return Err(Stalled);
        }
        let p = ep.loaded.pop_front().expect("an IN packet loaded");
        assert!(ep.loaded.is_empty(), "two IN packets loaded at once");
        got += p.len();
        let last = p.len() < EP0_LEN || got >= length;
        packets.push(p);
        ctl.in_complete(ep);
        if last {
            break;
        }
    }
    assert!(got <= length, "{got} bytes for wLength {length}");
    if length == 0 {
        // No data stage: that packet was the status stage.
        assert_eq!(packets, [Vec::<u8>::new()]);
        return Ok(Vec::new());
    }
    assert!(ep.loaded.is_empty(), "a packet after the last one: {:?}", ep.loaded);
    ctl.out(ep, &[]);
    Ok(packets)
}

fn read(ctl: &mut Control, s: [u8; 8]) -> Result<Vec<u8>, Stalled> {
    read_packets(ctl, &mut Rec::default(), s).map(|p| p.concat())
}

/// A control write with no data stage (or `data` as its OUT stage): true when acknowledged.
fn write(ctl: &mut Control, ep: &mut Rec, s: [u8; 8], data: Option<&[u8]>) -> bool {
    ctl.setup(ep, &s);
    if let Some(d) = data {
        if ep.stalled {
            return false;
        }
        assert!(ep.loaded.is_empty(), "IN packet before the OUT data stage");
        ctl.out(ep, d);
    }
    if ep.stalled {
        return false;
    }
    assert_eq!(ep.loaded.pop_front().as_deref(), Some(&[][..]), "status stage: a zero-length IN");
    ctl.in_complete(ep);
    true
}

fn descriptor(kind: u8, index: u8, length: u16) -> [u8; 8] {
    setup(0x80, 6, (kind as u16) << 8 | index as u16, if kind == 3 && index != 0 { 0x0409 } else { 0 }, length)
}

/// The configuration as a host walks it: every descriptor's length inside the total, the
/// interfaces and their endpoints counted, the CDC functional descriptors.
#[test]
fn descriptors_follow_chapter_9_and_cdc_acm() {
    let mut ctl = Control::new();
    let d = read(&mut ctl, descriptor(1, 0, 64)).unwrap();
    assert_eq!(d, DEVICE);
    assert_eq!((d[0], d[1]), (18, 1));
    assert_eq!(u16::from_le_bytes([d[2], d[3]]), 0x0200, "bcdUSB 2.00 (no BOS read)");
    assert_eq!((d[4], d[5], d[6]), (0x02, 0, 0), "CDC at the device level, no IAD");
    assert_eq!(d[7] as usize, EP0_LEN);
    assert_eq!((d[14], d[15], d[16], d[17]), (1, 2, 0, 1));

    let head = read(&mut ctl, descriptor(2, 0, 9)).unwrap();
    let total = u16::from_le_bytes([head[2], head[3]]);
    let c = read(&mut ctl, descriptor(2, 0, total)).unwrap();
    assert_eq!(c, CONFIG);
    assert_eq!(c.len(), total as usize);
    assert_eq!((c[1], c[5], c[7] & 0x80), (2, 1, 0x80));
    let mut at = 0;
    let mut interfaces = Vec::new(); // (number, class, endpoints declared, endpoints found)
    let mut functional = Vec::new();
    let mut endpoints = Vec::new();
    while at < c.len() {
        let x = &c[at..at + c[at] as usize];
        assert!(x.len() >= 2);
        match x[1] {
            2 => assert_eq!(x.len(), 9),
            4 => {
                assert_eq!(x.len(), 9);
                assert_eq!(x[3], 0, "alternate setting");
                interfaces.push((x[2], x[5], x[4], 0));
            }
            0x24 => functional.push(x.to_vec()),
            5 => {
                assert_eq!(x.len(), 7);
                let (_, class, _, found) = interfaces.last_mut().expect("endpoint before an interface");
                *found += 1;
                let size = u16::from_le_bytes([x[4], x[5]]);
                match (*class, x[3] & 3) {
                    (0x02, 3) => assert!(x[2] & 0x80 != 0 && x[6] != 0 && size <= 64, "notification {x:02x?}"),
                    (0x0A, 2) => assert_eq!(size, 64),
                    k => panic!("endpoint type {k:?}"),
                }
                endpoints.push(x[2]);
            }
            t => panic!("descriptor type {t:#x}"),
        }
        at += x.len();
    }
    assert_eq!(at, c.len());
    assert_eq!(c[4] as usize, interfaces.len(), "bNumInterfaces");
    assert_eq!(interfaces.iter().map(|i| (i.0, i.1)).collect::<Vec<_>>(), [(0, 0x02), (1, 0x0A)]);
    for i in &interfaces {
        assert_eq!(i.2, i.3, "bNumEndpoints of interface {}", i.0);
    }
    let mut sorted = endpoints.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), endpoints.len(), "endpoint addresses repeat: {endpoints:02x?}");
    let subtypes: Vec<u8> = functional.iter().map(|f| f[2]).collect();
    assert_eq!(subtypes[0], 0x00, "the header comes first");
    for t in [0x00, 0x01, 0x02, 0x06] {
        assert!(subtypes.contains(&t), "functional descriptor {t:#x}");
    }
    let union = functional.iter().find(|f| f[2] == 6).unwrap();
    assert_eq!(&union[3..], [0, 1]);

    let langs = read(&mut ctl, descriptor(3, 0, 255)).unwrap();
    assert_eq!(langs, LANGIDS);
    assert_eq!(u16::from_le_bytes([langs[2], langs[3]]), 0x0409);
    let mut strings = Vec::new();
    for (i, want) in [(1, &MANUFACTURER[..]), (2, &PRODUCT[..])] {
        let s = read(&mut ctl, descriptor(3, i, 255)).unwrap();
        assert_eq!(s, want);
        assert!(s.len() % 2 == 0 && s[0] as usize == s.len() && s[1] == 3);
        let units: Vec<u16> = s[2..].chunks(2).map(|p| u16::from_le_bytes([p[0], p[1]])).collect();
        strings.push(String::from_utf16(&units).unwrap());
    }
    assert_eq!(strings, ["ddastep", "ddastep Grbl"]);
}

/// What the device does not have STALLs, as Windows (device qualifier, for a bcdUSB 2.00
/// device) and Linux (BOS for 2.01+) expect; so do features it has not and malformed writes.
#[test]
fn unknown_requests_stall() {
    let mut ctl = Control::new();
    for s in [
        descriptor(6, 0, 10),       // device qualifier: full speed only
        descriptor(7, 0, 9),        // other speed configuration
        descriptor(0x0F, 0, 5),     // BOS
        descriptor(3, 3, 255),      // no serial number string
        descriptor(2, 1, 9),        // one configuration
        setup(0x00, 3, 1, 0, 0),    // SET_FEATURE(DEVICE_REMOTE_WAKEUP): not offered
        setup(0x00, 9, 2, 0, 0),    // SET_CONFIGURATION 2
        setup(0x00, 5, 3, 0, 4),    // SET_ADDRESS with a data stage
        setup(0x21, 0x20, 0, 0, 6), // SET_LINE_CODING of 6 bytes
        setup(0xC0, 0x01, 0, 0, 8), // a vendor request
        setup(0x01, 11, 1, 1, 0),   // SET_INTERFACE alternate setting 1
    ] {
        let mut ep = Rec::default();
        ctl.setup(&mut ep, &s);
        assert!(ep.stalled, "{s:02x?} answered {:?}", ep.loaded);
        assert!(ep.loaded.is_empty(), "{s:02x?}");
        assert_eq!(ep.address, None);
    }
    // A STALL lasts until the next SETUP only.
    assert_eq!(read(&mut ctl, descriptor(1, 0, 18)).unwrap(), DEVICE);
}

/// SET_ADDRESS: the status stage goes out at address 0, the new address after it (§9.4.6).
#[test]
fn set_address_applies_after_the_status_stage() {
    let mut ctl = Control::new();
    let mut ep = Rec::default();
    ctl.setup(&mut ep, &setup(0x00, 5, 23, 0, 0));
    assert_eq!(ep.loaded.pop_front().as_deref(), Some(&[][..]));
    assert_eq!(ep.address, None, "address set before the status stage");
    ctl.in_complete(&mut ep);
    assert_eq!(ep.address, Some(23));
    // A completion later (stray) sets nothing again.
    ep.address = None;
    ctl.in_complete(&mut ep);
    assert_eq!(ep.address, None);
}

/// SET_CONFIGURATION (the first one and one mid-session, as macOS sends) restarts every
/// non-control endpoint's toggle at DATA0 (§9.1.1.5); CLEAR_FEATURE(ENDPOINT_HALT) restarts
/// the one it names (§9.4.5), never endpoint 0's (its toggles follow the SETUP).
#[test]
fn set_configuration_and_clear_halt_restart_the_toggles() {
    let mut ctl = Control::new();
    let mut ep = Rec::default();
    for _ in 0..2 {
        assert!(write(&mut ctl, &mut ep, setup(0x00, 9, 1, 0, 0), None));
        assert_eq!(std::mem::take(&mut ep.toggles), [NOTIFY_EP, BULK_OUT_EP, BULK_IN_EP]);
    }
    for e in [BULK_OUT_EP, BULK_IN_EP] {
        assert!(write(&mut ctl, &mut ep, setup(0x02, 1, 0, e as u16, 0), None));
        assert_eq!(std::mem::take(&mut ep.toggles), [e]);
    }
    for e in [0x00, 0x80] {
        assert!(write(&mut ctl, &mut ep, setup(0x02, 1, 0, e, 0), None));
    }
    assert!(ep.toggles.is_empty(), "{:?}", ep.toggles);
}

/// Configuration, DTR and the line coding; a bus reset forgets them.
#[test]
fn cdc_requests_and_reset() {
    let mut ctl = Control::new();
    let mut ep = Rec::default();
    assert_eq!(read(&mut ctl, setup(0x80, 8, 0, 0, 1)).unwrap(), [0]);
    assert!(write(&mut ctl, &mut ep, setup(0x00, 9, 1, 0, 0), None));
    assert!(ctl.configured());
    assert_eq!(read(&mut ctl, setup(0x80, 8, 0, 0, 1)).unwrap(), [1]);
    assert_eq!(read(&mut ctl, setup(0x80, 0, 0, 0, 2)).unwrap(), [0, 0]);
    assert_eq!(read(&mut ctl, setup(0x82, 0, 0, 0x82, 2)).unwrap(), [0, 0]);
    assert!(write(&mut ctl, &mut ep, setup(0x02, 1, 0, 0x82, 0), None), "CLEAR_FEATURE(ENDPOINT_HALT)");
    let coding = [0x80, 0x25, 0, 0, 0, 0, 8]; // 9600 8N1
    assert!(write(&mut ctl, &mut ep, setup(0x21, 0x20, 0, 0, 7), Some(&coding)));
    assert_eq!(ctl.coding(), coding);
    assert_eq!(read(&mut ctl, setup(0xA1, 0x21, 0, 0, 7)).unwrap(), coding);
    assert!(!ctl.dtr());
    assert!(write(&mut ctl, &mut ep, setup(0x21, 0x22, 3, 0, 0), None));
    assert!(ctl.dtr());
    assert!(write(&mut ctl, &mut ep, setup(0x21, 0x22, 2, 0, 0), None));
    assert!(!ctl.dtr(), "RTS alone");
    assert!(write(&mut ctl, &mut ep, setup(0x21, 0x22, 1, 0, 0), None));
    assert!(write(&mut ctl, &mut ep, setup(0x21, 0x23, 0, 0, 0), None), "SEND_BREAK");
    assert!(ctl.dtr() && ctl.configured());
    assert!(!ep.stalled);
    ctl.reset();
    assert!(!ctl.configured() && !ctl.dtr());
}

/// Every descriptor read with any wLength: its first min(wLength, length) bytes, in full
/// 64-byte packets and a short last one when shorter than wLength.
#[test]
fn descriptor_reads_of_every_wlength() {
    let mut ctl = Control::new();
    for (kind, index, d) in [(1, 0, &DEVICE[..]), (2, 0, &CONFIG[..]), (3, 0, &LANGIDS[..]), (3, 1, &MANUFACTURER[..]), (3, 2, &PRODUCT[..])] {
        for length in (0..=300).chain([1023, 1024, 4096, 0xFFFF]) {
            let mut ep = Rec::default();
            let packets = read_packets(&mut ctl, &mut ep, descriptor(kind, index, length)).unwrap();
            let n = d.len().min(length as usize);
            assert_eq!(packets.concat(), &d[..n], "type {kind} index {index} wLength {length}");
            if n == 0 {
                continue;
            }
            assert!(packets[..packets.len() - 1].iter().all(|p| p.len() == EP0_LEN));
            let zlp = n % EP0_LEN == 0 && n < length as usize;
            assert_eq!(packets.len(), n.div_ceil(EP0_LEN) + zlp as usize, "type {kind} wLength {length}");
        }
    }
}

proptest! {
    /// The data stage split of any reply and wLength: contiguous, each packet at most 64
    /// bytes, all but the last full, exactly min(reply, wLength) bytes, and a short packet
    /// (zero-length if it must) at the end exactly when the reply is shorter than wLength.
    #[test]
    fn control_read_split(reply in 0usize..1200, length in prop_oneof![0u16..1300, any::<u16>()]) {
        let mut split = Split::new(reply, length);
        let mut ranges = Vec::new();
        while let Some(r) = split.next() {
            prop_assert!(ranges.len() < 100);
            ranges.push(r);
        }
        let n = reply.min(length as usize);
        let mut at = 0;
        for (i, r) in ranges.iter().enumerate() {
            prop_assert_eq!(r.start, at);
            prop_assert!(r.len() <= EP0_LEN);
            if i + 1 < ranges.len() {
                prop_assert_eq!(r.len(), EP0_LEN);
            }
            at = r.end;
        }
        prop_assert_eq!(at, n);
        let last_short = ranges.last().is_some_and(|r| r.len() < EP0_LEN);
        if n < length as usize {
            prop_assert!(last_short, "no short packet: {:?}", ranges);
        } else {
            prop_assert!(!ranges.iter().any(|r| r.is_empty()), "a needless zero-length packet: {:?}", ranges);
        }
    }

    /// Random SETUPs, OUT packets and IN completions never panic, never load a packet over
    /// 64 bytes or more than wLength in a read; each SETUP is STALLed or answered; and a good
    /// request afterwards gets its answer.
    #[test]
    fn garbage_never_panics_and_the_next_request_is_answered(
        events in prop::collection::vec(prop_oneof![
            4 => any::<[u8; 8]>().prop_map(Some),
            2 => (0u8..=0xFF, 0u8..13, any::<u16>(), any::<u16>(), prop_oneof![0u16..200, any::<u16>()])
                .prop_map(|(t, r, v, i, l)| Some(setup(t & 0xE3, r, v, i, l))),
            1 => Just(None),
        ], 0..60),
        outs in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..80), 1..8),
        completions in prop::collection::vec(0usize..4, 1..8),
    ) {
        let mut ctl = Control::new();
        for (k, e) in events.iter().enumerate() {
            let mut ep = Rec::default();
            match e {
                Some(s) => {
                    ctl.setup(&mut ep, s);
                    let length = u16::from_le_bytes([s[6], s[7]]) as usize;
                    prop_assert!(ep.stalled || !ep.loaded.is_empty() || (s[0] & 0x80 == 0 && length > 0),
                        "{:02x?}: neither a STALL nor an answer", s);
                    let mut sent = 0;
                    for _ in 0..completions[k % completions.len()] {
                        if let Some(p) = ep.loaded.pop_front() {
                            sent += p.len();
                            prop_assert!(s[0] & 0x80 == 0 || sent <= length, "{:02x?}: {} bytes", s, sent);
                        }
                        ctl.in_complete(&mut ep);
                    }
                }
                None => ctl.out(&mut ep, &outs[k % outs.len()]),
            }
        }
        prop_assert_eq!(read(&mut ctl, descriptor(1, 0, 18)), Ok(DEVICE.to_vec()));
        prop_assert_eq!(read(&mut ctl, descriptor(2, 0, 0xFFFF)), Ok(CONFIG.to_vec()));
    }
}
