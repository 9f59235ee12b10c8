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
//!
//! An optional `[encoder]` puts a quadrature encoder on one axis's motor (issue 14): the
//! carriage follows the motor's rotor, which follows the step pulses except where a `[[fault]]`
//! says otherwise — `miss_steps` pulses that do not move it, or `slip_steps` it falls back at
//! once (a crash) — from a time (`at_s`, taking effect at the next step edge) or a carriage
//! position (`at_mm`, when the carriage reaches it). The encoder's count is
//! `floor(rotor × counts_per_step)` (negated with `invert`); each count change is one edge of A
//! (PA6) or B (PA7), A leading B going forward, `lag_us` after the step edge that caused it
//! and at least `edge_ns` after the previous edge.
//!
//! An optional `[probe]` (issue 12) is a touch probe on one axis (`axis = "Z"`, `at_mm = -5.0`):
//! in contact while that carriage is at or below `at_mm`, wired NO to ground on the probe input
//! (PC14, pulled up: contact = low), with no bounce, its level changing at the step edge that
//! crosses `at_mm`.
//!
//! Optional `[[door]]` entries open and close the safety door at given times (`at_s = 1.0`,
//! `open = true`): the door input (PC15, pulled up) goes low while the door is open, as a
//! switch closing to ground would drive it.

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

/// GPIOA pins of the encoder's A and B outputs (TIM3 TI1, TI2; README pin map).
pub const ENCODER_PINS: [u8; 2] = [6, 7];

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

/// GPIOC pin of the probe input (README pin map; `ddastep::board::PROBE_PIN`).
pub const PROBE_PIN: u8 = 14;

/// A touch probe: contact while the axis's carriage is at or below `at_mm`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProbeSpec {
    pub axis: String,
    pub at_mm: f64,
}

/// GPIOC pin of the safety door input (README pin map; `ddastep::board::DOOR_PIN`).
pub const DOOR_PIN: u8 = 15;

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

/// The encoder's motor: its rotor, the count it shows, the faults still to come.
#[derive(Clone, Debug)]
struct Motor {
    spec: EncoderSpec,
    axis: usize,
    /// Rotor position, steps (the carriage's `steps` follow it).
    rotor: i64,
    count: i64,
    /// Step pulses still to be missed.
    missing: u32,
    last_dir: i64,
    faults: Vec<Fault>,
    /// Cycle of the last encoder edge scheduled.
    last_edge: u64,
    /// Faults applied: (cycle, steps lost).
    applied: Vec<(u64, u32)>,
}

/// (A, B) levels of quadrature state `count` (A leads B counting up).
fn quadrature(count: i64) -> (bool, bool) {
    [(false, false), (true, false), (true, true), (false, true)][count.rem_euclid(4) as usize]
}

/// The virtual machine: carriages and their switches.
#[derive(Clone, Debug)]
pub struct VirtualMachine {
    bounce_cycles: u64,
    carriages: Vec<Carriage>,
    events: Vec<SwitchEvent>,
    motor: Option<Motor>,
    /// The probe: axis, contact at or below this position (mm), in contact now.
    probe: Option<(usize, f64, bool)>,
    /// Probe input changes: (cycle, in contact).
    probe_events: Vec<(u64, bool)>,
    /// The door's openings and closings.
    door: Vec<DoorEvent>,
}

impl VirtualMachine {
    pub fn new(spec: &MachineSpec) -> Self {
        let carriages = spec.axis.iter().map(|a| Carriage { spec: a.clone(), steps: 0, level: true }).collect();
        let motor = spec.encoder.as_ref().map(|e| Motor {
            axis: spec.axis.iter().position(|a| a.name == e.axis).unwrap_or(0),
            spec: e.clone(),
            rotor: 0,
            count: 0,
            missing: 0,
            last_dir: 1,
            faults: spec.fault.clone(),
            last_edge: 0,
            applied: Vec::new(),
        });
        let probe = spec.probe.as_ref().map(|p| (spec.axis.iter().position(|a| a.name == p.axis).unwrap_or(0), p.at_mm, false));
        VirtualMachine {
            bounce_cycles: (spec.bounce_us * HZ as f64 / 1e6) as u64,
            carriages,
            events: Vec::new(),
            motor,
            probe,
            probe_events: Vec::new(),
            door: spec.door.clone(),
        }
    }

    /// Probe input changes: (cycle, in contact), in time order.
    pub fn probe_events(&self) -> &[(u64, bool)] {
        &self.probe_events
    }

    // the probe's contact after a move of its axis: a flip of PC14 when it changed
    fn probe_check(&mut self, t: u64, flips: &mut Vec<InputFlip>) {
        let Some((axis, at, was)) = self.probe else { return };
        let on = self.carriages.get(axis).is_some_and(|c| c.position_mm() <= at + 1e-9);
        if on != was || t == 0 {
            self.probe = Some((axis, at, on));
            if t > 0 {
                self.probe_events.push((t, on));
            }
            flips.push(InputFlip { cycle: t, port: Port::C, pin: PROBE_PIN, level: !on });
        }
    }

    /// The encoder's count (what its A/B edges add up to), if the machine has one.
    pub fn encoder_count(&self) -> Option<i64> {
        self.motor.as_ref().map(|m| m.count)
    }

    /// Faults applied so far: (cycle, steps lost).
    pub fn faults_applied(&self) -> &[(u64, u32)] {
        self.motor.as_ref().map_or(&[], |m| &m.applied)
    }

