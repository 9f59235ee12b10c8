//! Run outputs: the JSON/human report (per-axis numbers come from the `la` checker fed with
//! the bench's pin edges) and a VCD of the step, dir and enable pins. For the CLI and tests.
//!
//! Pin map (the firmware's, `ddastep::board`): step X..U = PB9..PB15, dir X..U = PB0, PB1, PB3, PB4, PB5,
//! PB6, PB7, enable = PB8; spindle PWM = PA8 (TIM1 CH1, recorded as a duty cycle), spindle
//! enable = PA15, spindle direction = PA5, flood = PA4, mist = PA3. VCD time is modeled cycles × 1000/72 ns, rounded to 1 ns.

use std::io::Write;
use std::path::Path;

use anyhow::Result;
use ddastep::board as pins;
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use super::board::Board;
use super::clock::HZ;
use super::mcu::TIM2_IRQ;
use super::nvic::IRQ0;
use crate::la::{Analyzer, AxisChannels, Config};

/// Axis names in channel order.
pub const AXES: [&str; 7] = ["X", "Y", "Z", "A", "B", "C", "U"];
/// GPIOB step and dir pins per axis: the firmware's pin map.
pub use ddastep::board::{DIR_PINS, STEP_PINS};
/// GPIOB shared enable pin.
pub const EN_PIN: u8 = pins::ENABLE_PIN;
/// GPIOA pins of the spindle and coolant outputs, with their VCD names.
pub const TOOL_PINS: [(u8, &str); 4] = [
    (pins::SPINDLE_ENABLE_PIN, "SPINDLE_EN"),
    (pins::SPINDLE_DIR_PIN, "SPINDLE_DIR"),
    (pins::COOLANT_FLOOD_PIN, "FLOOD"),
    (pins::COOLANT_MIST_PIN, "MIST"),
];
/// Dir pin low = positive motion (Grbl's convention with `$3=0`; a `$3` mask would flip axes,
/// which the report does not follow).
pub const DIR_LOW_IS_POSITIVE: bool = true;

/// Per-axis numbers.
#[derive(Clone, Debug, Serialize)]
pub struct AxisReport {
    /// Steps seen: rising edges (both edges with `Board::dual_edge`).
    pub rising_edges: u64,
    pub net_steps: i64,
    pub max_rate_hz: f64,
    pub min_high_ns: Option<f64>,
    pub min_low_ns: Option<f64>,
    pub min_dir_setup_ns: Option<f64>,
}

/// TIM2 handler numbers (modeled cycles, entry and return overhead included).
#[derive(Clone, Debug, Serialize)]
pub struct StepIsr {
    pub entries: u64,
    pub total_cycles: u64,
    pub mean_cycles: f64,
    pub min_cycles: u64,
    pub max_cycles: u64,
    pub mean_instructions: f64,
    pub max_instructions: u64,
    pub bsrr_offset_min_cycles: Option<u64>,
    pub bsrr_offset_max_cycles: Option<u64>,
}

/// Axes in X..U order, serialized as a JSON object.
#[derive(Clone, Debug)]
pub struct Axes(pub Vec<(String, AxisReport)>);

impl Serialize for Axes {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// The `--json` report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub axes: Axes,
    pub max_slave_deviation_steps: f64,
    pub step_isr: StepIsr,
    /// Interrupt load: handler-mode share (every exception, entry to return) of the busiest
    /// 1 ms window after boot (from the first WFI sleep on). The summary's headline load.
    pub interrupt_load_peak: f64,
    /// The step path's interrupt (TIM2, or DMA1 channel 1's fill: `Board::step_irq`) alone,
    /// entry to return, busiest 1 ms window after boot. `$I`'s peak times the same handler's
    /// body only (without exception entry, return and the code around its two DWT reads).
    pub step_isr_load_peak: f64,
    /// Not asleep (everything but WFI: interrupts and idle's thread-mode work, such as parsing,
    /// planning and saving `$` settings to flash), busiest 1 ms window after boot. Streaming
    /// settings keeps idle busy for whole milliseconds, so this reads 100 % on most jobs.
    pub cpu_load_peak: f64,
    /// Not asleep, busiest 1 ms window including boot (init runs with interrupts off: 100 %).
    pub cpu_load_peak_with_boot: f64,
    /// Modeled cycle of the first WFI sleep after reset (end of boot).
    pub boot_cycles: Option<u64>,
    pub overruns: u64,
    pub sim_cycles: u64,
    pub sim_seconds: f64,
    pub instructions: u64,
    pub serial: String,
    pub usart_rx_overruns: u64,
    pub unmodeled_registers: Vec<String>,
    pub spindle: SpindleReport,
    pub dma: DmaReport,
}

