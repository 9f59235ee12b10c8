//! `$H` homing (and grblHAL's `$HX`, `$HY`, `$HZ`), Grbl 1.1's `limits_go_home` as a state
//! machine [`Controller::poll`] runs: Z first, then X and Y together (`$H`); each group makes
//! four passes, every one a planned move through the engine:
//!
//! 0. seek toward the switches at `$25`, at most 1.5 × the travel `$130+i`;
//! 1. pull-off `$27` at `$25`;
//! 2. locate toward the switches at `$24`, at most 5 × `$27`;
//! 3. pull-off `$27` at `$25`;
//!
//! with a `$26` ms pause after each. Toward the switch means positive unless the axis's bit of
//! `$23` is set. In an approach pass a switch closing stops the motion at once (the firmware's
//! limit interrupt stops the engine when [`Controller::homing_watch`] names the axis; the poll
//! does the same from the pins it is given, within a millisecond): the engine's position is
//! the trip position, exact. The axes still searching go on to the pass's target; a switch
//! already closed when a pass starts counts as found at once (the pull-off then clears it, as
//! Grbl). As in Grbl the path feed is the rate × √(axes moving), so each axis moves at the rate.
//!
//! Failures, as Grbl: ALARM:9 (an approach reached its end without its switch), ALARM:8 (a
//! switch still closed after a pull-off), ALARM:6 (Ctrl-X during the cycle, in
//! [`Controller::soft_reset`]); then the `$H` line's `ok` and a reset into the alarm state.
//!
//! The end position follows Grbl without `HOMING_FORCE_SET_ORIGIN`: a homed axis's machine
//! position is −`$27` when it homes toward its max end, and −`$130+i` + `$27` toward its min
//! end, so machine zero is the max end's switch and the soft-limit box `-$130+i ..= 0` holds.
//! Success clears the alarm lock; a full `$H` then runs the startup lines.

use super::{Controller, Homing};
use crate::num::{round_i32, wrapping_diff};
use crate::error::Error;
use crate::grbl::reply::Out;
use crate::motion::shared::State;
use crate::grbl::report;
use crate::grbl::spindle::Power;

