//! The virtual machine around the emulated board: per axis a carriage that follows the step
//! and direction pins, and limit switches at the ends of its travel that drive the limit
//! inputs (README pin map: X, Y, Z on PA0, PA1, PA2), with contact bounce. Loaded from a TOML
//! machine file (`cargo sim -- --machine FILE`; sample: `bench/demo/gantry300.toml`).
//!
//! Wiring, as on a Grbl machine with the inputs pulled up: the switches of one axis share its
//! pin; normally-open (NO) switches are in parallel to ground (pressed: pin low), normally-
//! closed (NC) ones in series (pressed: the loop opens, pin high; `$5=1` on the firmware).
//! A carriage counts one step per active step edge (rising, or falling with
//! `step_active_low`), in the direction the DIR pin gives at that edge (low = positive, as in
//! Grbl; `invert_dir` flips it). A switch is pressed while the carriage is at or past it:
//! `min` at `position ≤ at_mm`, `max` at `position ≥ at_mm`. Each change of a pin level
//! bounces: the new level, the old one at 20 %, the new at 45 %, the old at 70 % and the new
//! for good at 100 % of `bounce_us`.

use std::any::Any;
use std::path::Path;

use anyhow::{bail, Context, Result};
use serde::Deserialize;

use crate::emu::plant::Plant;
use crate::emu::{InputFlip, Port, DIR_PINS, HZ, STEP_PINS};

/// GPIOA pins of the X, Y, Z limit inputs (README pin map; `ddastep::board::LIMIT_PINS`).
pub const LIMIT_PINS: [u8; 3] = [0, 1, 2];

/// A switch's contact (the names users write in the file).
#[allow(clippy::upper_case_acronyms)]
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
pub enum Contact {
    NO,
    NC,
}

/// One limit switch: where it is and how it is wired.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Switch {
    pub at_mm: f64,
    pub contact: Contact,
}

/// One axis of the machine file.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AxisSpec {
    pub name: String,
    pub steps_per_mm: f64,
    /// Carriage position at power-on, mm (the machine's own frame: the switch positions).
    #[serde(default)]
    pub position_mm: f64,
    #[serde(default)]
    pub min: Option<Switch>,
    #[serde(default)]
    pub max: Option<Switch>,
    #[serde(default)]
    pub invert_dir: bool,
    #[serde(default)]
    pub step_active_low: bool,
}

/// A machine file.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MachineSpec {
    /// Contact bounce after each change of a limit pin, µs.
    #[serde(default = "default_bounce")]
    pub bounce_us: f64,
    pub axis: Vec<AxisSpec>,
}

fn default_bounce() -> f64 {
    5.0
}

impl MachineSpec {
    /// Parses and checks a machine file's text.
    pub fn parse(text: &str) -> Result<Self> {
        let spec: MachineSpec = toml::from_str(text)?;
        if spec.axis.is_empty() || spec.axis.len() > LIMIT_PINS.len() {
            bail!("a machine has 1 to {} axes (X Y Z: the limit inputs PA0-PA2)", LIMIT_PINS.len());
        }
        if !(0.0..=1000.0).contains(&spec.bounce_us) {
            bail!("bounce_us must be 0..=1000");
        }
        for a in &spec.axis {
            if !(a.steps_per_mm.is_finite() && a.steps_per_mm > 0.0) {
                bail!("axis {}: steps_per_mm must be positive", a.name);
            }
            if let (Some(lo), Some(hi)) = (a.min, a.max) {
                if lo.at_mm >= hi.at_mm {
                    bail!("axis {}: the min switch must be below the max switch", a.name);
                }
            }
        }
        Ok(spec)
    }

    /// Reads a machine file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        Self::parse(&text).with_context(|| format!("machine file {}", path.display()))
    }
}

/// One carriage's state.
#[derive(Clone, Debug)]
struct Carriage {
    spec: AxisSpec,
    /// Steps from the power-on position.
    steps: i64,
    /// Limit pin level last scheduled (after its bounce).
    level: bool,
}

