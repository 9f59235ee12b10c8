//! Spindle, laser and coolant: when a block's changes take effect, and the output every poll.
//!
//! Outside laser mode a change of M3/M4/M5, of S while the spindle turns, or of M7/M8/M9 waits
//! for the queue to run out (Grbl's spindle and coolant sync), then applies before the block's
//! motion. In laser mode (`$32=1`, Grbl's rules) S travels with each move, so motion does not
//! stop; only M3/M4/M5 changes, and an S change under M3 with no motion, wait. A move carries
//! its laser power ([`Power`]): S, or off for G0 and M5; under M4 the poll scales it by the
//! engine's master rate over the move's cruise rate, each millisecond. With no move running the
//! laser is on only under M3 in a G1/G2/G3 mode (focusing); during a feed hold it is off.

use super::Controller;
use crate::grbl::gcode::{Modal, Motion};
use crate::motion::shared::State;
use crate::grbl::spindle::{duty, Power, SpindleDir, SpindleOut, FLOOD, MIST};

impl<const N: usize> Controller<'_, N> {
    /// What a block with the new `modal` changes: the stage that waits for the queue, if any,
    /// and the laser power its moves carry.
    pub(super) fn tool_sync(&self, modal: &Modal, moves: bool, rapid: bool) -> (Option<(SpindleDir, f32, u8)>, Power) {
        let old = &self.modal;
        let dir_changed = modal.spindle_dir != old.spindle_dir;
        let s_changed = modal.spindle != old.spindle;
        let sync = if self.settings.laser_mode {
            dir_changed || (s_changed && modal.spindle_dir == SpindleDir::Cw && !moves)
        } else {
            dir_changed || (s_changed && modal.spindle_dir != SpindleDir::Off)
        };
        let new = (modal.spindle_dir, modal.spindle, modal.coolant);
        let stage = (sync || modal.coolant != old.coolant).then_some(new);
        let on = modal.spindle_dir != SpindleDir::Off && !rapid;
        let power = Power {
            speed: if on { modal.spindle } else { 0.0 },
            dynamic: modal.spindle_dir == SpindleDir::Ccw,
            cruise_hz: 0.0,
        };
        (stage, power)
    }

    /// Spindle and coolant as driven now: the modal ones, or all off while the safety door
    /// holds them (see `door.rs`).
    fn tool_now(&self) -> (SpindleDir, f32, u8) {
        if self.door_tool_off() {
            (SpindleDir::Off, 0.0, 0)
        } else {
            self.tool
        }
    }

    /// For status reports: the spindle speed in force (S with the override, within `$31..=$30`
    /// as Grbl reports it; 0 when off) and the `A:` letters (S/C spindle, F flood, M mist).
    pub(super) fn accessories(&self) -> (f32, [u8; 3], usize) {
        let (dir, speed, coolant) = self.tool_now();
        let mut acc = [0u8; 3];
        let mut n = 0;
        let mut push = |c: u8| {
            if let Some(a) = acc.get_mut(n) {
                *a = c;
            }
            n += 1;
        };
        let speed = match dir {
            SpindleDir::Off => 0.0,
            _ => {
                push(if dir == SpindleDir::Cw { b'S' } else { b'C' });
                let s = &self.settings;
                let v = speed * self.shared.overrides().spindle as f32 / 100.0;
                if v > 0.0 { v.max(s.spindle_min).min(s.spindle_max) } else { 0.0 }
            }
        };
        if coolant & FLOOD != 0 {
            push(b'F');
        }
        if coolant & MIST != 0 {
            push(b'M');
        }
        (speed, acc, n)
    }

    /// The spindle PWM and pins now (spindle override applied).
    pub(super) fn spindle_out(&self) -> SpindleOut {
        let s = &self.settings;
        let (dir, speed, coolant) = self.tool_now();
        if dir == SpindleDir::Off {
            // Nothing to compute (the common case, once per poll).
            return SpindleOut { mist: coolant & MIST != 0, flood: coolant & FLOOD != 0, ..SpindleOut::default() };
        }
        let state = self.shared.state();
        let speed = if !s.laser_mode {
            speed
        } else if state == State::Held {
            0.0
        } else if state != State::Idle || self.feeder.pending() > 0 {
            // S changes travel with moves: the running move's power is the one in force.
            let p = self.power_ring[self.shared.moves_done() as usize % self.power_ring.len()];
            p.at(self.shared.rate_hz())
        } else if dir == SpindleDir::Cw && matches!(self.modal.motion, Motion::Linear | Motion::CwArc | Motion::CcwArc) {
            self.modal.spindle
        } else {
            0.0
        };
        let ov = self.shared.overrides().spindle as f32 / 100.0;
        let arr = crate::grbl::spindle::PwmTiming::new(s.spindle_pwm_hz).arr;
        SpindleOut {
            ccr: duty(speed * ov, s.spindle_min, s.spindle_max, arr),
            enable: true,
            ccw: dir == SpindleDir::Ccw,
            mist: coolant & MIST != 0,
            flood: coolant & FLOOD != 0,
        }
    }
}