    // one step pulse on the encoder's axis at `t`, in direction `dir`: the rotor's move (0 when
    // missed), with the faults due applied; schedules the encoder's edges
    fn motor_step(&mut self, t: u64, dir: i64, flips: &mut Vec<InputFlip>) -> i64 {
        let Some(m) = &mut self.motor else { return dir };
        let c = &self.carriages[m.axis];
        let pos = c.position_mm();
        let due = |f: &Fault| {
            f.at_s.is_some_and(|s| t as f64 >= s * HZ as f64)
                || f.at_mm.is_some_and(|x| (pos - x).abs() * c.spec.steps_per_mm < 0.5)
        };
        let mut moved = dir;
        let mut i = 0;
        while i < m.faults.len() {
            if due(&m.faults[i]) {
                let f = m.faults.remove(i);
                m.missing += f.miss_steps;
                moved -= f.slip_steps as i64 * m.last_dir;
                m.applied.push((t, f.miss_steps + f.slip_steps));
            } else {
                i += 1;
            }
        }
        if m.missing > 0 {
            m.missing -= 1;
            moved -= dir;
        }
        m.last_dir = dir;
        m.rotor += moved;
        let sign = if m.spec.invert { -1.0 } else { 1.0 };
        let count = (m.rotor as f64 * m.spec.counts_per_step * sign).floor() as i64;
        let gap = (m.spec.edge_ns * HZ as f64 / 1e9).ceil() as u64;
        let start = t + (m.spec.lag_us * HZ as f64 / 1e6) as u64;
        while m.count != count {
            let (a0, b0) = quadrature(m.count);
            m.count += (count - m.count).signum();
            let (a1, b1) = quadrature(m.count);
            let at = start.max(m.last_edge + gap);
            m.last_edge = at;
            let (pin, level) = if a0 != a1 { (ENCODER_PINS[0], a1) } else { (ENCODER_PINS[1], b1) };
            debug_assert!(a0 != a1 || b0 != b1);
            flips.push(InputFlip { cycle: at, port: Port::A, pin, level });
        }
        moved
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
        if let Some(m) = &self.motor {
            let lost: u32 = m.applied.iter().map(|a| a.1).sum();
            out += &format!("\n  encoder on {}: count {:+}, {} fault(s) applied, {lost} steps lost", m.spec.axis, m.count, m.applied.len());
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
        self.probe_check(0, flips);
        for d in &self.door {
            flips.push(InputFlip { cycle: (d.at_s * HZ as f64) as u64, port: Port::C, pin: DOOR_PIN, level: !d.open });
        }
        if self.motor.is_some() {
            for pin in ENCODER_PINS {
                flips.push(InputFlip { cycle: 0, port: Port::A, pin, level: false });
            }
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
            let dir = if dir_low != c.spec.invert_dir { 1 } else { -1 };
            let moved = if self.motor.as_ref().is_some_and(|m| m.axis == i) { self.motor_step(t, dir, flips) } else { dir };
            let c = &mut self.carriages[i];
            c.steps += moved;
            let level = c.pin_level();
            if level != c.level {
                c.level = level;
                self.events.push(SwitchEvent { cycle: t, axis: i, level });
                self.bounce(t, LIMIT_PINS[i], level, flips);
            }
            if self.probe.is_some_and(|p| p.0 == i) {
                self.probe_check(t, flips);
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
    fn encoder_edges_follow_the_rotor_and_faults_lose_steps() {
        let text = "[[axis]]\nname='X'\nsteps_per_mm=10\n[encoder]\naxis='X'\ncounts_per_step=4\nlag_us=1\n\
                    [[fault]]\nat_mm=1.0\nmiss_steps=3\n[[fault]]\nat_mm=0.5\nslip_steps=2\n";
        let spec = MachineSpec::parse(text).unwrap();
        let mut m = VirtualMachine::new(&spec);
        let mut t = 0;
        let flips = step(&mut m, 4, true, &mut t);
        // 16 counts: alternating A and B edges, A first, 125 ns apart, the first 1 µs late.
        assert_eq!(flips.len(), 16);
        assert_eq!((flips[0].pin, flips[0].level, flips[1].pin, flips[1].level), (6, true, 7, true));
        assert_eq!(flips[0].cycle, 100 + 72);
        assert!(flips.windows(2).all(|w| w[1].cycle >= w[0].cycle));
        assert_eq!(m.encoder_count(), Some(16));
        // At 0.5 mm the rotor slips 2 steps back; at 1.0 mm (reached 2 steps later than
        // commanded) it misses 3 pulses.
        step(&mut m, 1 + 5 + 2 + 3 + 4, true, &mut t);
        assert_eq!(m.steps(), [4 + 15 - 2 - 3]);
        assert_eq!(m.encoder_count(), Some(4 * 14));
        assert_eq!(m.faults_applied().iter().map(|f| f.1).collect::<Vec<_>>(), [2, 3]);
        // Backwards: counts down.
        step(&mut m, 14, false, &mut t);
        assert_eq!(m.encoder_count(), Some(0));
        assert!(MachineSpec::parse("[[axis]]\nname='X'\nsteps_per_mm=1\n[[fault]]\nat_s=1\n").is_err());
        assert!(MachineSpec::parse("[[axis]]\nname='X'\nsteps_per_mm=1\n[encoder]\naxis='Y'\ncounts_per_step=1\n").is_err());
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
