//! The host on the other end of the USB cable, as Linux's hub and cdc-acm drivers drive it:
//! attach debounce, bus reset, GET_DESCRIPTOR(device, 64) at address 0, a second reset,
//! SET_ADDRESS, the device descriptor, the device qualifier (which a full-speed device must
//! STALL; Windows asks), the configuration and string descriptors, SET_CONFIGURATION, the
//! probe's SET_LINE_CODING, then SET_CONTROL_LINE_STATE (DTR, RTS), SET_LINE_CODING and
//! GET_LINE_CODING (Windows' usbser reads it back) when a program opens the port. Bulk IN/OUT in 1 ms frames of [`SLOTS`] transaction slots of
//! [`SLOT_CYCLES`] (a 64-byte full-speed transaction with its token, handshake and gaps takes
//! about 50 µs), 64-byte packets; a NAKed OUT is retried in a later slot.
//!
//! The descriptors are parsed as a host does and checked against the chapter 9 and CDC 1.1
//! rules Linux's cdc-acm and Windows' usbser rely on, and so are the control transfers (no
//! more than wLength, packets of at most bMaxPacketSize0, nothing left loaded after a data
//! stage); what fails goes to [`UsbStats::errors`].
//! For `mcu.rs` (which advances it with the clock) and `board.rs`.

use std::collections::VecDeque;

use super::usb::{Handshake, UsbPeripheral};
use super::usb_splits::Splits;

/// One transaction slot (50 µs at 72 MHz).
pub const SLOT_CYCLES: u64 = 3_600;
/// Transaction slots in a 1 ms frame (after the SOF).
pub const SLOTS: u64 = 19;
/// A 1 ms frame at 72 MHz.
pub const FRAME_CYCLES: u64 = 72_000;
const MS: u64 = 72_000;
/// Linux's attach debounce (hub.c: 100 ms stable) and reset timings (10 ms reset, 10 ms
/// recovery), SET_ADDRESS recovery (2 ms, USB 2.0 §9.2.6.3).
const DEBOUNCE: u64 = 100 * MS;
const RESET_TIME: u64 = 10 * MS;
const RESET_RECOVERY: u64 = 10 * MS;
const SET_ADDRESS_RECOVERY: u64 = 2 * MS;
/// Bus idle before the device's SUSP (3 ms, USB 2.0 §7.1.7.6).
const SUSPEND_AFTER: u64 = 3 * MS;
/// A control transfer gives up after this long without progress (Linux: 5 s).
const CONTROL_TIMEOUT: u64 = 5_000 * MS;
/// The bulk packet size the host expects (full speed's largest).
const BULK_MAX: usize = 64;

/// What the host counted.
#[derive(Clone, Debug, Default)]
pub struct UsbStats {
    /// SET_CONFIGURATION completed: how many times the board was enumerated.
    pub enumerations: u64,
    /// Bulk bytes host to device and device to host.
    pub bytes_out: u64,
    pub bytes_in: u64,
    /// OUT packets the device NAKed (each retry counts).
    pub naked_out: u64,
    /// Bulk IN packets with the wrong DATA0/1 toggle (dropped as duplicates).
    pub in_toggle_errors: u64,
    /// Descriptor rule violations, stalls and timeouts.
    pub errors: Vec<String>,
    /// The configuration carries an interface association descriptor.
    pub iad: bool,
    /// The strings read (manufacturer, product).
    pub strings: Vec<String>,
}

