//! Run outputs: the JSON/human report (per-axis numbers come from the `la` checker fed with
//! the bench's pin edges, `summary.rs`) and a VCD of the step, dir and enable pins
//! (`vcd_out.rs`; the pin map is `pinmap.rs`). For the CLI and tests.

use std::path::Path;

use anyhow::Result;
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use super::board::Board;
use super::mcu::TIM2_IRQ;
use super::nvic::IRQ0;
use super::summary::EdgeSummary;
use super::vcd_out::VcdStream;

pub use super::pinmap::{AXES, DIR_LOW_IS_POSITIVE, DIR_PINS, EN_PIN, STEP_PINS, TOOL_PINS};

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
    /// Largest deviation of a slave from its move's straight line, over every move (the
    /// engine's moves, placed on the pins where its step half finishes each: `summary.rs`).
    /// `null` where it cannot be computed: DMA burst mode with more than one move.
    pub max_slave_deviation_steps: Option<f64>,
    /// Moves seen on the pins (runs of steps between two move ends or 50 ms pauses).
    pub moves: u64,
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
    /// The USB side (`--usb`); left out of the JSON when the cable was never plugged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub usb: Option<UsbReport>,
}

/// The modeled USB link (`usb.rs`, `usb_host.rs`), as the host counted it.
#[derive(Clone, Debug, Serialize)]
pub struct UsbReport {
    /// SET_CONFIGURATIONs: how many times the host enumerated the board.
    pub enumerations: u64,
    /// Bulk bytes host to board (`bytes_out`) and board to host (`bytes_in`).
    pub bytes_out: u64,
    pub bytes_in: u64,
    /// OUT packets the board NAKed (flow control; each retry counts).
    pub naked_out_packets: u64,
    /// Descriptor rule violations, stalls, timeouts and toggle errors seen by the host.
    pub errors: Vec<String>,
    /// What the board sent over USB.
    pub serial: String,
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

impl Board {
    // the report of everything so far
    pub fn report(&self) -> Report {
        let mut sum = EdgeSummary::new(self.dual_edge);
        sum.move_ends(self.move_ends());
        sum.edges(self.edges());
        self.report_from(sum)
    }

    // the report, with the edge figures from a summary fed with every edge and move end so
    // far (`--serve`, which does not keep the edges)
    pub fn report_from(&self, sum: EdgeSummary) -> Report {
        let fig = sum.finish(self.cycles());
        let axes = fig
            .la
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
        let u = self.serial_bytes().0;
        Report {
            axes: Axes(axes),
            max_slave_deviation_steps: fig.max_slave_deviation_steps,
            moves: fig.moves,
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
            spindle: self.spindle_report(fig.tool_rises),
            dma: DmaReport {
                transfers: self.dma_transfers(),
                bus_cycles: self.dma_bus_cycles(),
                stolen_cycles: self.dma_stolen_cycles(),
                bus_load: self.dma_bus_cycles() as f64 / self.cycles().max(1) as f64,
                overruns: self.dma_overruns(),
            },
            usb: self.usb_report(),
        }
    }

    // the spindle/laser PWM so far, with the tool pins' rises (`EdgeSummary::tool_rises`)
    pub fn spindle_report(&self, rises: [u64; 4]) -> SpindleReport {
        let pwm = self.pwm_changes();
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
        let mut v = VcdStream::create(path)?;
        v.feed(self.edges(), self.pwm_changes())?;
        v.finish(self.cycles())
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
        match self.max_slave_deviation_steps {
            Some(d) => writeln!(f, "max slave deviation (each move against its own line, {} moves): {d:.3} steps", self.moves)?,
            None => writeln!(f, "max slave deviation: not computed (DMA burst mode: the fill runs the engine ahead of the pins, so its {} moves cannot be told apart on them)", self.moves)?,
        }
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
        if let Some(u) = &self.usb {
            writeln!(f, "USB: {} enumeration(s), {} bytes out, {} bytes in, {} NAKed OUT packets, {} errors", u.enumerations, u.bytes_out, u.bytes_in, u.naked_out_packets, u.errors.len())?;
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