/// DMA1 (`dma.rs`): what the step-output DMA mode moved and what it cost the bus.
#[derive(Clone, Debug, Serialize)]
pub struct DmaReport {
    /// Data items moved per channel (index 0 = channel 1).
    pub transfers: [u64; 7],
    /// Bus-matrix cycles of all transfers, and the part charged to the running CPU.
    pub bus_cycles: u64,
    pub stolen_cycles: u64,
    /// Bus-matrix cycles per simulated cycle.
    pub bus_load: f64,
    /// Included in `overruns`.
    pub overruns: u64,
}

/// The spindle/laser PWM (TIM1 on PA8) and the tool pins.
#[derive(Clone, Debug, Serialize)]
pub struct SpindleReport {
    /// Changes of the PWM duty or frequency.
    pub pwm_changes: usize,
    pub max_duty: f64,
    pub final_duty: f64,
    /// PWM frequency at the last change (0 if it never ran).
    pub pwm_hz: f64,
    /// Rising edges of SPINDLE_EN, SPINDLE_DIR, FLOOD, MIST.
    pub pin_rises: [u64; 4],
}

// picoseconds of a modeled cycle count
fn ps(cycles: u64) -> u64 {
    (cycles as u128 * 1_000_000_000_000 / HZ as u128) as u64
}

impl Board {
    // the report of everything so far
    pub fn report(&self) -> Report {
        let mut channels = Vec::new();
        for (i, name) in AXES.iter().enumerate() {
            channels.push(AxisChannels::new(name, 2 * i, Some(2 * i + 1)));
        }
        let mut config = Config::new(channels);
        config.dir_invert = DIR_LOW_IS_POSITIVE;
        config.dual_edge = self.dual_edge;
        let mut la = Analyzer::new(config).expect("fixed channel map");
        for ch in 0..14 {
            la.edge(0, ch, false);
        }
        for e in self.edges().iter().filter(|e| e.port == 1) {
            let ch = STEP_PINS.iter().position(|&p| p == e.pin).map(|a| 2 * a).or_else(|| DIR_PINS.iter().position(|&p| p == e.pin).map(|a| 2 * a + 1));
            if let Some(ch) = ch {
                la.edge(ps(e.cycle), ch, e.level);
            }
        }
        la.advance(ps(self.cycles()));
        let r = la.finish();
        let axes = r
            .axes
            .iter()
            .map(|a| {
                (a.name.clone(), AxisReport {
                    rising_edges: a.steps,
                    net_steps: a.net_steps,
                    max_rate_hz: a.max_rate_hz,
                    min_high_ns: a.min_high_ns,
                    min_low_ns: a.min_low_ns,
                    min_dir_setup_ns: a.min_dir_setup_ns,
                })
            })
            .collect();
        let dev = r.axes.iter().filter_map(|a| a.max_deviation_steps).fold(0.0, f64::max);
        let u = self.serial_bytes().0;
        Report {
            axes: Axes(axes),
            max_slave_deviation_steps: dev,
            step_isr: self.step_isr(),
            interrupt_load_peak: self.stats().interrupt_load_peak(self.cycles()),
            step_isr_load_peak: self.stats().step_isr_load_peak(self.cycles()),
            cpu_load_peak: self.stats().cpu_load_peak(self.cycles()),
            cpu_load_peak_with_boot: self.stats().cpu_load_peak_with_boot(self.cycles()),
            boot_cycles: self.stats().first_sleep,
            overruns: self.overruns(),
            sim_cycles: self.cycles(),
            sim_seconds: self.seconds(),
            instructions: self.instructions(),
            serial: String::from_utf8_lossy(u).into_owned(),
            usart_rx_overruns: self.usart_rx_overruns(),
            unmodeled_registers: self.unmodeled().iter().map(|(a, pc)| format!("{a:#010x} (pc {pc:#010x})")).collect(),
            spindle: self.spindle_report(),
            dma: DmaReport {
                transfers: self.dma_transfers(),
                bus_cycles: self.dma_bus_cycles(),
                stolen_cycles: self.dma_stolen_cycles(),
                bus_load: self.dma_bus_cycles() as f64 / self.cycles().max(1) as f64,
                overruns: self.dma_overruns(),
            },
        }
    }