impl Carriage {
    fn position_mm(&self) -> f64 {
        self.spec.position_mm + self.steps as f64 / self.spec.steps_per_mm
    }

    /// (min pressed, max pressed).
    fn pressed(&self) -> (bool, bool) {
        let p = self.position_mm();
        (self.spec.min.is_some_and(|s| p <= s.at_mm), self.spec.max.is_some_and(|s| p >= s.at_mm))
    }

    /// The limit pin's level with both switches wired as the module says.
    fn pin_level(&self) -> bool {
        let (lo, hi) = self.pressed();
        let mut no_closed = false; // some NO switch pulls the pin low
        let mut nc_open = false; // some NC switch opened the series loop
        let mut has_nc = false;
        for (sw, on) in [(self.spec.min, lo), (self.spec.max, hi)] {
            match sw.map(|s| s.contact) {
                Some(Contact::NO) => no_closed |= on,
                Some(Contact::NC) => {
                    has_nc = true;
                    nc_open |= on;
                }
                None => {}
            }
        }
        // Low when a NO switch is closed or an intact NC loop grounds the pin.
        !(no_closed || (has_nc && !nc_open))
    }
}

/// A switch change seen by the machine (for tests and the summary).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwitchEvent {
    pub cycle: u64,
    pub axis: usize,
    /// Pin level after the bounce.
    pub level: bool,
}

/// The virtual machine: carriages and their switches.
#[derive(Clone, Debug)]
pub struct VirtualMachine {
    bounce_cycles: u64,
    carriages: Vec<Carriage>,
    events: Vec<SwitchEvent>,
}

impl VirtualMachine {
    pub fn new(spec: &MachineSpec) -> Self {
        let carriages = spec.axis.iter().map(|a| Carriage { spec: a.clone(), steps: 0, level: true }).collect();
        VirtualMachine { bounce_cycles: (spec.bounce_us * HZ as f64 / 1e6) as u64, carriages, events: Vec::new() }
    }

    /// Carriage positions, mm (machine file frame).
    pub fn positions_mm(&self) -> Vec<f64> {
        self.carriages.iter().map(Carriage::position_mm).collect()
    }

    /// Steps each carriage moved since power-on.
    pub fn steps(&self) -> Vec<i64> {
        self.carriages.iter().map(|c| c.steps).collect()
    }

    /// Every limit pin change (after bounce), in time order.
    pub fn events(&self) -> &[SwitchEvent] {
        &self.events
    }

    /// One line per axis: carriage position and limit pin changes.
    pub fn summary(&self) -> String {
        let mut out = String::from("virtual machine:");
        for (i, c) in self.carriages.iter().enumerate() {
            let hits = self.events.iter().filter(|e| e.axis == i).count();
            out += &format!("\n  {} at {:.4} mm ({:+} steps), limit pin changes {hits}", c.spec.name, c.position_mm(), c.steps);
        }
        out
    }

    /// The virtual machine wired to `board`, if any.
    pub fn of(board: &crate::emu::Board) -> Option<&VirtualMachine> {
        board.plant()?.as_any().downcast_ref()
    }

    // the bouncing sequence for a pin change to `level` at `t`
    fn bounce(&self, t: u64, pin: u8, level: bool, flips: &mut Vec<InputFlip>) {
        let b = self.bounce_cycles;
        let steps: &[(u64, bool)] = if b == 0 {
            &[(0, true)]
        } else {
            &[(0, true), (20, false), (45, true), (70, false), (100, true)]
        };
        for &(pct, new) in steps {
            flips.push(InputFlip { cycle: t + b * pct / 100, port: Port::A, pin, level: level == new });
        }
    }
}

