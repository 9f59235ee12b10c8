//! The virtual machine's state while it runs: carriages that follow the step and dir pins,
//! bouncing limit switches, the encoder's motor with its faults, the probe and the door; the
//! board drives it as its [`Plant`].

use std::any::Any;

use super::spec::*;
use crate::emu::plant::Plant;
use crate::emu::{InputFlip, Port, DIR_PINS, HZ, STEP_PINS};

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