    // the spindle/laser PWM and tool pins so far
    pub fn spindle_report(&self) -> SpindleReport {
        let pwm = self.pwm_changes();
        let rises = TOOL_PINS.map(|(pin, _)| self.edges().iter().filter(|e| e.port == 0 && e.pin == pin && e.level).count() as u64);
        SpindleReport {
            pwm_changes: pwm.len(),
            max_duty: pwm.iter().map(|c| c.duty).fold(0.0, f64::max),
            final_duty: pwm.last().map_or(0.0, |c| c.duty),
            pwm_hz: pwm.last().map_or(0.0, |c| c.hz),
            pin_rises: rises,
        }
    }

    // the TIM2 handler figures since reset (or `reset_step_isr_stats`)
    pub fn step_isr(&self) -> StepIsr {
        let s = &self.stats().step_isr;
        let mean = |sum: u64| if s.entries == 0 { 0.0 } else { sum as f64 / s.entries as f64 };
        StepIsr {
            entries: s.entries,
            total_cycles: s.cycles_sum,
            mean_cycles: mean(s.cycles_sum),
            min_cycles: s.cycles_min.unwrap_or(0),
            max_cycles: s.cycles_max,
            mean_instructions: mean(s.insns_sum),
            max_instructions: s.insns_max,
            bsrr_offset_min_cycles: s.bsrr_min,
            bsrr_offset_max_cycles: s.bsrr_max,
        }
    }

