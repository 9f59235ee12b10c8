//! The Grbl 1.1 front end: line bytes in, replies out, moves into the queue.
//!
//! Who uses it: the firmware's serial task. The RX interrupt sorts bytes with
//! [`crate::protocol::realtime`]: `!`/`~` go straight to `Shared::set_hold`, `?` to
//! [`Controller::status_request`], Ctrl-X to [`Controller::soft_reset`] (the shell also empties
//! its RX ring), the rest into an RX ring of at least 128 bytes. The task feeds that ring to
//! [`Controller::byte`] while it returns `true`, and calls [`Controller::poll`] at least every
//! millisecond or two (also when no byte arrives) and applies the [`Actions`] it returns.
//!
//! Every line becomes a job carried out in Grbl's order — listing, dwell, G92, motion, then
//! M18/M0/M2 — and gets its `ok` only when the job is done: a motion line whose move does not
//! fit in the queue is held (and `byte` takes nothing more) until a later `poll` pushes it, so a
//! character-counting sender never overruns us and nothing accepted is lost. G4, G92, M0, M2
//! and M18 wait until the queue has run out and the engine is idle.

mod system;

use crate::gcode::{self, Modal, Stop};
use crate::planner::{Limits, Planned, Planner};
use crate::protocol::{put_error, put_ok, Error, LineBuf, LineEvent, Out, LINE_LEN, REPLY_ROOM};
use crate::queue::{Feeder, Shared, State};
use crate::ramp::RampSlot;
use crate::report;
use crate::settings::{Ramped, Settings};

/// Time from enabling the drivers to the first step, in poll milliseconds (2 ≥ 1 ms real).
pub const ENABLE_SETTLE_MS: u32 = 2;
/// Free TX bytes before a held line may finish (`[MSG:Pgm End]` and `ok`).
const POLL_REPLY_ROOM: usize = 32;
/// Moves whose feed (mm per master step) is remembered for status reports.
const FEED_RING: usize = 32;

/// What the firmware shell must do after a [`Controller::poll`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Actions {
    /// Drivers enabled (logical).
    pub enable: bool,
    /// Level of the enable pin (the board's enable is active low; `$4` inverts).
    pub enable_pin_high: bool,
    /// New step pulse width for the compare register (CCR1), timer ticks.
    pub pulse_ticks: Option<u32>,
    /// Settings changed: write [`Controller::settings`]`.to_bytes()` to flash.
    pub save: bool,
    /// `$2`/`$3` (or `$RST`) changed the pin map, which the engine takes at boot: save, then
    /// reset the MCU.
    pub restart: bool,
}

/// A long reply written a line at a time as TX room appears.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Listing {
    Settings(u8),
    Params(u8),
}

/// One accepted line still being carried out; each stage is cleared when done.
#[derive(Clone, Copy, Debug)]
struct Job<const N: usize> {
    listing: Option<Listing>,
    dwell_ms: Option<u32>,
    dwell_end: Option<u32>,
    set_steps: Option<[i32; N]>,
    mv: Option<Planned<N>>,
    drivers_off: bool,
    pause: bool,
    end: bool,
    /// Settings changed: report [`Actions::save`] from the poll that sends the `ok`, so the
    /// flash write (which stalls the CPU) happens before the next line can start a move.
    save: bool,
}

impl<const N: usize> Job<N> {
    const NONE: Self = Job {
        listing: None,
        dwell_ms: None,
        dwell_end: None,
        set_steps: None,
        mv: None,
        drivers_off: false,
        pause: false,
        end: false,
        save: false,
    };
}

