//! The Grbl 1.1 front end: line bytes in, replies out, moves into the queue.
//!
//! Who uses it: the firmware's serial task. The RX interrupt sorts bytes with
//! [`crate::grbl::protocol::realtime`]: `!`/`~` go straight to `Shared::set_hold`, `?` to
//! [`Controller::status_request`], 0x85 to [`Controller::jog_cancel`], Ctrl-X to
//! [`Controller::soft_reset`] (the shell also empties its RX ring), the rest into an RX ring of
//! at least 128 bytes. The task feeds that ring to [`Controller::byte`] while it returns
//! `true`, and calls [`Controller::poll`] at least every millisecond or two (also when no byte
//! arrives) and applies the [`Actions`] it returns.
//!
//! Every line becomes a job carried out in Grbl's order — listing, dwell, motion, then
//! M18/M0/M2 — and gets its `ok` only when the job is done: a motion line whose move does not
//! fit in the queue is held (and `byte` takes nothing more) until a later `poll` pushes it, so a
//! character-counting sender never overruns us and nothing accepted is lost. G4, M0, M2, M18
//! and writes to flash wait until the queue has run out and the engine is idle.
//!
//! Positions: the planner works in machine millimetres; work offsets ([`Offsets`]) turn
//! program coordinates into machine ones in the interpreter, and reports subtract them again.

mod door;
mod homing;
mod encoder;
mod jogging;
mod probe;
mod soft_limits;
mod status;
mod system;
mod tool;

use crate::planning::arc::Segments;
use crate::grbl::coords::Offsets;
use crate::grbl::gcode::{self, Modal, Stop};
use crate::planning::inverse_time;
use crate::planning::planner::{Limits, Planned, Planner};
use crate::error::Error;
use crate::grbl::protocol::{put_error, put_ok, LineBuf, LineEvent, Out, LINE_LEN, REPLY_ROOM, RX_BUFFER_LEN};
use crate::motion::queue::{Feeder, Overrides, Shared, State};
use crate::motion::ramp::{RampConfig, RampSlot};
use crate::num::wrapping_diff;
use crate::grbl::report;
use crate::grbl::settings::{Ramped, Settings};
use crate::grbl::spindle::{Power, PwmTiming, SpindleDir, SpindleOut};
use crate::grbl::store::{Stored, IMAGE_LEN, STARTUP_LINES};
use soft_limits::SoftLimit;

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
    /// The persistent image changed: write [`Controller::image`] to flash (only ever asked
    /// while the machine is idle: the flash write stalls the CPU).
    pub save: bool,
    /// `$2`/`$3` (or `$RST`) changed the pin map, which the engine takes at boot: save, then
    /// reset the MCU.
    pub restart: bool,
    /// Spindle/laser PWM compare value and the spindle and coolant pins, every poll.
    pub spindle: SpindleOut,
    /// New spindle PWM timing for TIM1 (at the first poll and after `$33` changes).
    pub pwm: Option<PwmTiming>,
}

/// A long reply written a line at a time as TX room appears.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Listing {
    Settings(u8),
    Params(u8),
}

/// Jogging, as the status report and 0x85 see it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Jogging {
    Off,
    /// Jog moves queued or running.
    On,
    /// Cancelled: decelerating with a feed hold, then the queue is flushed.
    Cancel,
    /// Flushed: the engine takes the stop at its next tick (≤ 0.5 ms while held); still
    /// jogging until it is idle, so no report says `Hold:0` in between.
    Stopping,
}

/// How fast a straight move (or an arc's chord) runs.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Rate {
    /// G0: the axes' max rates.
    Rapid,
    /// G94: path feed, mm/min.
    Feed(f32),
    /// G93: the move's time, minutes.
    Minutes(f32),
}

