//! The board's USB side, for tests and the `sim` CLI: the cable, the tty opened by a program
//! (DTR), bytes written to it and read from it, and what the host counted.

use anyhow::{bail, Result};

use super::Board;
use crate::emu::clock::HZ;
use crate::emu::report::UsbReport;
use crate::emu::usb_host::UsbStats;

impl Board {
    // plug the USB cable in (or pull it)
    pub fn usb_plug(&mut self, plugged: bool) {
        let m = self.cpu.get_data_mut();
        let now = m.now;
        m.usb_host.set_plugged(plugged, now);
    }

    // pull the cable at `at` (modeled cycle) and plug it back at `back`, if given
    pub fn usb_unplug_at(&mut self, at: u64, back: Option<u64>) {
        let h = &mut self.cpu.get_data_mut().usb_host;
        h.plug_schedule.push_back((at, false));
        if let Some(back) = back {
            h.plug_schedule.push_back((back.max(at), true));
        }
    }

    // a program opens the tty (DTR and RTS set) or closes it
    pub fn usb_open(&mut self, open: bool) {
        self.cpu.get_data_mut().usb_host.open = open;
    }

    // the host sends SET_CONFIGURATION(1) again, then CLEAR_FEATURE(ENDPOINT_HALT) on the bulk
    // OUT and IN endpoints, each resetting its toggles to DATA0 (as macOS and libusb do)
    pub fn usb_resync(&mut self) {
        self.cpu.get_data_mut().usb_host.resync();
    }

    // the host enumerated and configured the board
    pub fn usb_configured(&self) -> bool {
        self.cpu.get_data().usb_host.configured()
    }

    // one write to the tty
    pub fn usb_send(&mut self, bytes: &[u8]) {
        self.cpu.get_data_mut().usb_host.write(bytes);
    }

    // send the bytes written in OUT packets of random lengths (1..=64, across writes) drawn
    // from `seed`, instead of 64-byte packets that end with each write
    pub fn usb_random_splits(&mut self, seed: u64) {
        self.cpu.get_data_mut().usb_host.splits = Some(crate::emu::usb_splits::Splits::new(seed));
    }

    // bytes written to the tty and not yet taken by the board
    pub fn usb_pending(&self) -> usize {
        self.cpu.get_data().usb_host.pending()
    }

    // everything the board sent over USB
    pub fn usb_output(&self) -> String {
        String::from_utf8_lossy(&self.cpu.get_data().usb_host.received).into_owned()
    }

    // raw bytes the board sent over USB and the cycle of each
    pub fn usb_bytes(&self) -> (&[u8], &[u64]) {
        let h = &self.cpu.get_data().usb_host;
        (&h.received, &h.rx_times)
    }

    // what the host counted (enumerations, bytes, NAKs, descriptor errors)
    pub fn usb_stats(&self) -> UsbStats {
        self.cpu.get_data().usb_host.stats.clone()
    }

    // the report's `usb` object, if the cable was ever plugged
    pub fn usb_report(&self) -> Option<UsbReport> {
        let m = self.cpu.get_data();
        let h = &m.usb_host;
        if !h.plugged && h.stats.enumerations == 0 {
            return None;
        }
        let mut errors = h.stats.errors.clone();
        if h.stats.in_toggle_errors > 0 || m.usb.toggle_mismatches > 0 {
            errors.push(format!("DATA0/1 toggle: {} IN, {} OUT", h.stats.in_toggle_errors, m.usb.toggle_mismatches));
        }
        Some(UsbReport {
            enumerations: h.stats.enumerations,
            bytes_out: h.stats.bytes_out,
            bytes_in: h.stats.bytes_in,
            naked_out_packets: h.stats.naked_out,
            errors,
            serial: String::from_utf8_lossy(&h.received).into_owned(),
        })
    }

    // OUT packets the board took with a stale DATA0/1 toggle
    pub fn usb_toggle_mismatches(&self) -> u64 {
        self.cpu.get_data().usb.toggle_mismatches
    }

    // plug in, run until the host has configured the board and the port is open
    pub fn usb_connect(&mut self, max_cycles: u64) -> Result<()> {
        self.usb_plug(true);
        if !self.run_until(max_cycles, |b| b.usb_configured())? {
            bail!("not enumerated within {:.3} s (simulated): {:?}", max_cycles as f64 / HZ as f64, self.usb_stats());
        }
        self.usb_open(true);
        Ok(())
    }

    // send one line over USB (adds '\n') and run until a reply line starts with "ok" or "error"
    pub fn usb_send_line_wait_ok(&mut self, line: &str) -> Result<String> {
        self.line_wait_reply(line, 10 * HZ, " over USB", |b| &b.cpu.get_data().usb_host.received, Board::usb_send)
    }
}