/// The Grbl-compatible controller for `N` axes.
pub struct Controller<'a, const N: usize> {
    feeder: Feeder<'a, N>,
    shared: &'a Shared<N>,
    slot: &'a RampSlot,
    settings: Settings,
    ramped: Ramped,
    limits: Limits<N>,
    profile_dirty: bool,
    lines: LineBuf,
    modal: Modal,
    planner: Planner<N>,
    job: Option<Job<N>>,
    alarm: bool,
    status_wanted: bool,
    now: u32,
    drivers_on: bool,
    m17: bool,
    enabled_at: Option<u32>,
    idle_since: Option<u32>,
    save: bool,
    restart: bool,
    pulse_changed: bool,
    pushed: u32,
    feed_ring: [f32; FEED_RING],
    /// After a soft reset: take the engine's position once it has stopped.
    resync: bool,
}

impl<'a, const N: usize> Controller<'a, N> {
    /// A controller at the engine's current position; builds the profile (or does so at the
    /// first `poll` the engine is parked for).
    pub fn new(feeder: Feeder<'a, N>, shared: &'a Shared<N>, slot: &'a RampSlot, settings: Settings) -> Self {
        let mut c = Controller {
            feeder,
            shared,
            slot,
            settings,
            ramped: Ramped::wanted(&settings, N),
            limits: Limits::new(&settings, 1),
            profile_dirty: true,
            lines: LineBuf::new(),
            modal: Modal::RESET,
            planner: Planner::new(),
            job: None,
            alarm: false,
            status_wanted: false,
            now: 0,
            drivers_on: settings.idle_delay_ms == 255,
            m17: false,
            enabled_at: None,
            idle_since: None,
            save: false,
            restart: false,
            pulse_changed: true,
            pushed: shared.moves_done(),
            feed_ring: [0.0; FEED_RING],
            resync: false,
        };
        c.apply_profile();
        c.planner.sync(shared.positions(), &c.limits);
        c
    }

    /// The settings in force (for flash after [`Actions::save`]).
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The ramp the profile was built with (what `$I` reports).
    pub fn ramped(&self) -> &Ramped {
        &self.ramped
    }

    /// Moves queued or running.
    pub fn pending_moves(&self) -> u32 {
        self.feeder.pending()
    }

    /// The planner's absolute step position: where the engine ends once the queue runs out.
    pub fn planned_steps(&self) -> [i64; N] {
        *self.planner.position_steps()
    }

    /// True while a line is being carried out: [`Self::byte`] takes nothing until it is done.
    pub fn busy(&self) -> bool {
        self.job.is_some()
    }

    /// The start-up banner (also after a soft reset).
    pub fn welcome(&mut self, out: &mut impl Out) {
        out.put(report::BANNER);
        if self.alarm {
            out.put(report::UNLOCK_HINT);
        }
    }

    /// Takes one line byte; `false` when it cannot yet (a line is held, or fewer than
    /// [`REPLY_ROOM`] TX bytes are free): keep the byte and offer it again after a `poll`.
    #[must_use]
    pub fn byte(&mut self, b: u8, out: &mut impl Out) -> bool {
        if self.busy() || self.resync || out.room() < REPLY_ROOM {
            return false;
        }
        match self.lines.push(b) {
            LineEvent::More => {}
            LineEvent::Bad(e) => put_error(out, e),
            LineEvent::Line(n) => {
                let mut line = [0u8; LINE_LEN];
                line[..n].copy_from_slice(self.lines.line());
                let r = match line.first() {
                    _ if n == 0 => Ok(()),
                    Some(b'$') => self.system(&line[1..n], out),
                    _ if self.alarm => Err(Error::AlarmLock),
                    _ => self.gcode(&line[..n], out),
                };
                match r {
                    Err(e) => put_error(out, e),
                    Ok(()) if self.job.is_none() => put_ok(out),
                    Ok(()) => {}
                }
            }
        }
        true
    }

    /// `?` arrived: a status report goes out at the next `poll`.
    pub fn status_request(&mut self) {
        self.status_wanted = true;
    }

