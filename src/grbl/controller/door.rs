//! The safety door, as Grbl 1.1 built with its door input and without parking.
//!
//! The door opens (the input on PC15 goes active, or 0x84 arrives): motion stops with a feed
//! hold (`Door:2` while it decelerates), then the spindle and coolant go off (`Door:1` while
//! the door is still open, `Door:0` once it is closed). A cycle start `~` resumes only with the
//! door closed: spindle and coolant come back on first, and motion waits for them (`Door:3`,
//! Grbl's 4 s spindle and 1 s coolant delays; none for a laser). A door opened again during
//! the restore stops everything again. A jog is cancelled; a homing cycle fails with ALARM:7.
//! In the alarm state and in check mode the door is not acted on (Grbl); `$X` and `$H` with
//! the door open get error:13.

use super::{Controller, Door};
use crate::grbl::reply::Out;
use crate::num::wrapping_diff;
use crate::motion::shared::State;
use crate::grbl::spindle::SpindleDir;

/// Grbl's spindle-restart delay after a door, ms (`SAFETY_DOOR_SPINDLE_DELAY`).
const SPINDLE_DELAY_MS: u32 = 4000;
/// Grbl's coolant-restart delay after a door, ms (`SAFETY_DOOR_COOLANT_DELAY`).
const COOLANT_DELAY_MS: u32 = 1000;

impl<const N: usize> Controller<'_, N> {
    /// The door input as the shell read it: `open` when the pin is active (pulled to ground).
    pub fn set_door_input(&mut self, open: bool) {
        self.door_pin = open;
    }

    /// 0x84: the door opened (a sender's button, or a board without the input).
    pub fn door_command(&mut self) {
        self.door_event = true;
    }

    /// True while `~` belongs to the door cycle (the RX dispatch must not release the hold).
    pub fn door_active(&self) -> bool {
        self.door != Door::Off
    }

    /// `~` during a door state: resumes only with the door closed and motion stopped.
    #[inline(never)]
    pub fn cycle_start(&mut self) {
        if self.door == Door::Ready && !self.door_pin {
            let (dir, _, coolant) = self.tool;
            let delay = if dir != SpindleDir::Off && !self.settings.laser_mode {
                SPINDLE_DELAY_MS
            } else if coolant != 0 {
                COOLANT_DELAY_MS
            } else {
                0
            };
            self.door = Door::Restoring(self.now.wrapping_add(delay));
        }
    }

    /// The status report's state word in a door state.
    pub(super) fn door_state(&self) -> &'static [u8] {
        match self.door {
            Door::Stopping => b"Door:2",
            Door::Ajar => b"Door:1",
            Door::Ready | Door::Off => b"Door:0",
            Door::Restoring(_) => b"Door:3",
        }
    }

    /// Spindle and coolant are off for the door (from the stop until the restore).
    pub(super) fn door_tool_off(&self) -> bool {
        matches!(self.door, Door::Ajar | Door::Ready)
    }

    /// Every poll: starts, follows and ends the door cycle.
    #[inline(never)]
    pub(super) fn door_poll(&mut self, out: &mut impl Out) {
        let event = core::mem::take(&mut self.door_event) || self.door_pin;
        if event && self.homing.is_some() {
            // Grbl's ALARM:7: the door opened during the homing cycle.
            return self.homing_fail(crate::grbl::report::ALARM_HOMING_DOOR, out);
        }
        if self.alarm || self.check || self.sleep {
            self.door = Door::Off;
            return;
        }
        match self.door {
            Door::Off if !event => return,
            Door::Off | Door::Restoring(_) if event => {
                self.jog_cancel();
                self.door = Door::Stopping;
            }
            Door::Restoring(at) => {
                if wrapping_diff(self.now, at) >= 0 {
                    self.door = Door::Off;
                    self.shared.set_hold(false);
                }
                return;
            }
            Door::Stopping => {
                if self.jogging() {
                    return; // the jog cancel stops and flushes (`jogging.rs`)
                }
                if matches!(self.shared.state(), State::Run | State::Holding) {
                    self.shared.set_hold(true);
                    return;
                }
                self.door = Door::Ajar;
            }
            Door::Ajar | Door::Ready => self.door = if self.door_pin { Door::Ajar } else { Door::Ready },
            Door::Off => {}
        }
        // Held until `~` (also against a `~` the RX dispatch let through before it knew).
        if !self.jogging() {
            self.shared.set_hold(true);
        }
    }
}
