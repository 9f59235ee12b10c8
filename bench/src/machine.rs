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
//! An optional `[encoder]` puts a quadrature encoder on one axis's motor: the
//! carriage follows the motor's rotor, which follows the step pulses except where a `[[fault]]`
//! says otherwise — `miss_steps` pulses that do not move it, or `slip_steps` it falls back at
//! once (a crash) — from a time (`at_s`, taking effect at the next step edge) or a carriage
//! position (`at_mm`, when the carriage reaches it). The encoder's count is
//! `floor(rotor × counts_per_step)` (negated with `invert`); each count change is one edge of A
//! (PA6) or B (PA7), A leading B going forward, `lag_us` after the step edge that caused it
//! and at least `edge_ns` after the previous edge.
//!
//! An optional `[probe]` is a touch probe on one axis (`axis = "Z"`, `at_mm = -5.0`):
//! in contact while that carriage is at or below `at_mm`, wired NO to ground on the probe input
//! (PC14, pulled up: contact = low), with no bounce, its level changing at the step edge that
//! crosses `at_mm`.
//!
//! Optional `[[door]]` entries open and close the safety door at given times (`at_s = 1.0`,
//! `open = true`): the door input (PC15, pulled up) goes low while the door is open, as a
//! switch closing to ground would drive it.
//!
//! `spec.rs` reads and checks the machine file; `model.rs` is the machine while it runs.

mod model;
mod spec;

pub use model::{SwitchEvent, VirtualMachine};
pub use spec::{AxisSpec, Contact, DoorEvent, EncoderSpec, Fault, MachineSpec, ProbeSpec, Switch, DOOR_PIN, ENCODER_PINS, LIMIT_PINS, PROBE_PIN};