    /// Ctrl-X: stop at once, drop queued moves and any partial or held line, reset the modal
    /// state, take the engine's position, print the banner. During motion this is ALARM:3
    /// (positions stay exact, but Grbl asks for `$X`).
    pub fn soft_reset(&mut self, out: &mut impl Out) {
        let moving = self.feeder.pending() > 0 || self.shared.state() != State::Idle;
        self.feeder.abort();
        self.shared.set_hold(false);
        self.lines.clear();
        self.job = None;
        self.modal = Modal::RESET;
        self.pushed = self.shared.moves_done();
        // The engine stops at its next tick; its position is final only then (see `poll`).
        self.resync = true;
        self.take_position();
        if moving {
            self.alarm = true;
            out.put(report::ALARM_RESET);
        }
        self.welcome(out);
    }

    /// Timekeeping and retries: rebuilds a pending profile, enables/disables the drivers,
    /// carries on a held line (printing its `ok`), writes a requested status report.
    pub fn poll(&mut self, now_ms: u32, out: &mut impl Out) -> Actions {
        self.now = now_ms;
        self.take_position();
        if self.profile_dirty {
            self.apply_profile();
        }
        self.feeder.service();
        self.drive_enable();
        if self.job.is_some() && out.room() >= POLL_REPLY_ROOM && self.advance(true, out) {
            put_ok(out);
        }
        if self.status_wanted && out.room() >= report::status_len(N) {
            self.status_wanted = false;
            self.status(out);
        }
        let pulse = core::mem::take(&mut self.pulse_changed).then(|| self.settings.timing().pulse_ticks);
        Actions {
            enable: self.drivers_on,
            enable_pin_high: self.drivers_on == self.settings.enable_invert,
            pulse_ticks: pulse,
            save: core::mem::take(&mut self.save),
            restart: core::mem::take(&mut self.restart),
        }
    }

    /// After a soft reset: once the engine has stopped, its position is the planner's.
    fn take_position(&mut self) {
        if self.resync && self.shared.state() == State::Idle {
            self.planner.sync(self.shared.positions(), &self.limits);
            self.resync = false;
        }
    }

    /// Queue empty and engine idle (not held): G4, G92, `$` settings may act.
    fn drained(&self) -> bool {
        self.feeder.pending() == 0 && self.shared.state() == State::Idle
    }

    /// Rebuilds the ramp table and timing if the engine is parked; otherwise asks it to park.
    fn apply_profile(&mut self) {
        let Some(mut guard) = self.slot.try_write() else {
            self.profile_dirty = true;
            return;
        };
        self.ramped = self.settings.build_profile(N, &mut guard);
        drop(guard);
        self.limits = Limits::new(&self.settings, self.ramped.cfg.vmax);
        self.profile_dirty = false;
        self.pulse_changed = true;
    }

    /// Drivers: on for motion (and M17), off `$1` ms after the machine goes idle.
    fn drive_enable(&mut self) {
        if !self.drivers_on {
            self.enabled_at = None;
            return;
        }
        self.enabled_at.get_or_insert(self.now);
        let waiting = self.job.is_some_and(|j| j.mv.is_some());
        let keep = self.m17 || self.settings.idle_delay_ms == 255;
        if keep || waiting || !self.drained() {
            self.idle_since = None;
            return;
        }
        let since = *self.idle_since.get_or_insert(self.now);
        if self.now.wrapping_sub(since) >= self.settings.idle_delay_ms as u32 {
            self.drivers_on = false;
            self.enabled_at = None;
            self.idle_since = None;
        }
    }

    fn drivers_ready(&self) -> bool {
        self.drivers_on && self.enabled_at.is_some_and(|t| self.now.wrapping_sub(t) >= ENABLE_SETTLE_MS)
    }

