//! The VCD writer: step, dir and enable pins, the tool pins and the spindle PWM duty, written as
//! the edges come (`--serve --vcd` feeds it each slice's edges and forgets them;
//! `Board::write_vcd` feeds it every edge at once). VCD time is modeled cycles × 1000/72 ns,
//! rounded to 1 ns.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::Result;

use super::clock::HZ;
use super::gpio::PinEdge;
use super::pwm::PwmChange;
use super::pinmap::{AXES, DIR_PINS, EN_PIN, STEP_PINS, TOOL_PINS};

/// A VCD file being written.
pub struct VcdStream {
    w: vcd::Writer<BufWriter<File>>,
    /// Ids of the GPIOB pins (step, dir, enable) and GPIOA tool pins, by pin.
    port_b: Vec<(u8, vcd::IdCode)>,
    port_a: Vec<(u8, vcd::IdCode)>,
    duty: vcd::IdCode,
    /// Last timestamp written (ns).
    last: u64,
}

// ns of a modeled cycle count, rounded
fn ns(cycle: u64) -> u64 {
    (cycle * 1000 + HZ / 2_000_000) / (HZ / 1_000_000)
}

impl VcdStream {
    // create the file and write the header and the initial values (all 0 at time 0)
    pub fn create(path: impl AsRef<Path>) -> Result<Self> {
        let mut w = vcd::Writer::new(BufWriter::new(File::create(path)?));
        w.timescale(1, vcd::TimescaleUnit::NS)?;
        w.add_module("bluepill")?;
        let mut port_b = Vec::new();
        for (i, name) in AXES.iter().enumerate() {
            port_b.push((STEP_PINS[i], w.add_wire(1, &format!("{name}_STEP"))?));
            port_b.push((DIR_PINS[i], w.add_wire(1, &format!("{name}_DIR"))?));
        }
        port_b.push((EN_PIN, w.add_wire(1, "EN")?));
        let mut port_a = Vec::new();
        for (pin, name) in TOOL_PINS {
            port_a.push((pin, w.add_wire(1, name)?));
        }
        let duty = w.add_var(vcd::VarType::Real, 64, "SPINDLE_PWM_DUTY", None)?;
        w.upscope()?;
        w.enddefinitions()?;
        w.timestamp(0)?;
        for (_, id) in port_b.iter().chain(&port_a) {
            w.change_scalar(*id, vcd::Value::V0)?;
        }
        w.change_real(duty, 0.0)?;
        Ok(Self { w, port_b, port_a, duty, last: 0 })
    }

    // the next pin edges and PWM changes (each in cycle order, later than everything fed
    // before; at one cycle, pin edges before duty changes)
    pub fn feed(&mut self, edges: &[PinEdge], pwm: &[PwmChange]) -> Result<()> {
        let id = |list: &[(u8, vcd::IdCode)], pin: u8| list.iter().find(|(p, _)| *p == pin).map(|(_, id)| *id);
        let pins = edges.iter().filter_map(|e| {
            let id = match e.port {
                1 => id(&self.port_b, e.pin),
                0 => id(&self.port_a, e.pin),
                _ => None,
            }?;
            Some((e.cycle, id, Some(e.level), 0.0))
        });
        let duty = pwm.iter().map(|c| (c.cycle, self.duty, None, c.duty));
        let mut events: Vec<_> = pins.chain(duty).collect();
        events.sort_by_key(|e| e.0);
        for (cycle, id, level, value) in events {
            // (Never back in time: a DMA store can land a little before a CPU store already
            // recorded, see `mcu/mmio.rs`, and a slice may have been written.)
            let t = ns(cycle).max(self.last);
            if t != self.last {
                self.w.timestamp(t)?;
                self.last = t;
            }
            match level {
                Some(l) => self.w.change_scalar(id, if l { vcd::Value::V1 } else { vcd::Value::V0 })?,
                None => self.w.change_real(id, value)?,
            }
        }
        Ok(())
    }

    // the closing timestamp (cycle `now`), then flush
    pub fn finish(mut self, now: u64) -> Result<()> {
        self.w.timestamp((now * 1000) / (HZ / 1_000_000))?;
        self.w.writer().flush()?;
        Ok(())
    }
}