/// The CDC ACM endpoints found in the configuration.
#[derive(Clone, Copy, Debug, Default)]
struct Cdc {
    bulk_in: u8,
    bulk_out: u8,
    notify: u8,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum What {
    Device64,
    Device,
    /// Windows asks a USB 2.0 device for its device qualifier; a full-speed-only one STALLs.
    Qualifier,
    ConfigHead,
    Config,
    BosHead,
    Bos,
    LangIds,
    Str(u8),
    SetAddress(u8),
    SetConfig,
    /// CLEAR_FEATURE(ENDPOINT_HALT) on this endpoint: its toggle restarts at DATA0 (§9.4.5).
    ClearHalt(u8),
    /// GET_LINE_CODING after SET_LINE_CODING (Windows' usbser reads it back): the bytes set.
    LineCoding([u8; 7]),
    Plain,
}

#[derive(Clone, Debug)]
enum Step {
    /// Nothing until this cycle.
    Wait(u64),
    /// SE0 on the bus (the device's RESET), then the recovery time.
    Reset,
    Control([u8; 8], Vec<u8>, What),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Setup,
    DataIn,
    DataOut,
    StatusIn,
    StatusOut,
}

struct Ctl {
    setup: [u8; 8],
    out: Vec<u8>,
    what: What,
    stage: Stage,
    got: Vec<u8>,
    sent: usize,
    toggle: bool,
    since: u64,
}

/// The host, its enumeration plan and the bulk streams.
pub struct UsbHost {
    /// The cable is in (off unless a run plugs it; the device's D+ pull-up shows unless it drives PA12 low).
    pub plugged: bool,
    /// A program has the tty open (DTR, RTS set).
    pub open: bool,
    /// Cable pulls and plugs to come: (cycle, plugged), in cycle order (`--unplug`).
    pub plug_schedule: VecDeque<(u64, bool)>,
    line_state: bool,
    attached: bool,
    suspended: bool,
    /// When the bus went idle (unplugged), for the device's SUSP.
    idle_since: Option<u64>,
    plan: VecDeque<Step>,
    ctl: Option<Ctl>,
    addr: u8,
    next_addr: u8,
    mps0: usize,
    configured: bool,
    cdc: Option<Cdc>,
    strings: [u8; 3],
    out_toggle: bool,
    in_toggle: bool,
    /// Writes not yet sent (each write is sent as 64-byte packets, the last one short).
    pub writes: VecDeque<Vec<u8>>,
    sending: Option<(Vec<u8>, usize)>,
    /// Random OUT packet lengths across writes (else 64-byte packets, each write's last short).
    pub splits: Option<Splits>,
    /// The length of the OUT packet the device NAKed: its retry sends the same bytes.
    out_len: Option<usize>,
    /// Last slot handled (absolute slot number).
    slot: u64,
    frame: u64,
    /// Bytes the device sent, with the cycle of each packet.
    pub received: Vec<u8>,
    pub rx_times: Vec<u64>,
    pub stats: UsbStats,
    in_turn: bool,
}

impl Default for UsbHost {
    fn default() -> Self {
        UsbHost {
            plugged: false,
            open: false,
            plug_schedule: VecDeque::new(),
            line_state: false,
            attached: false,
            suspended: false,
            idle_since: None,
            plan: VecDeque::new(),
            ctl: None,
            addr: 0,
            next_addr: 1,
            mps0: 64,
            configured: false,
            cdc: None,
            strings: [0; 3],
            out_toggle: false,
            in_toggle: false,
            writes: VecDeque::new(),
            sending: None,
            splits: None,
            out_len: None,
            slot: 0,
            frame: 0,
            received: Vec::new(),
            rx_times: Vec::new(),
            stats: UsbStats::default(),
            in_turn: false,
        }
    }
}

fn setup_packet(request_type: u8, request: u8, value: u16, index: u16, length: u16) -> [u8; 8] {
    let [v0, v1] = value.to_le_bytes();
    let [i0, i1] = index.to_le_bytes();
    let [l0, l1] = length.to_le_bytes();
    [request_type, request, v0, v1, i0, i1, l0, l1]
}

fn get_descriptor(kind: u8, index: u8, lang: u16, len: u16, what: What) -> Step {
    Step::Control(setup_packet(0x80, 6, (kind as u16) << 8 | index as u16, lang, len), Vec::new(), what)
}

/// SET_LINE_CODING to interface 0: rate, 1 stop bit, no parity, 8 data bits.
fn line_coding(rate: u32) -> Step {
    Step::Control(setup_packet(0x21, 0x20, 0, 0, 7), coding_bytes(rate).to_vec(), What::Plain)
}

fn coding_bytes(rate: u32) -> [u8; 7] {
    let [r0, r1, r2, r3] = rate.to_le_bytes();
    [r0, r1, r2, r3, 0, 0, 8]
}

/// GET_LINE_CODING from interface 0, expecting `rate` 8N1.
fn get_line_coding(rate: u32) -> Step {
    Step::Control(setup_packet(0xA1, 0x21, 0, 0, 7), Vec::new(), What::LineCoding(coding_bytes(rate)))
}

fn control_line_state(dtr_rts: bool) -> Step {
    Step::Control(setup_packet(0x21, 0x22, if dtr_rts { 3 } else { 0 }, 0, 0), Vec::new(), What::Plain)
}

impl UsbHost {
    /// Enumerated and configured, with the CDC endpoints known.
    pub fn configured(&self) -> bool {
        self.configured
    }