impl<const N: usize> Controller<'_, N> {
    /// `$H` (`axis` `None`) or `$HX`/`$HY`/`$HZ`: checks and starts the cycle; the line's `ok`
    /// comes when it ends.
    #[inline(never)]
    pub(super) fn home_start(&mut self, axis: Option<u8>, out: &mut impl Out) -> Result<(), Error> {
        if !self.settings.homing {
            return Err(Error::SettingDisabled);
        }
        if !self.drained() || self.check || self.jogging() {
            return Err(Error::NotIdle);
        }
        let (group, next) = match axis {
            None => (4, 3),
            Some(b'X') => (1, 0),
            Some(b'Y') => (2, 0),
            Some(b'Z') => (4, 0),
            _ => return Err(Error::InvalidStatement),
        };
        // Contradictory settings would give a wrong position: refuse them.
        let s = &self.settings;
        if (0..3).any(|i| (group | next) & 1 << i != 0 && s.homing_pulloff >= s.max_travel[i]) {
            return Err(Error::InvalidStatement);
        }
        self.homing = Some(Homing {
            group,
            next,
            pass: 0,
            found: 0,
            moved: false,
            moving: false,
            all: axis.is_none(),
            epoch: 0,
            start_at: self.now,
            target: [0; 3],
        });
        self.new_job().home = true;
        self.advance(false, out);
        Ok(())
    }

    /// While homing: the axes whose switch closing must stop the motion now (the approach
    /// passes' axes still searching, only while their move runs; the firmware's limit
    /// interrupt stops the engine for them, hard limits are off). `None` when not homing.
    pub fn homing_watch(&self) -> Option<u8> {
        self.homing.map(|h| if h.moving && h.pass & 1 == 0 { h.group & !h.found } else { 0 })
    }

    /// One step of the cycle (every poll).
    #[inline(never)]
    pub(super) fn homing_poll(&mut self, out: &mut impl Out) {
        let Some(mut h) = self.homing else { return };
        // A feed hold does not pause homing (Grbl reads none during the cycle).
        self.shared.set_hold(false);
        let approach = h.pass & 1 == 0;
        let pins = self.limit_pins & h.group;
        if h.moving {
            let stopped = self.shared.epoch() != h.epoch;
            if !stopped {
                if approach && pins & !h.found != 0 {
                    self.feeder.abort(); // a switch closed: stop at once (poll-side path)
                }
                if self.feeder.pending() > 0 || self.shared.state() != State::Idle {
                    self.homing = Some(h);
                    return;
                }
            } else if self.shared.state() != State::Idle {
                self.homing = Some(h);
                return;
            } else {
                // Stopped short (a switch): its contacts settle for `$26` ms before the pins
                // are believed (a bounce must not read as released).
                h.start_at = self.now.wrapping_add(self.settings.homing_debounce_ms);
            }
            // Stopped at a switch or at the target: the engine's position is exact.
            self.flush_to_engine();
            h.moving = false;
        }
        if wrapping_diff(self.now, h.start_at) < 0 {
            self.homing = Some(h);
            return;
        }
        let at = *self.planner.position_steps();
        if approach {
            h.found |= pins;
        }
        // The axes still to move: an approach's until their switch closes.
        let moving = h.group & !h.found;
        let arrived = h.moved && (0..3).all(|i| moving & 1 << i == 0 || at[i] == h.target[i] as i64);
        if moving == 0 || (arrived && pins == 0 && !approach) {
            return self.homing_pass_done(h);
        }
        if arrived {
            return self.homing_fail(if approach { report::ALARM_APPROACH } else { report::ALARM_PULLOFF }, out);
        }
        let s = &self.settings;
        if !h.moved {
            let mut travel = 0.0;
            for i in 0..3 {
                if h.group & 1 << i != 0 {
                    travel = libm::fmaxf(travel, s.max_travel[i]);
                }
            }
            let pulloff = s.homing_pulloff;
            let dist = match h.pass {
                0 => 1.5 * travel,
                2 => 5.0 * pulloff,
                _ => pulloff,
            };
            for i in 0..3 {
                let toward_max = s.homing_dir & 1 << i == 0;
                let d = round_i32(dist * s.steps_per_mm[i]);
                h.target[i] = at[i] as i32 + if toward_max == approach { d } else { -d };
            }
        }
        // The axes still to move go to their targets (again, after a stop short); the others stay.
        let mut mm = *self.planner.position_mm();
        for i in 0..3 {
            if moving & 1 << i != 0 {
                mm[i] = h.target[i] as f32 / s.steps_per_mm[i];
            }
        }
        let rate = if h.pass == 2 { s.homing_feed } else { s.homing_seek };
        // √(axes moving): a group has one or two axes.
        let feed = rate * if moving.count_ones() > 1 { core::f32::consts::SQRT_2 } else { 1.0 };
        let mut planner = self.planner;
        h.epoch = self.shared.epoch();
        match planner.line(&mm, Some(feed), &self.limits) {
            Ok(Some(pl)) => {
                if !self.push(&pl, false, Power::default()) {
                    self.homing = Some(h);
                    return; // drivers settling or queue busy: next poll
                }
                self.planner = planner;
                h.moving = true;
            }
            // Nothing to move (a zero distance): the pass ends where it is.
            Ok(None) => {}
            // A target the planner cannot reach (steps beyond i32): no switch can be found.
            Err(_) => return self.homing_fail(report::ALARM_APPROACH, out),
        }
        h.moved = true;
        self.homing = Some(h);
    }

    /// A pass ended well: pause `$26` ms, then the next pass, group, or the end.
    #[inline(never)]
    fn homing_pass_done(&mut self, mut h: Homing) {
        h.pass += 1;
        h.found = 0;
        h.moved = false;
        h.start_at = self.now.wrapping_add(self.settings.homing_debounce_ms);
        if h.pass < 4 {
            self.homing = Some(h);
            return;
        }
        // The group is home: Grbl's machine position (see the module).
        let s = &self.settings;
        let mut p = self.shared.positions();
        for i in 0..3 {
            if h.group & 1 << i != 0 {
                let pulloff = s.homing_pulloff;
                let mm = if s.homing_dir & 1 << i != 0 { pulloff - s.max_travel[i] } else { -pulloff };
                p[i] = round_i32(mm * s.steps_per_mm[i]);
            }
        }
        self.feeder.set_positions(p);
        self.planner.sync(p, &self.limits);
        self.homing = None;
        if h.next != 0 {
            self.homing = Some(Homing { group: h.next, next: 0, pass: 0, ..h });
            return;
        }
        self.alarm = false;
        if h.all {
            self.startup_next = self.next_startup(0);
        }
    }

    /// A failed cycle: stop, the alarm, then (after the line's `ok`) a reset into alarm.
    pub(super) fn homing_fail(&mut self, alarm: u8, out: &mut impl Out) {
        self.feeder.abort();
        self.homing = None;
        self.alarm = true;
        report::alarm(out, alarm);
        self.reset_after = true;
    }
}
