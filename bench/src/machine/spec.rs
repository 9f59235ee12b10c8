//! The machine file (TOML): axes with their switches, the optional encoder, probe and door,
//! checked on load. The pins a machine drives are the firmware's (`ddastep::board`).

use std::path::Path;

use anyhow::{bail, Context, Result};
use ddastep::board;
use serde::Deserialize;

/// GPIOA pins of the X, Y, Z limit inputs (the machine has at most these three axes).
pub const LIMIT_PINS: [u8; 3] = [board::LIMIT_PINS[0], board::LIMIT_PINS[1], board::LIMIT_PINS[2]];

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

/// GPIOA pins of the encoder's A and B outputs (TIM3 TI1, TI2).
pub const ENCODER_PINS: [u8; 2] = board::ENCODER_PINS;

/// A quadrature encoder on one axis's motor.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EncoderSpec {
    /// The axis's name in the file (its motor).
    pub axis: String,
    /// Counts (edges of A and B) per motor step.
    pub counts_per_step: f64,
    #[serde(default)]
    pub invert: bool,
    /// Rotor lag behind the step edge, µs.
    #[serde(default)]
    pub lag_us: f64,
    /// Shortest time between two encoder edges, ns (the firmware's TIM3 filter needs 111).
    #[serde(default = "default_edge_ns")]
    pub edge_ns: f64,
}

fn default_edge_ns() -> f64 {
    125.0
}

/// Lost steps injected on the encoder's motor.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Fault {
    /// From this simulated time (the next step edge after it).
    #[serde(default)]
    pub at_s: Option<f64>,
    /// When the carriage reaches this position, mm.
    #[serde(default)]
    pub at_mm: Option<f64>,
    /// The next this many step pulses do not move the rotor.
    #[serde(default)]
    pub miss_steps: u32,
    /// The rotor falls back this many steps at once, against its last direction.
    #[serde(default)]
    pub slip_steps: u32,
}

/// GPIOC pin of the probe input.
pub const PROBE_PIN: u8 = board::PROBE_PIN;

/// A touch probe: contact while the axis's carriage is at or below `at_mm`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProbeSpec {
    pub axis: String,
    pub at_mm: f64,
}

/// GPIOC pin of the safety door input.
pub const DOOR_PIN: u8 = board::DOOR_PIN;

/// The safety door opens or closes at a simulated time.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DoorEvent {
    pub at_s: f64,
    pub open: bool,
}

/// A machine file.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MachineSpec {
    /// Contact bounce after each change of a limit pin, µs.
    #[serde(default = "default_bounce")]
    pub bounce_us: f64,
    pub axis: Vec<AxisSpec>,
    #[serde(default)]
    pub encoder: Option<EncoderSpec>,
    #[serde(default)]
    pub fault: Vec<Fault>,
    #[serde(default)]
    pub probe: Option<ProbeSpec>,
    #[serde(default)]
    pub door: Vec<DoorEvent>,
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
        if let Some(e) = &spec.encoder {
            if !spec.axis.iter().any(|a| a.name == e.axis) {
                bail!("encoder: no axis {}", e.axis);
            }
            if !(e.counts_per_step > 0.0 && e.counts_per_step <= 64.0 && e.lag_us >= 0.0 && e.edge_ns >= 0.0) {
                bail!("encoder: counts_per_step must be in (0, 64], lag_us and edge_ns not negative");
            }
        } else if !spec.fault.is_empty() {
            bail!("faults act on the encoder's motor: add an [encoder]");
        }
        if spec.door.iter().any(|d| !(d.at_s.is_finite() && d.at_s >= 0.0)) {
            bail!("door: at_s must be a time >= 0");
        }
        for f in &spec.fault {
            if f.at_s.is_some() == f.at_mm.is_some() {
                bail!("a fault needs one of at_s and at_mm");
            }
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

#[cfg(test)]
mod tests {
    use super::*;

    const GANTRY: &str = include_str!("../../demo/gantry300.toml");

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
}