    /// Queues bytes as one write to the tty.
    pub fn write(&mut self, bytes: &[u8]) {
        if !bytes.is_empty() {
            self.writes.push_back(bytes.to_vec());
        }
    }

    /// Mid-session, as macOS (SET_CONFIGURATION again) and libusb's `clear_halt` (bulk OUT,
    /// then bulk IN) do: each resets the endpoints' toggles to DATA0 on both sides (USB 2.0
    /// §9.1.1.5, §9.4.5). The bulk streams go on after them.
    pub fn resync(&mut self) {
        let Some(cdc) = self.cdc.filter(|_| self.configured) else { return };
        self.plan.push_back(Step::Control(setup_packet(0, 9, 1, 0, 0), Vec::new(), What::SetConfig));
        for ep in [cdc.bulk_out, cdc.bulk_in | 0x80] {
            self.plan.push_back(Step::Control(setup_packet(0x02, 1, 0, ep as u16, 0), Vec::new(), What::ClearHalt(ep)));
        }
    }

    /// Bytes written and not yet taken by the device.
    pub fn pending(&self) -> usize {
        self.writes.iter().map(Vec::len).sum::<usize>() + self.sending.as_ref().map_or(0, |(d, at)| d.len() - at)
    }

    /// Pulls the cable (`false`) or plugs it back.
    pub fn set_plugged(&mut self, plugged: bool, now: u64) {
        if self.plugged == plugged {
            return;
        }
        self.plugged = plugged;
        if !plugged {
            self.detach(now);
        }
    }

    fn detach(&mut self, now: u64) {
        self.attached = false;
        self.configured = false;
        self.plan.clear();
        self.ctl = None;
        self.addr = 0;
        self.line_state = false;
        self.sending = None;
        self.out_len = None;
        self.idle_since = Some(now);
    }

    fn slot_cycle(slot: u64) -> u64 {
        (slot / SLOTS) * FRAME_CYCLES + (slot % SLOTS + 1) * SLOT_CYCLES
    }

    fn slot_at(t: u64) -> u64 {
        let frame = t / FRAME_CYCLES;
        let within = (t % FRAME_CYCLES) / SLOT_CYCLES;
        frame * SLOTS + within.saturating_sub(1).min(SLOTS - 1)
    }

