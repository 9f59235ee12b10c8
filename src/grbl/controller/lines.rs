//! Lines in: line bytes assembled, `$` and G-code lines checked and turned into a job (its
//! moves planned), the `ok` or `error:N` reply, the `$N` startup lines.
//!
//! Who uses it: the firmware shell's serial task ([`Controller::byte`]); [`Controller::poll`]
//! for the startup lines.

use super::{Controller, Job, Rate};
use crate::error::Error;
use crate::grbl::gcode::{self, Stop};
use crate::grbl::protocol::{LineEvent, LINE_LEN};
use crate::grbl::reply::{put_error, put_ok, Out, REPLY_ROOM};
use crate::grbl::report;
use crate::grbl::store::STARTUP_LINES;
use crate::motion::ramp::RampConfig;
use crate::planning::exact::Decimal;
use crate::planning::inverse_time;
use crate::planning::planner::{Limits, Planned, Planner};

impl<const N: usize> Controller<'_, N> {
    /// Takes one line byte; `false` when it cannot yet (a line is held, or fewer than
    /// [`REPLY_ROOM`] TX bytes are free): keep the byte and offer it again after a `poll`.
    #[must_use]
    #[inline(never)]
    pub fn byte(&mut self, b: u8, out: &mut impl Out) -> bool {
        if self.busy() || self.sleep || self.resync || out.room() < REPLY_ROOM {
            return false;
        }
        match self.lines.push(b) {
            LineEvent::More => {}
            LineEvent::Bad(e) => put_error(out, e),
            LineEvent::Line(n) => {
                // (A line is never longer: the bound drops the slices' panic path.)
                let n = n.min(LINE_LEN);
                let mut line = [0u8; LINE_LEN];
                line[..n].copy_from_slice(self.lines.line());
                let r = match line.first() {
                    _ if n == 0 => Ok(()),
                    Some(b'$') => self.system(&line[1..n], out),
                    // G-code is locked out in alarm, and while jogging (Grbl's error:9); a
                    // part that failed the chip check says why first.
                    _ if self.alarm || self.jogging() => {
                        self.refuse(out);
                        Err(Error::AlarmLock)
                    }
                    _ => self.gcode(&line[..n], out),
                };
                match r {
                    Err(e) => put_error(out, e),
                    Ok(()) if self.job.is_none() => self.ok(out),
                    Ok(()) => {}
                }
            }
        }
        true
    }

    /// A line's `ok`, and the reset `$C`/`$RST` asked to follow it.
    pub(super) fn ok(&mut self, out: &mut impl Out) {
        if self.tripped() {
            return; // a soft-limit trip: the line gets no reply (Grbl)
        }
        put_ok(out);
        if core::mem::take(&mut self.reset_after) {
            self.soft_reset(out);
        }
    }

    /// Runs the `$N` lines, one job at a time (`>line:ok`, as Grbl reports them).
    pub(super) fn run_startup(&mut self, out: &mut impl Out) {
        while self.startup_next < STARTUP_LINES && self.job.is_none() && out.room() >= REPLY_ROOM {
            let Some(&text) = self.stored.startup.get(self.startup_next) else { break };
            self.startup_next = self.next_startup(self.startup_next + 1);
            let line = text.as_bytes();
            if line.is_empty() {
                continue;
            }
            out.put(b">");
            out.put(line);
            out.put(b":");
            match self.gcode(line, out) {
                Err(e) => put_error(out, e),
                Ok(()) if self.job.is_none() && !self.tripped() => put_ok(out),
                Ok(()) => {}
            }
        }
    }

    /// A new job (`Job::none()`) in its slot, for the caller to fill in and start with
    /// [`Self::advance`] (built in place: a job built on the stack is copied in whole).
    #[inline(never)]
    pub(super) fn new_job(&mut self) -> &mut Job<N> {
        self.job.insert(Job::none())
    }

    /// Marks the line being carried out (or a new job) to write the persistent image.
    pub(super) fn save_later(&mut self, out: &mut impl Out) {
        match &mut self.job {
            Some(j) => j.save = true,
            None => {
                self.new_job().save = true;
                self.advance(false, out);
            }
        }
    }

    /// A G-code line: checked in full, then committed and started. In check mode (`$C`) the
    /// state and position follow the line, but nothing moves, waits or is stored.
    pub(super) fn gcode(&mut self, line: &[u8], out: &mut impl Out) -> Result<(), Error> {
        let mut block = gcode::Block::<N>::empty();
        gcode::parse_into(line, &mut block)?;
        if block.axes.get(self.axes..).unwrap_or_default().iter().any(Option::is_some) {
            return Err(Error::UnsupportedCommand);
        }
        let mut fx = gcode::Effects::none();
        let modal = self.modal.interpret_into(&block, self.planner.position_mm(), &self.offsets, &mut fx)?;
        // Soft limits: every target this line moves to, arc chord ends included (a chord
        // between two points in the box stays in it). Acted on once the line has no error.
        let motion_out = fx.motion.as_ref().is_some_and(|(t, _)| self.beyond_travel(t));
        // A rejected line leaves the planner as it was. `Planner::line_exact` changes nothing
        // when it fails, so a lone G0/G1 plans in place; a line with more that can fail after
        // it (G28/G30's second move, an arc's range check), a G93 move (`plan` rests the
        // planner first) or a soft-limit trip plans from a copy kept to roll back to.
        let lone = fx.home.is_none() && fx.arc.is_none() && !modal.inverse_time && !motion_out;
        let undo = (!lone).then(|| self.planner);
        // G93: F is 1/minutes (checked positive where a motion needs it).
        let rate = if modal.inverse_time { Rate::Minutes(1.0 / modal.feed) } else { Rate::Feed(modal.feed) };
        // (Each step in place, not a closure returning the moves: those would be copied out.)
        let roll_back = |planner: &mut Planner<N>| {
            if let Some(p) = undo {
                *planner = p;
            }
        };
        let mv = match &fx.motion {
            Some((t, rapid)) => {
                let r = if *rapid { Rate::Rapid } else { rate };
                match plan(&mut self.planner, t, &fx.exact, r, &self.limits, &self.ramped.cfg) {
                    Ok(m) => m,
                    Err(e) => {
                        roll_back(&mut self.planner);
                        return Err(e);
                    }
                }
            }
            None => None,
        };
        let mv2 = match &fx.home {
            Some(t) => match self.planner.line(t, None, &self.limits) {
                Ok(m) => m,
                Err(e) => {
                    roll_back(&mut self.planner);
                    return Err(e);
                }
            },
            None => None,
        };
        let (arc, rate) = match &fx.arc {
            Some(a) => {
                if let Err(e) = a.check_range(&self.limits.steps_per_mm) {
                    roll_back(&mut self.planner);
                    return Err(e);
                }
                let seg = a.segments(self.settings.arc_tolerance);
                // G93 over an arc: its time shared by the (equal) chords.
                let per = match rate {
                    Rate::Minutes(t) => Rate::Minutes(t / seg.chords() as f32),
                    r => r,
                };
                (Some(seg), per)
            }
            None => (None, Rate::Rapid),
        };
        let arc_out = arc.is_some_and(|mut seg| seg.any(|p| self.beyond_travel(&p)));
        let home_out = fx.home.as_ref().is_some_and(|t| self.beyond_travel(t));
        if arc_out || home_out || motion_out {
            roll_back(&mut self.planner);
            self.soft_limit_trip();
            return Ok(());
        }
        // Commit: nothing below can fail. (The offsets change in place: a copy of them
        // costs every line ~800 bytes of moves.)
        // (The work offset is compared only when something it depends on may change.)
        let store = fx.coord_write.is_some();
        let wco_may_change = store || fx.g92.is_some() || fx.tlo.is_some() || modal.coord != self.modal.coord;
        let wco = wco_may_change.then(|| self.offsets.wco(self.modal.coord));
        if let Some((slot, v)) = &fx.coord_write {
            self.offsets.stored.set(*slot, v);
        }
        if let Some(g) = &fx.g92 {
            self.offsets.g92 = *g;
        }
        if let Some(t) = fx.tlo {
            self.offsets.tlo = t;
        }
        let moves = mv.is_some() || mv2.is_some() || arc.is_some();
        let (tool, power) = self.tool_sync(&modal, moves, fx.motion.is_some_and(|m| m.1));
        if wco.is_some_and(|w| self.offsets.wco(modal.coord) != w) {
            self.wco_count = 0;
        }
        self.modal = modal;
        if self.check {
            if let Some(a) = &fx.arc {
                // Check mode: only the position follows the arc.
                // (Infallible after `check_range`: nothing may fail once committed.)
                let _ = self.planner.line(a.target(), None, &self.limits);
            }
            if fx.stop == Some(Stop::End) {
                out.put(report::PROGRAM_END);
            }
            return Ok(());
        }
        if store {
            self.stored.coords = self.offsets.stored;
        }
        if fx.drivers == Some(true) {
            self.drivers_on = true;
            self.m17 = true;
        }
        // (Set field by field on `Job::none()` in its slot: struct-update syntax, or a job
        // built on the stack and moved in, copies every field.)
        let job = self.new_job();
        job.dwell_ms = fx.dwell_ms;
        job.mv = mv;
        job.mv2 = mv2;
        job.arc = arc;
        job.rate = rate;
        job.tool = tool;
        job.power = power;
        job.drivers_off = fx.drivers == Some(false);
        job.pause = fx.stop == Some(Stop::Pause);
        job.end = fx.stop == Some(Stop::End);
        job.save = store;
        job.probe = fx.probe;
        self.advance(false, out);
        Ok(())
    }
}

