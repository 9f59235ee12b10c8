//! The poll: timekeeping and retries each millisecond or two — the profile rebuilt once the
//! engine is parked, the drivers enabled and disabled, a held job carried on (its moves
//! pushed as the queue has room, arcs chord by chord, dwells, flash writes).
//!
//! Who uses it: the firmware shell's serial task ([`Controller::poll`]).

use super::lines::plan;
use super::probe;
use super::{Actions, Controller, Jogging, ENABLE_SETTLE_MS, FEED_RING, POLL_REPLY_ROOM};
use crate::grbl::reply::Out;
use crate::grbl::report;
use crate::grbl::spindle::{Power, PwmTiming};
use crate::num::wrapping_diff;
use crate::motion::shared::State;
use crate::planning::planner::Planned;

impl<const N: usize> Controller<'_, N> {
    /// Timekeeping and retries: rebuilds a pending profile, enables/disables the drivers,
    /// finishes a jog cancel, carries on a held line (printing its `ok`), runs startup lines,
    /// writes a requested status report.
    pub fn poll(&mut self, now_ms: u32, out: &mut impl Out) -> Actions {
        self.now = now_ms;
        self.take_position();
        if self.profile_dirty {
            self.apply_profile();
        }
        self.feeder.service();
        self.jog_poll(out);
        self.homing_poll(out);
        self.soft_limit_poll(out);
        self.door_poll(out);
        self.drive_enable();
        if self.job.is_some() && out.room() >= POLL_REPLY_ROOM && self.advance(true, out) {
            self.ok(out);
        }
        self.run_startup(out);
        if self.status_wanted && out.room() >= report::status_len(N) {
            self.status_wanted = false;
            self.status(out);
        }
        let pulse = core::mem::take(&mut self.pulse_changed).then(|| self.settings.timing().pulse_ticks);
        let pwm = (self.pwm_hz != self.settings.spindle_pwm_hz).then(|| {
            self.pwm_hz = self.settings.spindle_pwm_hz;
            PwmTiming::new(self.pwm_hz)
        });
        Actions {
            spindle: self.spindle_out(),
            pwm,
            enable: self.drivers_on,
            enable_pin_high: self.drivers_on == self.settings.enable_invert,
            pulse_ticks: pulse,
            save: core::mem::take(&mut self.save),
            reinit: core::mem::take(&mut self.reinit),
            reset: false,
        }
    }

    /// After a soft reset: once the engine has stopped, its position is the planner's.
    pub(super) fn take_position(&mut self) {
        if self.resync && self.shared.state() == State::Idle {
            self.sync_planner();
            self.resync = false;
        }
    }

    /// Drops the queue and takes the engine's position, which must stand still (a switch,
    /// a hard limit, the end of a probe cycle), as the planner's.
    #[inline(never)]
    pub(super) fn flush_to_engine(&mut self) {
        self.feeder.abort();
        self.pushed = self.shared.moves_done();
        self.sync_planner();
    }

    /// The engine's position as the planner's.
    #[inline(never)]
    pub(super) fn sync_planner(&mut self) {
        self.planner.sync(self.shared.positions(), &self.limits);
    }

    /// Queue empty and engine idle (not held): G4, flash writes, `$` settings may act.
    pub(super) fn drained(&self) -> bool {
        self.feeder.pending() == 0 && self.shared.state() == State::Idle
    }

    /// Rebuilds the ramp table and timing if the engine is parked; otherwise asks it to park.
    pub(super) fn apply_profile(&mut self) {
        let Some(mut guard) = self.slot.try_write() else {
            self.profile_dirty = true;
            return;
        };
        self.ramped = self.settings.build_profile(self.axes, &mut guard);
        drop(guard);
        self.limits = self.settings.planner_limits(self.ramped.cfg.vmax);
        self.profile_dirty = false;
        self.pulse_changed = true;
    }

    /// Drivers: on for motion (and M17), off `$1` ms after the machine goes idle.
    pub(super) fn drive_enable(&mut self) {
        if !self.drivers_on {
            self.enabled_at = None;
            return;
        }
        self.enabled_at.get_or_insert(self.now);
        let waiting = self.job.is_some_and(|j| j.mv.is_some() || j.mv2.is_some() || j.arc.is_some());
        let keep = (self.m17 || self.settings.idle_delay_ms == 255) && !self.sleep;
        if keep || waiting || !self.drained() {
            self.idle_since = None;
            return;
        }
        let since = *self.idle_since.get_or_insert(self.now);
        if self.sleep || self.now.wrapping_sub(since) >= self.settings.idle_delay_ms as u32 {
            self.drivers_on = false;
            self.enabled_at = None;
            self.idle_since = None;
        }
    }

    pub(super) fn drivers_ready(&self) -> bool {
        self.drivers_on && self.enabled_at.is_some_and(|t| self.now.wrapping_sub(t) >= ENABLE_SETTLE_MS)
    }

    /// Pushes one planned move; false while it does not fit (or the drivers are settling).
    pub(super) fn push(&mut self, pl: &Planned<N>, jog: bool, power: Power) -> bool {
        if !self.drivers_ready() {
            self.drivers_on = true;
            return false;
        }
        if self.profile_dirty || self.feeder.push(pl.mv).is_err() {
            return false;
        }
        self.feed_ring[self.pushed as usize % FEED_RING] = pl.mm_per_step;
        let cruise_hz = crate::motion::ramp::hz_of_period(pl.mv.cruise());
        self.power_ring[self.pushed as usize % FEED_RING] = Power { cruise_hz, ..power };
        self.pushed = self.pushed.wrapping_add(1);
        self.idle_since = None;
        if jog {
            self.jog = Jogging::On;
        }
        true
    }

    /// Carries the job on as far as it can; true when it just finished.
    pub(super) fn advance(&mut self, in_poll: bool, out: &mut impl Out) -> bool {
        // The common wait, a move held for queue room, decided without copying the job out
        // (a job is ~400 bytes; streaming polls this many times per line).
        if self.job.as_ref().is_some_and(|j| j.waits_for_room()) && self.feeder.full() {
            return false;
        }
        let Some(mut job) = self.job else { return false };
        let done = 'run: {
            if job.home && self.homing.is_some() {
                break 'run false;
            }
            if let Some(l) = job.listing {
                job.listing = self.list(l, out);
                if job.listing.is_some() {
                    break 'run false;
                }
            }
            if let Some(t) = job.tool {
                // Grbl stops for a spindle or coolant change (laser mode: see `tool_sync`).
                if !self.drained() {
                    break 'run false;
                }
                self.tool = t;
                job.tool = None;
            }
            if let Some(ms) = job.dwell_ms {
                // The dwell starts at a poll (its clock) once the queue has run out.
                if !self.drained() || (job.dwell_end.is_none() && !in_poll) {
                    break 'run false;
                }
                let end = *job.dwell_end.get_or_insert(self.now.wrapping_add(ms));
                if wrapping_diff(self.now, end) < 0 {
                    break 'run false;
                }
                job.dwell_ms = None;
            }
            if job.save {
                // The flash write stalls the CPU: only from a poll, with the machine at rest.
                if !in_poll || !self.drained() {
                    break 'run false;
                }
                self.stored.settings = self.settings;
                self.stored.seq = self.stored.seq.wrapping_add(1);
                self.save = true;
                job.save = false;
            }
            if job.probe != 0 && job.probe & probe::ARMED == 0 && !self.probe_step(&mut job, out) {
                break 'run false;
            }
            for slot in [&mut job.mv, &mut job.mv2] {
                if let Some(pl) = slot {
                    if !self.push(pl, job.jog, job.power) {
                        break 'run false;
                    }
                    *slot = None;
                }
            }
            // Arc chords, one planned move at a time. `Arc::check_range` made planning
            // infallible; were it not, the chord would merge into the next (the position stays
            // exact).
            while let Some(seg) = job.arc.as_mut() {
                let Some(p) = seg.next() else {
                    job.arc = None;
                    break;
                };
                job.mv = plan(&mut self.planner, &p, &[None; N], job.rate, &self.limits, &self.ramped.cfg).unwrap_or(None);
                if let Some(pl) = &job.mv {
                    if !self.push(pl, false, job.power) {
                        break 'run false;
                    }
                    job.mv = None;
                }
            }
            if job.probe & probe::ARMED != 0 && !self.probe_step(&mut job, out) {
                break 'run false;
            }
            if job.drivers_off || job.pause || job.end {
                if !self.drained() {
                    break 'run false;
                }
                if job.drivers_off {
                    self.drivers_on = false;
                    self.m17 = false;
                }
                if job.pause && !self.check {
                    self.shared.set_hold(true);
                }
                if job.end {
                    out.put(report::PROGRAM_END);
                }
            }
            true
        };
        // (Two stores: one `Option` built first would be copied whole, `None` included.)
        if done {
            self.job = None;
        } else {
            self.job = Some(job);
        }
        done
    }
}