    /// The next cycle at which the host does something the device notices.
    pub fn next_event(&self, dev: &UsbPeripheral, now: u64, dp_high: bool) -> Option<u64> {
        let plug = self.plug_schedule.front().map(|p| p.0.max(now));
        let host = self.host_event(dev, now, dp_high);
        match (plug, host) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    fn host_event(&self, dev: &UsbPeripheral, now: u64, dp_high: bool) -> Option<u64> {
        if let Some(idle) = self.idle_since.filter(|_| !self.suspended) {
            return Some(idle + SUSPEND_AFTER);
        }
        if !self.plugged || !dp_high {
            return None;
        }
        if !self.attached {
            return Some(now);
        }
        let next_slot = Self::slot_cycle(self.slot + 1).max(now);
        match (self.plan.front(), &self.ctl) {
            (Some(Step::Wait(t)), None) => return Some((*t).max(next_slot)),
            (Some(_), None) => return Some(next_slot),
            _ => {}
        }
        if let Some(c) = &self.ctl {
            let ready = match c.stage {
                Stage::Setup => dev.takes_setup(self.addr),
                Stage::DataIn | Stage::StatusIn => dev.ready(self.addr, 0, true),
                Stage::DataOut | Stage::StatusOut => dev.ready(self.addr, 0, false),
            };
            return Some(if ready { next_slot } else { (c.since + CONTROL_TIMEOUT).max(next_slot) });
        }
        if self.open != self.line_state {
            return Some(next_slot);
        }
        if let (Some(cdc), true) = (self.cdc, self.configured) {
            let out = (self.sending.is_some() || !self.writes.is_empty()) && dev.ready(self.addr, cdc.bulk_out, false);
            let inp = self.open && dev.ready(self.addr, cdc.bulk_in, true);
            if out || inp {
                return Some(next_slot);
            }
        }
        None
    }

    /// Runs the host up to cycle `t`; `dp_high` says whether the device's D+ pull-up shows.
    pub fn advance(&mut self, dev: &mut UsbPeripheral, t: u64, dp_high: bool) {
        while let Some(&(at, plugged)) = self.plug_schedule.front().filter(|p| p.0 <= t) {
            self.plug_schedule.pop_front();
            self.set_plugged(plugged, at);
        }
        if let Some(idle) = self.idle_since {
            if !self.suspended && idle + SUSPEND_AFTER <= t {
                self.suspended = true;
                dev.suspend();
            }
        }
        if !self.plugged || !dp_high {
            if self.attached {
                self.detach(t);
            }
            return;
        }
        if !self.attached {
            self.attached = true;
            self.idle_since = None;
            if std::mem::take(&mut self.suspended) {
                dev.wakeup();
            }
            self.plan.clear();
            self.plan.push_back(Step::Wait(t + DEBOUNCE));
            self.plan.push_back(Step::Reset);
            self.plan.push_back(get_descriptor(1, 0, 0, 64, What::Device64));
            self.slot = Self::slot_at(t);
            self.frame = t / FRAME_CYCLES;
        }
        // Frames (SOF) up to t.
        while (self.frame + 1) * FRAME_CYCLES <= t {
            self.frame += 1;
            dev.sof();
        }
        while Self::slot_cycle(self.slot + 1) <= t {
            self.slot += 1;
            let at = Self::slot_cycle(self.slot);
            self.run_slot(dev, at);
        }
    }

    // one transaction slot at cycle `at`
    fn run_slot(&mut self, dev: &mut UsbPeripheral, at: u64) {
        if self.ctl.is_none() {
            match self.plan.front().cloned() {
                Some(Step::Wait(until)) => {
                    if at >= until {
                        self.plan.pop_front();
                    }
                    return;
                }
                Some(Step::Reset) => {
                    self.plan.pop_front();
                    dev.bus_reset();
                    self.addr = 0;
                    self.configured = false;
                    self.plan.push_front(Step::Wait(at + RESET_TIME + RESET_RECOVERY));
                    return;
                }
                Some(Step::Control(setup, out, what)) => {
                    self.plan.pop_front();
                    self.ctl = Some(Ctl { setup, out, what, stage: Stage::Setup, got: Vec::new(), sent: 0, toggle: false, since: at });
                }
                None => {}
            }
        }
        if self.ctl.is_some() {
            self.control_slot(dev, at);
            return;
        }
        if !self.configured {
            return;
        }
        if self.open != self.line_state {
            self.line_state = self.open;
            self.plan.push_back(control_line_state(self.open));
            if self.open {
                self.plan.push_back(line_coding(115_200));
                self.plan.push_back(get_line_coding(115_200));
            }
            return;
        }
        let Some(cdc) = self.cdc else { return };
        // Alternate OUT and IN when both have work.
        self.in_turn = !self.in_turn;
        let has_out = self.sending.is_some() || !self.writes.is_empty();
        if has_out && (!self.in_turn || !self.open) {
            self.bulk_out(dev, cdc.bulk_out);
        } else if self.open {
            self.bulk_in(dev, cdc.bulk_in, at);
        }
    }

    fn bulk_out(&mut self, dev: &mut UsbPeripheral, ep: u8) {
        if self.sending.is_none() {
            self.sending = self.writes.pop_front().map(|w| (w, 0));
        }
        let Some((data, at)) = &self.sending else { return };
        let packet: Vec<u8> = match &mut self.splits {
            None => data[*at..(*at + BULK_MAX).min(data.len())].to_vec(),
            Some(s) => {
                let len = *self.out_len.get_or_insert_with(|| s.next_len(BULK_MAX));
                let p: Vec<u8> = data[*at..].iter().chain(self.writes.iter().flatten()).take(len).copied().collect();
                self.out_len = Some(p.len());
                p
            }
        };
        match dev.out(self.addr, ep, self.out_toggle, &packet) {
            Handshake::Ack => {
                self.out_toggle = !self.out_toggle;
                self.out_len = None;
                self.stats.bytes_out += packet.len() as u64;
                self.consume(packet.len());
            }
            Handshake::Nak => self.stats.naked_out += 1,
            other => self.stats.errors.push(format!("bulk OUT: {other:?}")),
        }
    }

    // drop `n` bytes the device took from the front of the writes (a write ending on a full
    // packet ends there: cdc-acm sends no zero-length one)
    fn consume(&mut self, mut n: usize) {
        while n > 0 {
            let Some((data, at)) = &mut self.sending else { return };
            let k = n.min(data.len() - *at);
            *at += k;
            n -= k;
            if *at == data.len() {
                self.sending = self.writes.pop_front().map(|w| (w, 0));
            }
        }
    }

    fn bulk_in(&mut self, dev: &mut UsbPeripheral, ep: u8, at: u64) {
        match dev.in_(self.addr, ep | 0) {
            Handshake::Data(d, toggle) => {
                if d.len() > BULK_MAX {
                    self.stats.errors.push(format!("bulk IN packet of {} bytes", d.len()));
                }
                if toggle != self.in_toggle {
                    self.stats.in_toggle_errors += 1;
                    return;
                }
                self.in_toggle = !self.in_toggle;
                self.stats.bytes_in += d.len() as u64;
                self.rx_times.extend(std::iter::repeat_n(at, d.len()));
                self.received.extend(d);
            }
            Handshake::Nak => {}
            other => self.stats.errors.push(format!("bulk IN: {other:?}")),
        }
    }

    fn control_slot(&mut self, dev: &mut UsbPeripheral, at: u64) {
        let addr = self.addr;
        let mps0 = self.mps0;
        let c = self.ctl.as_mut().unwrap();
        let length = u16::from_le_bytes([c.setup[6], c.setup[7]]) as usize;
        let dir_in = c.setup[0] & 0x80 != 0;
        if at >= c.since + CONTROL_TIMEOUT {
            let e = format!("control {:02x?}: timed out in {:?}", c.setup, c.stage);
            self.fail(e);
            return;
        }
        let h = match c.stage {
            Stage::Setup => dev.setup(addr, 0, &c.setup),
            Stage::DataIn | Stage::StatusIn => dev.in_(addr, 0),
            Stage::DataOut => {
                let end = (c.sent + mps0).min(c.out.len());
                dev.out(addr, 0, c.toggle, &c.out[c.sent..end].to_vec())
            }
            Stage::StatusOut => dev.out(addr, 0, true, &[]),
        };
        match (c.stage, h) {
            (_, Handshake::Nak | Handshake::Timeout) => {}
            (_, Handshake::Stall) if c.what == What::Qualifier && c.stage != Stage::Setup => {
                // The answer a full-speed-only device owes (USB 2.0 §9.6.2).
                self.ctl = None;
            }
            (_, Handshake::Stall) => {
                let e = format!("control {:02x?}: STALL in {:?}", c.setup, c.stage);
                self.fail(e);
            }
            (Stage::Setup, _) => {
                c.toggle = true;
                c.since = at;
                c.stage = match (length, dir_in) {
                    (0, _) => Stage::StatusIn,
                    (_, true) => Stage::DataIn,
                    (_, false) => Stage::DataOut,
                };
            }
            (Stage::DataIn, Handshake::Data(d, toggle)) => {
                if toggle != c.toggle {
                    return; // a duplicate: dropped
                }
                c.toggle = !c.toggle;
                c.since = at;
                let short = d.len() < mps0;
                if d.len() > mps0 {
                    self.stats.errors.push(format!("control {:02x?}: IN packet of {} bytes (bMaxPacketSize0 {mps0})", c.setup, d.len()));
                }
                c.got.extend(d);
                if c.got.len() > length {
                    self.stats.errors.push(format!("control {:02x?}: {} bytes for wLength {length}", c.setup, c.got.len()));
                }
                if short || c.got.len() >= length {
                    c.got.truncate(length);
                    c.stage = Stage::StatusOut;
                }
            }
            (Stage::DataOut, Handshake::Ack) => {
                c.sent = (c.sent + mps0).min(c.out.len());
                c.toggle = !c.toggle;
                c.since = at;
                if c.sent >= c.out.len() {
                    c.stage = Stage::StatusIn;
                }
            }
            (Stage::StatusIn, Handshake::Data(d, _)) => {
                if !d.is_empty() {
                    let e = format!("control {:02x?}: status stage with {} bytes", c.setup, d.len());
                    self.stats.errors.push(e);
                }
                let c = self.ctl.take().unwrap();
                self.done(c, at);
            }
            (Stage::StatusOut, Handshake::Ack) => {
                let c = self.ctl.take().unwrap();
                // The data stage ended on the host's side: nothing more may be loaded (a
                // zero-length packet where none was due).
                if dev.ready(addr, 0, true) {
                    self.stats.errors.push(format!("control {:02x?}: an IN packet still loaded after the data stage", c.setup));
                }
                self.done(c, at);
            }
            (stage, h) => {
                let e = format!("control {:02x?}: {h:?} in {stage:?}", c.setup);
                self.fail(e);
            }
        }
    }

    // a control transfer failed: Linux gives up on the device and tries again from a reset
    fn fail(&mut self, e: String) {
        self.stats.errors.push(e);
        self.ctl = None;
        if !self.configured {
            self.plan.clear();
            self.plan.push_back(Step::Reset);
            self.plan.push_back(get_descriptor(1, 0, 0, 64, What::Device64));
        }
    }

    // a control transfer completed: check what came back, plan what follows
    fn done(&mut self, c: Ctl, at: u64) {
        let d = &c.got;
        match c.what {
            What::Device64 => {
                if d.len() < 8 {
                    self.stats.errors.push(format!("device descriptor: {} bytes at first read", d.len()));
                    return;
                }
                self.mps0 = d[7] as usize;
                let n = self.next_addr;
                self.next_addr = self.next_addr % 127 + 1;
                self.plan.push_front(Step::Control(setup_packet(0, 5, n as u16, 0, 0), Vec::new(), What::SetAddress(n)));
                self.plan.push_front(Step::Reset);
            }
            What::SetAddress(n) => {
                self.addr = n;
                self.plan.push_front(get_descriptor(1, 0, 0, 18, What::Device));
                self.plan.push_front(Step::Wait(at + SET_ADDRESS_RECOVERY));
            }
            What::Device => {
                self.check_device(d);
                if d.len() >= 17 {
                    self.strings = [d[14], d[15], d[16]];
                }
                self.plan.push_front(get_descriptor(2, 0, 0, 9, What::ConfigHead));
                if d.len() >= 4 && u16::from_le_bytes([d[2], d[3]]) >= 0x0200 {
                    self.plan.push_front(get_descriptor(6, 0, 0, 10, What::Qualifier));
                }
                // USB 2.01 and later: Linux reads the BOS descriptor (hub.c, usb_get_bos_descriptor).
                if d.len() >= 4 && u16::from_le_bytes([d[2], d[3]]) >= 0x0201 {
                    self.plan.push_front(get_descriptor(0x0F, 0, 0, 5, What::BosHead));
                }
            }
            What::BosHead => {
                if d.len() < 5 || d[0] != 5 || d[1] != 0x0F {
                    self.stats.errors.push(format!("BOS descriptor header {d:02x?}"));
                } else {
                    let total = u16::from_le_bytes([d[2], d[3]]);
                    self.plan.push_front(get_descriptor(0x0F, 0, 0, total, What::Bos));
                }
            }
            What::Bos => {
                let total = if d.len() >= 4 { u16::from_le_bytes([d[2], d[3]]) as usize } else { 0 };
                if d.len() != total {
                    self.stats.errors.push(format!("BOS descriptor: {} bytes of {total}", d.len()));
                }
            }
            What::ConfigHead => {
                let total = if d.len() >= 4 { u16::from_le_bytes([d[2], d[3]]) } else { 9 };
                self.plan.push_front(get_descriptor(2, 0, 0, total, What::Config));
            }
            What::Config => {
                self.cdc = self.check_config(d);
                self.plan.push_front(get_descriptor(3, 0, 0, 255, What::LangIds));
            }
            What::LangIds => {
                if d.len() < 4 || d[1] != 3 || u16::from_le_bytes([d[2], d[3]]) != 0x0409 {
                    self.stats.errors.push(format!("string 0 (languages): {d:02x?}"));
                }
                let mut next = vec![Step::Control(setup_packet(0, 9, 1, 0, 0), Vec::new(), What::SetConfig), line_coding(9_600), get_line_coding(9_600)];
                for &i in self.strings.iter().rev().filter(|&&i| i != 0) {
                    next.insert(0, get_descriptor(3, i, 0x0409, 255, What::Str(i)));
                }
                for s in next.into_iter().rev() {
                    self.plan.push_front(s);
                }
            }
            What::Str(i) => {
                if d.len() < 2 || d[1] != 3 || d[0] as usize != d.len() || d.len() % 2 != 0 {
                    self.stats.errors.push(format!("string {i}: {d:02x?}"));
                } else {
                    let units: Vec<u16> = d[2..].chunks(2).map(|p| u16::from_le_bytes([p[0], p[1]])).collect();
                    self.stats.strings.push(String::from_utf16_lossy(&units));
                }
            }
            What::Qualifier => self.stats.errors.push(format!("device qualifier answered ({d:02x?}) by a full-speed device")),
            What::LineCoding(want) => {
                if d[..] != want[..] {
                    self.stats.errors.push(format!("GET_LINE_CODING {d:02x?} after SET_LINE_CODING {want:02x?}"));
                }
            }
            What::SetConfig => {
                self.configured = self.cdc.is_some();
                self.stats.enumerations += 1;
                self.out_toggle = false;
                self.in_toggle = false;
            }
            What::ClearHalt(ep) => match self.cdc {
                Some(cdc) if ep == cdc.bulk_out => self.out_toggle = false,
                Some(cdc) if ep == cdc.bulk_in | 0x80 => self.in_toggle = false,
                _ => {}
            },
            What::Plain => {}
        }
    }

    // chapter 9 rules for the device descriptor
    fn check_device(&mut self, d: &[u8]) {
        let mut err = |m: String| self.stats.errors.push(format!("device descriptor: {m}"));
        if d.len() != 18 || d[0] != 18 || d[1] != 1 {
            err(format!("length/type {:02x?}", &d[..d.len().min(2)]));
            return;
        }
        let bcd = u16::from_le_bytes([d[2], d[3]]);
        if ![0x0110, 0x0200, 0x0201, 0x0210].contains(&bcd) {
            err(format!("bcdUSB {bcd:#06x}"));
        }
        if ![8, 16, 32, 64].contains(&d[7]) {
            err(format!("bMaxPacketSize0 {}", d[7]));
        }
        // CDC at the device level (class 0x02) or an IAD composite (0xEF/0x02/0x01).
        match (d[4], d[5], d[6]) {
            (0x02, 0, 0) | (0xEF, 0x02, 0x01) => {}
            c => err(format!("device class {c:02x?}")),
        }
        if d[17] == 0 {
            err("no configuration".into());
        }
    }

    // chapter 9 and CDC 1.1 rules for the configuration; the CDC endpoints if they hold
    fn check_config(&mut self, d: &[u8]) -> Option<Cdc> {
        let mut errors = Vec::new();
        if d.len() < 9 || d[1] != 2 || u16::from_le_bytes([d[2], d[3]]) as usize != d.len() {
            errors.push(format!("configuration header {:02x?}", &d[..d.len().min(9)]));
        }
        let mut cdc = Cdc::default();
        let mut iface: Option<(u8, u8)> = None; // (number, class)
        let mut interfaces = 0;
        let mut functional = Vec::new();
        let mut union = None;
        let mut at = 0;
        while at + 2 <= d.len() {
            let len = d[at] as usize;
            if len < 2 || at + len > d.len() {
                errors.push(format!("descriptor at {at}: length {len}"));
                break;
            }
            let x = &d[at..at + len];
            match x[1] {
                4 if len >= 9 => {
                    iface = Some((x[2], x[5]));
                    if x[3] == 0 {
                        interfaces += 1;
                    }
                    match (x[5], x[6]) {
                        (0x02, 0x02) | (0x0A, 0x00) => {}
                        c => errors.push(format!("interface {} class/subclass {c:02x?}", x[2])),
                    }
                }
                0x0B => self.stats.iad = true,
                0x24 if len >= 3 => {
                    functional.push(x[2]);
                    if x[2] == 0x06 && len >= 5 {
                        union = Some((x[3], x[4]));
                    }
                }
                5 if len >= 7 => {
                    let addr = x[2];
                    let kind = x[3] & 3;
                    let size = u16::from_le_bytes([x[4], x[5]]);
                    match (iface.map(|i| i.1), kind) {
                        (Some(0x02), 3) => {
                            if addr & 0x80 == 0 || x[6] == 0 || size > 64 {
                                errors.push(format!("notification endpoint {addr:#04x} size {size} interval {}", x[6]));
                            }
                            cdc.notify = addr & 0x7F;
                        }
                        (Some(0x0A), 2) => {
                            if ![8, 16, 32, 64].contains(&size) {
                                errors.push(format!("bulk endpoint {addr:#04x} size {size}"));
                            }
                            if addr & 0x80 != 0 {
                                cdc.bulk_in = addr & 0x7F;
                            } else {
                                cdc.bulk_out = addr;
                            }
                        }
                        k => errors.push(format!("endpoint {addr:#04x} type {} in interface class {:?}", k.1, k.0)),
                    }
                }
                _ => {}
            }
            at += len;
        }
        if d.len() >= 5 && d[4] != interfaces {
            errors.push(format!("bNumInterfaces {} for {interfaces} interfaces", d[4]));
        }
        for f in [0x00, 0x01, 0x02, 0x06] {
            if !functional.contains(&f) {
                errors.push(format!("no CDC functional descriptor {f:#04x}"));
            }
        }
        if union.is_none() {
            errors.push("no union".into());
        }
        let ok = errors.is_empty() && cdc.bulk_in != 0 && cdc.bulk_out != 0 && cdc.notify != 0;
        self.stats.errors.extend(errors.into_iter().map(|e| format!("configuration: {e}")));
        ok.then_some(cdc)
    }
}