/// One accepted line still being carried out; each stage is cleared when done.
#[derive(Clone, Copy, Debug)]
struct Job<const N: usize> {
    listing: Option<Listing>,
    dwell_ms: Option<u32>,
    dwell_end: Option<u32>,
    mv: Option<Planned<N>>,
    /// G28/G30: the move to the stored position after the intermediate one.
    mv2: Option<Planned<N>>,
    /// The moves are a jog.
    jog: bool,
    /// `$H`: done when the homing cycle ends.
    home: bool,
    /// G2/G3: chord ends still to plan, at `rate` each.
    arc: Option<Segments<N>>,
    rate: Rate,
    /// M3/M4/M5, S, M7/M8/M9 to apply once the queue has run out (before the motion).
    tool: Option<(SpindleDir, f32, u8)>,
    /// Laser mode: the power the block's moves carry (none for jogs).
    power: Power,
    drivers_off: bool,
    pause: bool,
    end: bool,
    /// Write the persistent image (once the machine is idle) before the `ok`.
    save: bool,
    /// G38.2–G38.5: the probe cycle (see `probe.rs`), 0 for none.
    probe: u8,
}

impl<const N: usize> Job<N> {
    /// Only a planned move is left before anything else can happen: it waits for queue room.
    fn waits_for_room(&self) -> bool {
        (self.mv.is_some() || self.mv2.is_some())
            && !self.home
            && self.listing.is_none()
            && self.tool.is_none()
            && self.dwell_ms.is_none()
            && !self.save
            && self.probe == 0
    }

    /// Nothing to do. (A function, not a constant: a constant of this size would be copied
    /// from flash whole, payloads of its `None`s included.)
    #[inline(never)]
    fn none() -> Self {
        Job {
            listing: None,
            dwell_ms: None,
            dwell_end: None,
            mv: None,
            mv2: None,
            jog: false,
            home: false,
            arc: None,
            rate: Rate::Rapid,
            tool: None,
            power: Power { speed: 0.0, dynamic: false, cruise_hz: 0.0 },
            drivers_off: false,
            pause: false,
            end: false,
            save: false,
            probe: 0,
        }
    }
}

/// The Grbl-compatible controller for up to `N` axes (`$42` of them in use).
pub struct Controller<'a, const N: usize> {
    feeder: Feeder<'a, N>,
    shared: &'a Shared<N>,
    slot: &'a RampSlot,
    settings: Settings,
    stored: Stored,
    axes: usize,
    ramped: Ramped,
    limits: Limits<N>,
    profile_dirty: bool,
    lines: LineBuf,
    modal: Modal,
    offsets: Offsets<N>,
    planner: Planner<N>,
    job: Option<Job<N>>,
    alarm: bool,
    check: bool,
    sleep: bool,
    jog: Jogging,
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
    /// Next `$N` startup line to run (`STARTUP_LINES`: none left).
    startup_next: usize,
    /// Status reports until `WCO:` / `Ov:` are due again (Grbl's refresh counters).
    wco_count: u8,
    ovr_count: u8,
    ov_seen: Overrides,
    rx_free: u32,
    /// Laser power of each move in the queue (laser mode), indexed like `feed_ring`.
    power_ring: [Power; FEED_RING],
    /// Spindle direction and speed, and coolant, in force.
    tool: (SpindleDir, f32, u8),
    /// `$33` last handed to the shell (0: none yet).
    pwm_hz: u32,
    /// `$C` off, `$RST`: a soft reset follows the line's `ok`.
    reset_after: bool,
    /// After a soft reset: take the engine's position once it has stopped.
    resync: bool,
    /// A soft-limit trip in progress (see `soft_limits.rs`).
    soft_limit: SoftLimit,
    /// The MCU was reset by the watchdog: say so after the next banner.
    watchdog_note: bool,
    /// Limit pins active (bit i = axis i), for `Pn:` and homing.
    limit_pins: u8,
    /// Encoder feedback's step-loss check (see `encoder.rs`).
    enc: crate::encoder::loss::Monitor,
    /// The probe input is active (`$6` applied).
    probe_pin: bool,
    /// A `$H` cycle in progress (see `homing.rs`).
    homing: Option<homing::Homing>,
    /// The safety door cycle (see `door.rs`), its input now, and a 0x84 waiting.
    door: door::Door,
    door_pin: bool,
    door_event: bool,
}

impl<'a, const N: usize> Controller<'a, N> {
    /// A controller at the engine's current position with the stored settings, coordinates
    /// and startup lines (a `Settings` converts, with none of the others); builds the profile
    /// (or does so at the first `poll` the engine is parked for). Startup lines run at the
    /// first polls.
    pub fn new(feeder: Feeder<'a, N>, shared: &'a Shared<N>, slot: &'a RampSlot, stored: impl Into<Stored>) -> Self {
        let mut c = core::mem::MaybeUninit::uninit();
        Self::init(&mut c, feeder, shared, slot, stored.into());
        // SAFETY: `init` wrote every field.
        unsafe { c.assume_init() }
    }

