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
//!
//! This file holds the controller's state (the struct, the types of its fields, its in-place
//! construction); each mechanism is a file of its own that works on it: `lines.rs` (bytes and
//! lines in, jobs out), `poll.rs` (carrying jobs on, drivers, profile), `reset.rs` (banner, Ctrl-X,
//! the chip check),
//! `access.rs` (what the shell reads and sets), and `door.rs`, `homing.rs`, `jogging.rs`, `probe.rs`,
//! `soft_limits.rs`, `status.rs`, `system.rs` (`$` commands), `tool.rs` (spindle, coolant),
//! `encoder.rs` (step-loss checks). They name this file's items; this file names none of theirs.

mod access;
mod door;
mod homing;
mod lines;
mod poll;
mod reset;
mod encoder;
mod jogging;
mod probe;
mod soft_limits;
mod status;
mod system;
mod tool;

use crate::planning::arc::Segments;
use crate::grbl::coords::Offsets;
use crate::grbl::gcode::Modal;
use crate::planning::planner::{Limits, Planned, Planner};
use crate::grbl::protocol::{LineBuf, RX_BUFFER_LEN};
use crate::motion::moves::Overrides;
use crate::motion::shared::Shared;
use crate::planning::feeder::Feeder;
use crate::motion::ramp::RampSlot;
use crate::grbl::settings::{Ramped, Settings};
use crate::grbl::spindle::{Power, PwmTiming, SpindleDir, SpindleOut};
use crate::grbl::store::{Stored, STARTUP_LINES};

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
    /// `$2`, `$3`, `$580`, `$581` (or `$RST`) changed the pin map or the step output's mode:
    /// rebuild the step output at rest (`Engine::rebuild`; the controller is at rest until the
    /// next poll).
    pub reinit: bool,
    /// A Ctrl-X was taken in this pass (set by `shell::idle_step`; after a hard limit the
    /// shell rebuilds the step output on it).
    pub reset: bool,
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
    /// `$I`'s chip and step-interrupt lines, after its build info.
    Info,
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
    /// from flash whole, payloads of its `None`s included. Inlined into `new_job`, which
    /// writes its fields into the slot: called, it is built aside and copied in whole.)
    #[inline(always)]
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

/// Where a soft-limit trip stands (`soft_limits.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SoftLimit {
    Off,
    /// Tripped: holding until the engine has stopped, then this alarm is reported.
    Stopping(u8),
    /// ALARM:2 reported: waiting for Ctrl-X.
    Locked,
}

/// Where the door cycle is (`door.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Door {
    /// No door state.
    Off,
    /// Opened: motion decelerating to a stop (`Door:2`).
    Stopping,
    /// Stopped with spindle and coolant off, the door still open (`Door:1`).
    Ajar,
    /// Stopped, the door closed: waiting for `~` (`Door:0`).
    Ready,
    /// `~` came: spindle and coolant back on, motion resumes at this poll time (`Door:3`).
    Restoring(u32),
}

/// One `$H` cycle in progress (`homing.rs`) (kept small: the controller lives in a static slot).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Homing {
    /// Axes of the group being homed (bit i = axis i).
    group: u8,
    /// The group after this one (X and Y after Z for `$H`), 0 for none.
    next: u8,
    /// 0 seek, 1 pull-off, 2 locate, 3 pull-off.
    pass: u8,
    /// Approach passes: axes whose switch closed.
    found: u8,
    /// A move of this pass was queued; `moving`: it has not been seen to end yet.
    moved: bool,
    moving: bool,
    /// `$H` (startup lines follow), not `$HX`…
    all: bool,
    /// The stop epoch the pass's move was queued in: a newer one means it was stopped.
    epoch: u32,
    /// The pass may start (after the debounce pause), poll ms.
    start_at: u32,
    /// The pass's target of each axis, steps.
    target: [i32; 3],
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
    reinit: bool,
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
    homing: Option<Homing>,
    /// The safety door cycle (see `door.rs`), its input now, and a 0x84 waiting.
    door: Door,
    door_pin: bool,
    door_event: bool,
    /// The part's device registers, once the shell has read them (`reset.rs`, `$I`).
    chip: Option<crate::grbl::chip::Chip>,
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
        // The two rings are written as zero bytes: `f32` 0.0, and `Power`'s derived default
        // (0.0, false, 0.0), valid values.
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
            addr_of_mut!((*p).reinit).write(false);
            addr_of_mut!((*p).pulse_changed).write(true);
            addr_of_mut!((*p).pushed).write(shared.moves_done());
            // (Zeroed: one memclr each, where the arrays would be built on the stack and
            // copied in.)
            addr_of_mut!((*p).feed_ring).write_bytes(0, 1);
            addr_of_mut!((*p).startup_next).write(0);
            addr_of_mut!((*p).wco_count).write(0);
            addr_of_mut!((*p).ovr_count).write(0);
            addr_of_mut!((*p).ov_seen).write(Overrides::NONE);
            addr_of_mut!((*p).rx_free).write(RX_BUFFER_LEN as u32);
            addr_of_mut!((*p).power_ring).write_bytes(0, 1);
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
            addr_of_mut!((*p).door).write(Door::Off);
            addr_of_mut!((*p).door_pin).write(false);
            addr_of_mut!((*p).door_event).write(false);
            addr_of_mut!((*p).chip).write(None);
            at.assume_init_mut()
        };
        c.startup_next = c.next_startup(0);
        c.enc_configure();
        c.apply_profile();
        c.sync_planner();
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
            enabled_at: _, idle_since: _, save: _, reinit: _, pulse_changed: _, pushed: _,
            feed_ring: _, startup_next: _, wco_count: _, ovr_count: _, ov_seen: _, rx_free: _,
            power_ring: _, tool: _, pwm_hz: _, reset_after: _, resync: _, soft_limit: _,
            watchdog_note: _, limit_pins: _, enc: _, probe_pin: _, homing: _, door: _,
            door_pin: _, door_event: _, chip: _,
        } = c;
    }

    /// The first non-empty startup line from `i` (`STARTUP_LINES`: none).
    fn next_startup(&self, i: usize) -> usize {
        (i..STARTUP_LINES).find(|&k| !self.stored.startup[k].as_bytes().is_empty()).unwrap_or(STARTUP_LINES)
    }
}