    /// Carries the job on as far as it can; true when it just finished.
    fn advance(&mut self, in_poll: bool, out: &mut impl Out) -> bool {
        let Some(mut job) = self.job else { return false };
        let done = 'run: {
            if job.save {
                if !in_poll {
                    break 'run false;
                }
                self.save = true;
                job.save = false;
            }
            if let Some(l) = job.listing {
                job.listing = self.list(l, out);
                if job.listing.is_some() {
                    break 'run false;
                }
            }
            if let Some(ms) = job.dwell_ms {
                // The dwell starts at a poll (its clock) once the queue has run out.
                if !self.drained() || (job.dwell_end.is_none() && !in_poll) {
                    break 'run false;
                }
                let end = *job.dwell_end.get_or_insert(self.now.wrapping_add(ms));
                if (self.now.wrapping_sub(end) as i32) < 0 {
                    break 'run false;
                }
                job.dwell_ms = None;
            }
            if let Some(steps) = job.set_steps {
                if !self.drained() {
                    break 'run false;
                }
                self.feeder.set_positions(steps);
                job.set_steps = None;
            }
            if let Some(pl) = job.mv {
                if !self.drivers_ready() {
                    self.drivers_on = true;
                    break 'run false;
                }
                if self.profile_dirty || self.feeder.push(pl.mv).is_err() {
                    break 'run false;
                }
                self.feed_ring[self.pushed as usize % FEED_RING] = pl.mm_per_step;
                self.pushed = self.pushed.wrapping_add(1);
                self.idle_since = None;
                job.mv = None;
            }
            if job.drivers_off || job.pause || job.end {
                if !self.drained() {
                    break 'run false;
                }
                if job.drivers_off {
                    self.drivers_on = false;
                    self.m17 = false;
                }
                if job.pause {
                    self.shared.set_hold(true);
                }
                if job.end {
                    out.put(report::PROGRAM_END);
                }
            }
            true
        };
        self.job = if done { None } else { Some(job) };
        done
    }

    /// Starts a job and carries it as far as it goes now.
    fn start(&mut self, job: Job<N>, out: &mut impl Out) {
        self.job = Some(job);
        self.advance(false, out);
    }

    /// A G-code line: checked in full, then committed and started.
    fn gcode(&mut self, line: &[u8], out: &mut impl Out) -> Result<(), Error> {
        let block = gcode::parse::<N>(line)?;
        let (modal, fx) = self.modal.interpret(&block, self.planner.position_mm())?;
        let mut planner = self.planner;
        let ovr = self.shared.overrides();
        self.limits.feed_ovr = ovr.feed as f64 / 100.0;
        self.limits.rapid_ovr = ovr.rapid as f64 / 100.0;
        let set_steps = match fx.set_position {
            Some(set) => Some(planner.set_position(&set, &self.limits)?),
            None => None,
        };
        let mv = match fx.motion {
            Some((target, rapid)) => planner.line(&target, (!rapid).then_some(modal.feed), &self.limits)?,
            None => None,
        };
        self.modal = modal;
        self.planner = planner;
        if fx.drivers == Some(true) {
            self.drivers_on = true;
            self.m17 = true;
        }
        let job = Job {
            dwell_ms: fx.dwell_ms,
            set_steps,
            mv,
            drivers_off: fx.drivers == Some(false),
            pause: fx.stop == Some(Stop::Pause),
            end: fx.stop == Some(Stop::End),
            ..Job::NONE
        };
        self.start(job, out);
        Ok(())
    }

    /// `<State|MPos:…|FS:feed,0>`: feed from the master rate and the running move's mm/step.
    fn status(&self, out: &mut impl Out) {
        let state: &[u8] = match self.shared.state() {
            _ if self.alarm => b"Alarm",
            State::Run => b"Run",
            State::Holding => b"Hold:1",
            State::Held => b"Hold:0",
            State::Idle if self.feeder.pending() > 0 => b"Run",
            State::Idle => b"Idle",
        };
        let pos = self.shared.positions();
        let mpos: [f64; N] = core::array::from_fn(|i| pos[i] as f64 / self.limits.steps_per_mm[i]);
        let rate = self.shared.rate_hz() as f64;
        let per_step = self.feed_ring[self.shared.moves_done() as usize % FEED_RING] as f64;
        report::status(out, state, &mpos, rate * per_step * 60.0);
    }
}