/// Plans one straight move at `rate`, to `target` (and `exact`, [`Planner::line_exact`]). G93: the move starts and ends at rest (junction speed 0
/// on both sides) and its master steps decide the cruise rate that makes it last its time on
/// the ramp the engine will walk for it ([`inverse_time::cruise_hz`]), given to the planner as
/// the equivalent feed, so its axis-rate clamps apply as to any feed.
pub(super) fn plan<const N: usize>(
    planner: &mut Planner<N>,
    target: &[f32; N],
    exact: &[Option<Decimal>; N],
    rate: Rate,
    lim: &Limits<N>,
    cfg: &RampConfig,
) -> Result<Option<Planned<N>>, Error> {
    // G93 plans from rest to rest: no junction speed on either side.
    let (feed, rest) = match rate {
        Rate::Rapid => (None, false),
        Rate::Feed(f) => (Some(f), false),
        Rate::Minutes(t) => {
            // At 1 mm/min no axis limit binds: the planner's rate is exactly master / (len·60).
            let mut dry = *planner;
            let feed = match dry.line_exact(target, exact, Some(1.0), lim)? {
                Some(probe) => {
                    let master = probe.mv.steps().iter().map(|s| s.unsigned_abs()).max().unwrap_or(0);
                    let ramp = match probe.mv.path() {
                        Some(p) => inverse_time::MasterRamp::new(p.share, p.accel, lim.per_mm, cfg),
                        None => inverse_time::MasterRamp::new(1.0, 0.0, 0.0, cfg),
                    };
                    inverse_time::cruise_hz(master as u64, t * 60.0, &ramp) / probe.wanted_hz
                }
                None => 1.0,
            };
            planner.rest();
            (Some(feed), true)
        }
    };
    let planned = planner.line_exact(target, exact, feed, lim);
    if rest {
        planner.rest();
    }
    planned
}