    // write a VCD of the step/dir/enable pins, the tool pins and the spindle PWM duty
    pub fn write_vcd(&self, path: impl AsRef<Path>) -> Result<()> {
        let file = std::io::BufWriter::new(std::fs::File::create(path)?);
        let mut w = vcd::Writer::new(file);
        w.timescale(1, vcd::TimescaleUnit::NS)?;
        w.add_module("bluepill")?;
        let mut ids = std::collections::HashMap::new();
        for (i, name) in AXES.iter().enumerate() {
            ids.insert(STEP_PINS[i], w.add_wire(1, &format!("{name}_STEP"))?);
            ids.insert(DIR_PINS[i], w.add_wire(1, &format!("{name}_DIR"))?);
        }
        ids.insert(EN_PIN, w.add_wire(1, "EN")?);
        let mut tool = std::collections::HashMap::new();
        for (pin, name) in TOOL_PINS {
            tool.insert(pin, w.add_wire(1, name)?);
        }
        let duty = w.add_var(vcd::VarType::Real, 64, "SPINDLE_PWM_DUTY", None)?;
        w.upscope()?;
        w.enddefinitions()?;
        w.timestamp(0)?;
        for id in ids.values().chain(tool.values()) {
            w.change_scalar(*id, vcd::Value::V0)?;
        }
        w.change_real(duty, 0.0)?;
        // Pin edges and duty changes in time order (both lists are sorted).
        let pins = self.edges().iter().filter_map(|e| {
            let id = match e.port {
                1 => ids.get(&e.pin),
                0 => tool.get(&e.pin),
                _ => None,
            }?;
            Some((e.cycle, *id, Some(e.level), 0.0))
        });
        let pwm = self.pwm_changes().iter().map(|c| (c.cycle, duty, None, c.duty));
        let mut events: Vec<_> = pins.chain(pwm).collect();
        events.sort_by_key(|e| e.0);
        let mut last = 0;
        for (cycle, id, level, value) in events {
            let t = (cycle * 1000 + HZ / 2_000_000) / (HZ / 1_000_000);
            if t != last {
                w.timestamp(t)?;
                last = t;
            }
            match level {
                Some(l) => w.change_scalar(id, if l { vcd::Value::V1 } else { vcd::Value::V0 })?,
                None => w.change_real(id, value)?,
            }
        }
        w.timestamp((self.cycles() * 1000) / (HZ / 1_000_000))?;
        w.writer().flush()?;
        Ok(())
    }
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        writeln!(f, "simulated {:.6} s = {} modeled cycles, {} instructions", self.sim_seconds, self.sim_cycles, self.instructions)?;
        writeln!(f, "axis  rising  net  max rate Hz  min high ns  min low ns  min dir setup ns")?;
        let o = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.0}"));
        for (name, a) in &self.axes.0 {
            if a.rising_edges == 0 {
                continue;
            }
            writeln!(f, "{name:>4} {:>7} {:>4} {:>12.0} {:>12} {:>11} {:>17}", a.rising_edges, a.net_steps, a.max_rate_hz, o(a.min_high_ns), o(a.min_low_ns), o(a.min_dir_setup_ns))?;
        }
        writeln!(f, "max slave deviation: {:.3} steps", self.max_slave_deviation_steps)?;
        let s = &self.step_isr;
        writeln!(f, "step ISR (TIM2): {} entries, {:.1} mean / {} max modeled cycles, {:.1} mean / {} max instructions", s.entries, s.mean_cycles, s.max_cycles, s.mean_instructions, s.max_instructions)?;
        if let (Some(a), Some(b)) = (s.bsrr_offset_min_cycles, s.bsrr_offset_max_cycles) {
            writeln!(f, "update event -> first BSRR store: {a}..{b} modeled cycles")?;
        }
        writeln!(
            f,
            "peak interrupt load (busiest 1 ms after boot, modeled, handlers from entry to return): {:.1} %; step interrupt alone {:.1} % (`$I` times its body only)",
            self.interrupt_load_peak * 100.0,
            self.step_isr_load_peak * 100.0
        )?;
        writeln!(f, "peak not-asleep time (same windows; idle's work too, e.g. saving `$` settings): {:.1} % ({:.1} % with boot)", self.cpu_load_peak * 100.0, self.cpu_load_peak_with_boot * 100.0)?;
        writeln!(f, "timer overruns: {}", self.overruns)?;
        let sp = &self.spindle;
        if sp.pwm_changes > 0 || sp.pin_rises.iter().any(|&n| n > 0) {
            writeln!(f, "spindle PWM (TIM1, PA8): {} changes, max duty {:.1} %, final {:.1} % at {:.0} Hz; rises EN/DIR/FLOOD/MIST {:?}", sp.pwm_changes, sp.max_duty * 100.0, sp.final_duty * 100.0, sp.pwm_hz, sp.pin_rises)?;
        }
        let d = &self.dma;
        if d.transfers.iter().any(|&n| n > 0) {
            writeln!(f, "DMA1: transfers per channel 1..7 {:?}, bus {:.2} % ({} cycles, {} taken from the running CPU), overruns {}", d.transfers, d.bus_load * 100.0, d.bus_cycles, d.stolen_cycles, d.overruns)?;
        }
        if !self.unmodeled_registers.is_empty() {
            writeln!(f, "unmodeled registers: {}", self.unmodeled_registers.join(", "))?;
        }
        Ok(())
    }
}

// the step interrupt's modeled cycles by function and by block (needs `Board::set_profile`)
pub fn isr_profile(board: &Board, top: usize) -> String {
    use std::fmt::Write as _;
    let exc = IRQ0 + TIM2_IRQ;
    let entries = board.stats().step_isr.entries.max(1) as f64;
    let mut s = String::new();
    let funcs = board.profile(exc);
    let total: u64 = funcs.iter().map(|f| f.cycles).sum();
    let _ = writeln!(s, "step ISR profile: {total} modeled cycles in {} entries ({:.1} per entry)", entries as u64, total as f64 / entries);
    let _ = writeln!(s, "  {:>6} {:>9} {:>8}  function", "share", "cycles", "/entry");
    for f in funcs.iter().take(top) {
        let _ = writeln!(s, "  {:>5.1}% {:>9} {:>8.1}  {}", f.share * 100.0, f.cycles, f.cycles as f64 / entries, f.function);
    }
    let _ = writeln!(s, "  {:>6} {:>9} {:>8}  block (address function+offset), cycles/run", "share", "cycles", "runs");
    for (name, c) in board.profile_blocks(exc).iter().take(top) {
        let _ = writeln!(s, "  {:>5.1}% {:>9} {:>8}  {name}, {:.1}", c.cycles as f64 * 100.0 / total.max(1) as f64, c.cycles, c.runs, c.cycles as f64 / c.runs.max(1) as f64);
    }
    s
}