    /// [`Self::new`] built in place (the firmware's static slot): the stack holds no copy of
    /// the controller, which would not fit beside the statics. Each field is written where it
    /// lives (a struct literal is built on the stack and copied in part by part).
    #[inline(never)]
    pub fn init<'s>(
        at: &'s mut core::mem::MaybeUninit<Self>,
        feeder: Feeder<'a, N>,
        shared: &'a Shared<N>,
        slot: &'a RampSlot,
        mut stored: Stored,
    ) -> &'s mut Self {
        use core::ptr::addr_of_mut;
        // A store written for more axes than this build drives shows this build's count.
        stored.settings.axes = stored.settings.axes.min(N as u8);
        let settings = stored.settings;
        let axes = settings.axis_count(N);
        let p = at.as_mut_ptr();
        // SAFETY: `p` is valid for writes; every field is written once below (the list is
        // the struct's, checked by `Self::fields`) before the slot is used as initialised.
        let c = unsafe {
            addr_of_mut!((*p).feeder).write(feeder);
            addr_of_mut!((*p).shared).write(shared);
            addr_of_mut!((*p).slot).write(slot);
            addr_of_mut!((*p).settings).write(settings);
            addr_of_mut!((*p).offsets).write(Offsets::new(stored.coords));
            addr_of_mut!((*p).stored).write(stored);
            addr_of_mut!((*p).axes).write(axes);
            addr_of_mut!((*p).ramped).write(Ramped::wanted(&settings, axes));
            addr_of_mut!((*p).limits).write(settings.planner_limits(1));
            addr_of_mut!((*p).profile_dirty).write(true);
            addr_of_mut!((*p).lines).write(LineBuf::new());
            addr_of_mut!((*p).modal).write(Modal::RESET);
            addr_of_mut!((*p).planner).write(Planner::new());
            addr_of_mut!((*p).job).write(None);
            // Grbl's homing lock: with homing enabled, power-up is in the alarm state.
            addr_of_mut!((*p).alarm).write(settings.homing);
            addr_of_mut!((*p).check).write(false);
            addr_of_mut!((*p).sleep).write(false);
            addr_of_mut!((*p).jog).write(Jogging::Off);
            addr_of_mut!((*p).status_wanted).write(false);
            addr_of_mut!((*p).now).write(0);
            addr_of_mut!((*p).drivers_on).write(settings.idle_delay_ms == 255);
            addr_of_mut!((*p).m17).write(false);
            addr_of_mut!((*p).enabled_at).write(None);
            addr_of_mut!((*p).idle_since).write(None);
            addr_of_mut!((*p).save).write(false);
            addr_of_mut!((*p).restart).write(false);
            addr_of_mut!((*p).pulse_changed).write(true);
            addr_of_mut!((*p).pushed).write(shared.moves_done());
            addr_of_mut!((*p).feed_ring).write([0.0; FEED_RING]);
            addr_of_mut!((*p).startup_next).write(0);
            addr_of_mut!((*p).wco_count).write(0);
            addr_of_mut!((*p).ovr_count).write(0);
            addr_of_mut!((*p).ov_seen).write(Overrides::NONE);
            addr_of_mut!((*p).rx_free).write(RX_BUFFER_LEN as u32);
            addr_of_mut!((*p).power_ring).write([Power::default(); FEED_RING]);
            addr_of_mut!((*p).tool).write((SpindleDir::Off, 0.0, 0));
            addr_of_mut!((*p).pwm_hz).write(0);
            addr_of_mut!((*p).reset_after).write(false);
            addr_of_mut!((*p).resync).write(false);
            addr_of_mut!((*p).soft_limit).write(SoftLimit::Off);
            addr_of_mut!((*p).watchdog_note).write(false);
            addr_of_mut!((*p).limit_pins).write(0);
            addr_of_mut!((*p).probe_pin).write(false);
            addr_of_mut!((*p).enc).write(crate::encoder::loss::Monitor::OFF);
            addr_of_mut!((*p).homing).write(None);
            addr_of_mut!((*p).door).write(door::Door::Off);
            addr_of_mut!((*p).door_pin).write(false);
            addr_of_mut!((*p).door_event).write(false);
            at.assume_init_mut()
        };
        c.startup_next = c.next_startup(0);
        c.enc_configure();
        c.apply_profile();
        c.planner.sync(shared.positions(), &c.limits);
        c
    }

    /// Compile-time check that [`Self::init`] writes every field: adding a field to the
    /// struct without listing it here (and there) fails to build.
    #[allow(dead_code)]
    fn fields(c: Self) {
        let Controller {
            feeder: _, shared: _, slot: _, settings: _, stored: _, axes: _, ramped: _, limits: _,
            profile_dirty: _, lines: _, modal: _, offsets: _, planner: _, job: _, alarm: _,
            check: _, sleep: _, jog: _, status_wanted: _, now: _, drivers_on: _, m17: _,
            enabled_at: _, idle_since: _, save: _, restart: _, pulse_changed: _, pushed: _,
            feed_ring: _, startup_next: _, wco_count: _, ovr_count: _, ov_seen: _, rx_free: _,
            power_ring: _, tool: _, pwm_hz: _, reset_after: _, resync: _, soft_limit: _,
            watchdog_note: _, limit_pins: _, enc: _, probe_pin: _, homing: _, door: _,
            door_pin: _, door_event: _,
        } = c;
    }

    /// The first non-empty startup line from `i` (`STARTUP_LINES`: none).
    fn next_startup(&self, i: usize) -> usize {
        (i..STARTUP_LINES).find(|&k| !self.stored.startup[k].as_bytes().is_empty()).unwrap_or(STARTUP_LINES)
    }

    /// The settings in force.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// What flash should hold (after [`Actions::save`]).
    pub fn stored(&self) -> &Stored {
        &self.stored
    }

    /// The flash image of [`Self::stored`].
    pub fn image(&self) -> [u8; IMAGE_LEN] {
        self.stored.to_bytes()
    }

    /// The ramp the profile was built with (what `$I` reports).
    pub fn ramped(&self) -> &Ramped {
        &self.ramped
    }

    /// Axes in use (`$42`, at most `N`).
    pub fn axes(&self) -> usize {
        self.axes
    }

    /// The work offsets in force.
    pub fn offsets(&self) -> &Offsets<N> {
        &self.offsets
    }

    /// The G-code modal state.
    pub fn modal(&self) -> &Modal {
        &self.modal
    }

    /// Moves queued or running.
    pub fn pending_moves(&self) -> u32 {
        self.feeder.pending()
    }

    /// The planner's absolute step position: where the engine ends once the queue runs out.
    pub fn planned_steps(&self) -> [i64; N] {
        *self.planner.position_steps()
    }

    /// True while a line (or a startup line) is being carried out: [`Self::byte`] takes
    /// nothing until it is done (nor while asleep).
    pub fn busy(&self) -> bool {
        self.job.is_some() || self.startup_next < STARTUP_LINES || self.tripped()
    }

    /// Free bytes in the shell's RX ring, for `Bf:` in status reports (at most the announced
    /// RX buffer size).
    pub fn set_rx_free(&mut self, n: usize) {
        self.rx_free = n.min(RX_BUFFER_LEN) as u32;
    }

    /// The limit inputs as the shell read them (GPIOA's input register), for `Pn:` in status
    /// reports; `$5` applies here.
    pub fn set_limit_inputs(&mut self, gpioa_idr: u32) {
        self.limit_pins = crate::grbl::limits::active_pins(gpioa_idr, self.settings.limit_invert);
    }

    /// The start-up banner (also after a soft reset).
    pub fn welcome(&mut self, out: &mut impl Out) {
        out.put(report::BANNER);
        if core::mem::take(&mut self.watchdog_note) {
            out.put(report::WATCHDOG_RESET);
        }
        if self.alarm {
            out.put(report::UNLOCK_HINT);
        }
    }

    /// The MCU came up from a watchdog reset (call before [`Self::welcome`]): the banner is
    /// followed by `[MSG:Reset by watchdog]`, and the controller is in the alarm state (the
    /// position is not known to be right; no startup lines run).
    pub fn watchdog_reset(&mut self) {
        self.watchdog_note = true;
        self.position_lost();
    }

    /// The position is not known to be right (a hard limit stopped the steps mid-move, or the
    /// watchdog reset the MCU): the alarm state, and no startup lines (call before
    /// [`Self::welcome`]).
    pub fn position_lost(&mut self) {
        self.alarm = true;
        self.startup_next = STARTUP_LINES;
    }

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
                let mut line = [0u8; LINE_LEN];
                line[..n].copy_from_slice(self.lines.line());
                let r = match line.first() {
                    _ if n == 0 => Ok(()),
                    Some(b'$') => self.system(&line[1..n], out),
                    // G-code is locked out in alarm, and while jogging (Grbl's error:9).
                    _ if self.alarm || self.jogging() => Err(Error::AlarmLock),
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

    /// `?` arrived: a status report goes out at the next `poll`.
    pub fn status_request(&mut self) {
        self.status_wanted = true;
    }

    /// Ctrl-X: stop at once, drop queued moves and any partial or held line, reset the modal
    /// state, G92 and the tool length offset, take the engine's position, print the banner.
    /// During motion this is ALARM:3 (positions stay exact, but Grbl asks for `$X`); from idle
    /// or a completed feed hold (`Hold:0`) it is not. Startup lines run again (not in alarm).
    pub fn soft_reset(&mut self, out: &mut impl Out) {
        let state = self.shared.state();
        let moving = state != State::Held && (self.feeder.pending() > 0 || state != State::Idle);
        self.feeder.abort();
        self.shared.set_hold(false);
        self.shared.set_overrides(Overrides::NONE);
        self.lines.clear();
        self.job = None;
        self.modal = Modal::RESET;
        // A probe cycle ends (its edge must not stop a later move); Grbl keeps the last probe
        // position, not its success flag.
        self.shared.probe_disarm();
        let prb = self.offsets.prb;
        self.offsets = Offsets::new(self.stored.coords);
        self.offsets.prb = prb;
        self.jog = Jogging::Off;
        self.check = false;
        self.soft_limit = SoftLimit::Off;
        self.door = door::Door::Off;
        self.door_event = false;
        self.pushed = self.shared.moves_done();
        // The engine stops at its next tick; its position is final only then (see `poll`).
        self.resync = true;
        self.take_position();
        self.wco_count = 0;
        self.ovr_count = 0;
        if self.homing.take().is_some() {
            // Grbl's ALARM:6: reset during the homing cycle.
            self.alarm = true;
            report::alarm(out, report::ALARM_HOMING_RESET);
        } else if moving {
            self.alarm = true;
            report::alarm(out, report::ALARM_RESET);
        }
        // Grbl wakes from `$SLP` into the alarm state.
        self.alarm |= core::mem::take(&mut self.sleep);
        self.startup_next = if self.alarm { STARTUP_LINES } else { self.next_startup(0) };
        self.welcome(out);
    }

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
            restart: core::mem::take(&mut self.restart),
        }
    }

    /// A line's `ok`, and the reset `$C`/`$RST` asked to follow it.
    fn ok(&mut self, out: &mut impl Out) {
        if self.tripped() {
            return; // a soft-limit trip: the line gets no reply (Grbl)
        }
        put_ok(out);
        if core::mem::take(&mut self.reset_after) {
            self.soft_reset(out);
        }
    }

    /// After a soft reset: once the engine has stopped, its position is the planner's.
    fn take_position(&mut self) {
        if self.resync && self.shared.state() == State::Idle {
            self.planner.sync(self.shared.positions(), &self.limits);
            self.resync = false;
        }
    }

    /// Queue empty and engine idle (not held): G4, flash writes, `$` settings may act.
    fn drained(&self) -> bool {
        self.feeder.pending() == 0 && self.shared.state() == State::Idle
    }

    /// Runs the `$N` lines, one job at a time (`>line:ok`, as Grbl reports them).
    fn run_startup(&mut self, out: &mut impl Out) {
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

    /// Rebuilds the ramp table and timing if the engine is parked; otherwise asks it to park.
    fn apply_profile(&mut self) {
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
    fn drive_enable(&mut self) {
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

    fn drivers_ready(&self) -> bool {
        self.drivers_on && self.enabled_at.is_some_and(|t| self.now.wrapping_sub(t) >= ENABLE_SETTLE_MS)
    }

    /// Pushes one planned move; false while it does not fit (or the drivers are settling).
    fn push(&mut self, pl: Planned<N>, jog: bool, power: Power) -> bool {
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
    fn advance(&mut self, in_poll: bool, out: &mut impl Out) -> bool {
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
                if let Some(pl) = *slot {
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
                job.mv = plan(&mut self.planner, &p, job.rate, &self.limits, &self.ramped.cfg).unwrap_or(None);
                if let Some(pl) = job.mv {
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
        self.job = if done { None } else { Some(job) };
        done
    }

    /// Starts a job and carries it as far as it goes now.
    fn start(&mut self, job: Job<N>, out: &mut impl Out) {
        self.job = Some(job);
        self.advance(false, out);
    }

    /// Marks the line being carried out (or a new job) to write the persistent image.
    fn save_later(&mut self, out: &mut impl Out) {
        match &mut self.job {
            Some(j) => j.save = true,
            None => {
                let mut job = Job::none();
                job.save = true;
                self.start(job, out);
            }
        }
    }

    /// A G-code line: checked in full, then committed and started. In check mode (`$C`) the
    /// state and position follow the line, but nothing moves, waits or is stored.
    fn gcode(&mut self, line: &[u8], out: &mut impl Out) -> Result<(), Error> {
        let block = gcode::parse::<N>(line)?;
        if block.axes.get(self.axes..).unwrap_or_default().iter().any(Option::is_some) {
            return Err(Error::UnsupportedCommand);
        }
        let mut fx = gcode::Effects::none();
        let modal = self.modal.interpret_into(&block, self.planner.position_mm(), &self.offsets, &mut fx)?;
        let mut planner = self.planner;
        // G93: F is 1/minutes (checked positive where a motion needs it).
        let rate = if modal.inverse_time { Rate::Minutes(1.0 / modal.feed) } else { Rate::Feed(modal.feed) };
        let cfg = self.ramped.cfg;
        let lim = &self.limits;
        let mv = match &fx.motion {
            Some((t, rapid)) => plan(&mut planner, t, if *rapid { Rate::Rapid } else { rate }, lim, &cfg)?,
            None => None,
        };
        let mv2 = match &fx.home {
            Some(t) => planner.line(t, None, lim)?,
            None => None,
        };
        let (arc, rate) = match &fx.arc {
            Some(a) => {
                a.check_range(&self.limits.steps_per_mm)?;
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
        // Soft limits: every target this line moves to, arc chord ends included (a chord
        // between two points in the box stays in it).
        let arc_out = arc.is_some_and(|mut seg| seg.any(|p| self.beyond_travel(&p)));
        let home_out = fx.home.as_ref().is_some_and(|t| self.beyond_travel(t));
        if arc_out || home_out || fx.motion.as_ref().is_some_and(|(t, _)| self.beyond_travel(t)) {
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
        self.planner = planner;
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
        let job = self.job.insert(Job::none());
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

/// Plans one straight move at `rate`. G93: the move starts and ends at rest (junction speed 0
/// on both sides) and its master steps decide the cruise rate that makes it last its time on
/// the ramp the engine will walk for it ([`inverse_time::cruise_hz`]), given to the planner as
/// the equivalent feed, so its axis-rate clamps apply as to any feed.
fn plan<const N: usize>(
    planner: &mut Planner<N>,
    target: &[f32; N],
    rate: Rate,
    lim: &Limits<N>,
    cfg: &RampConfig,
) -> Result<Option<Planned<N>>, Error> {
    let feed = match rate {
        Rate::Rapid => return planner.line(target, None, lim),
        Rate::Feed(f) => f,
        Rate::Minutes(t) => {
            // At 1 mm/min no axis limit binds: the planner's rate is exactly master / (len·60).
            let mut dry = *planner;
            let feed = match dry.line(target, Some(1.0), lim)? {
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
            // From rest to rest: no junction speed on either side.
            planner.rest();
            let planned = planner.line(target, Some(feed), lim);
            planner.rest();
            return planned;
        }
    };
    planner.line(target, Some(feed), lim)
}