impl Plant for VirtualMachine {
    fn initial(&mut self, flips: &mut Vec<InputFlip>) {
        for (c, &pin) in self.carriages.iter_mut().zip(&LIMIT_PINS) {
            c.level = c.pin_level();
            flips.push(InputFlip { cycle: 0, port: Port::A, pin, level: c.level });
        }
    }

    fn outputs(&mut self, t: u64, port: u8, old: u32, new: u32, flips: &mut Vec<InputFlip>) {
        if port != Port::B as u8 {
            return;
        }
        for i in 0..self.carriages.len() {
            let c = &mut self.carriages[i];
            let bit = 1u32 << STEP_PINS[i];
            let active = |w: u32| (w & bit != 0) != c.spec.step_active_low;
            if active(old) || !active(new) {
                continue;
            }
            let dir_low = new & 1 << DIR_PINS[i] == 0;
            c.steps += if dir_low != c.spec.invert_dir { 1 } else { -1 };
            let level = c.pin_level();
            if level != c.level {
                c.level = level;
                self.events.push(SwitchEvent { cycle: t, axis: i, level });
                self.bounce(t, LIMIT_PINS[i], level, flips);
            }
        }
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GANTRY: &str = include_str!("../demo/gantry300.toml");

    #[test]
    fn sample_parses_and_rejects_nonsense() {
        let m = MachineSpec::parse(GANTRY).unwrap();
        assert_eq!(m.axis.len(), 3);
        assert!(MachineSpec::parse("axis = []").is_err());
        let bad = "[[axis]]\nname='X'\nsteps_per_mm=0\n";
        assert!(MachineSpec::parse(bad).is_err());
        let crossed = "[[axis]]\nname='X'\nsteps_per_mm=1\nmin={at_mm=5,contact='NO'}\nmax={at_mm=1,contact='NO'}\n";
        assert!(MachineSpec::parse(crossed).is_err());
        assert!(MachineSpec::parse("bogus=1\n[[axis]]\nname='X'\nsteps_per_mm=1\n").is_err());
    }

    /// Drives the step pin of X `n` times in direction `positive`, returning scheduled flips.
    fn step(m: &mut VirtualMachine, n: u32, positive: bool, t: &mut u64) -> Vec<InputFlip> {
        let dir = if positive { 0 } else { 1 << DIR_PINS[0] };
        let mut flips = Vec::new();
        for _ in 0..n {
            *t += 100;
            m.outputs(*t, 1, dir, dir | 1 << STEP_PINS[0], &mut flips);
            *t += 100;
            m.outputs(*t, 1, dir | 1 << STEP_PINS[0], dir, &mut flips);
        }
        flips
    }

    #[test]
    fn carriage_follows_steps_and_switches_bounce() {
        let text = "bounce_us=10\n[[axis]]\nname='X'\nsteps_per_mm=10\nposition_mm=1\nmin={at_mm=0,contact='NO'}\nmax={at_mm=2,contact='NC'}\n";
        let mut m = VirtualMachine::new(&MachineSpec::parse(text).unwrap());
        let mut init = Vec::new();
        m.initial(&mut init);
        // Between the switches: NO open (high) but the intact NC loop grounds the pin.
        assert_eq!(init[0].level, false);
        let mut t = 0;
        assert!(step(&mut m, 9, false, &mut t).is_empty());
        assert!((m.positions_mm()[0] - 0.1).abs() < 1e-9);
        // The 10th step reaches 0.0: the NO min switch closes, pin stays low (no change).
        assert!(step(&mut m, 1, false, &mut t).is_empty());
        // Up to the NC max switch at 2.0 (20 steps): the loop opens, the pin goes high, bouncing.
        let flips = step(&mut m, 20, true, &mut t);
        let levels: Vec<bool> = flips.iter().map(|f| f.level).collect();
        assert_eq!(levels, [true, false, true, false, true]);
        assert_eq!(flips[4].cycle - flips[0].cycle, 10 * HZ / 1_000_000);
        assert_eq!(m.events().len(), 1);
        assert_eq!(m.steps(), [10]);
    }
}
