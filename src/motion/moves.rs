//! Moves as the planner hands them over: signed steps per axis, the master's cruise, and
//! what the look-ahead and the overrides need to run them.
//!
//! Who uses it: the planner builds [`Move`]s; the feeder prices them under the [`Overrides`]
//! in force ([`Rates`]) and prepares them for the engine.

use crate::motion::interp::master_axis;
use crate::motion::rate::{period_of_millihz, Period, MAX_RATE_HZ, MIN_RATE_HZ};

/// Why a move cannot be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MoveError {
    /// No axis moves.
    ZeroLength,
    /// A step count beyond ±(2^31 - 1).
    TooManySteps,
    /// Cruise rate outside 1 step/s ..= 1 MHz.
    RateOutOfRange,
}

/// One straight move: signed steps per axis and the master cruise rate; with a [`Path`], also
/// what the look-ahead needs to run it through its junctions. Built outside the interrupt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move<const N: usize> {
    pub(crate) steps: [i32; N],
    pub(crate) master: u8,
    pub(crate) ovr: Ovr,
    pub(crate) cruise: Period,
    pub(crate) path: Option<Path>,
}

/// Which override scales a move: feed for G1/G2/G3 (and G93), rapid for G0, none for jogs
/// (Grbl 1.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Ovr {
    None,
    Feed,
    Rapid,
}

/// A move's master cruise rate and what an override makes of it: Grbl scales the programmed
/// rate (F, or the axes' limit for G0), then the axes' max rates still bind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates {
    pub ovr: Ovr,
    /// Master steps/s asked at 100 % and allowed (see [`Path`]).
    pub asked_hz: f32,
    pub cap_hz: f32,
    /// Master period at 100 % (every clamp applied).
    pub cruise: Period,
}

impl Rates {
    /// The master cruise under the overrides `o`.
    pub fn cruise_at(&self, o: Overrides) -> Period {
        let pct = match self.ovr {
            Ovr::Feed => o.feed,
            Ovr::Rapid => o.rapid,
            Ovr::None => 100,
        };
        if pct == 100 {
            return self.cruise;
        }
        // max/min, not clamp (no panic path); f32 like the planner.
        let hz = (self.asked_hz * pct as f32 * 0.01).min(self.cap_hz).max(MIN_RATE_HZ as f32);
        period_of_millihz(crate::num::u64_of(hz * 1000.0))
    }
}

/// A move's length and limits in path units (mm, s), for the look-ahead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Path {
    /// Master steps per mm of path.
    pub share: f32,
    /// Path acceleration the moving axes allow, mm/s².
    pub accel: f32,
    /// Master steps/s asked at 100 % (F, or the axes' limit for G0), before any clamp, and
    /// the most the axes' max rates, the step timing and the table's top allow: an override
    /// scales the first, the second still binds.
    pub asked_hz: f32,
    pub cap_hz: f32,
    /// Highest speed at the junction with the previous move from junction deviation `$11`
    /// (0 from rest, +∞ straight on), mm/s; the look-ahead also caps it by both moves' speeds.
    pub junction: f32,
}

impl<const N: usize> Move<N> {
    /// A move of `steps` (signed, per axis) whose master axis cruises at `cruise_hz` steps/s.
    pub fn new(steps: [i64; N], cruise_hz: u32) -> Result<Self, MoveError> {
        Self::new_millihz(steps, cruise_hz as u64 * 1000)
    }

    /// The same with the cruise rate in milli-steps per second (G93 times need more than whole
    /// steps/s at low rates).
    pub fn new_millihz(steps: [i64; N], cruise_millihz: u64) -> Result<Self, MoveError> {
        if !(MIN_RATE_HZ as u64 * 1000..=MAX_RATE_HZ as u64 * 1000).contains(&cruise_millihz) {
            return Err(MoveError::RateOutOfRange);
        }
        let mut s = [0i32; N];
        let mut counts = [0u32; N];
        for i in 0..N {
            if steps[i] > i32::MAX as i64 || steps[i] < -(i32::MAX as i64) {
                return Err(MoveError::TooManySteps);
            }
            s[i] = steps[i] as i32;
            counts[i] = s[i].unsigned_abs();
        }
        let master = master_axis(&counts);
        if counts.get(master).is_none_or(|&c| c == 0) {
            return Err(MoveError::ZeroLength);
        }
        Ok(Move { steps: s, master: master as u8, ovr: Ovr::None, cruise: period_of_millihz(cruise_millihz), path: None })
    }

    /// Signed steps per axis.
    pub fn steps(&self) -> &[i32; N] {
        &self.steps
    }

    /// The master axis (most steps, ties to the lowest index).
    pub fn master(&self) -> usize {
        self.master as usize
    }

    /// Master cruise period.
    pub fn cruise(&self) -> Period {
        self.cruise
    }

    /// Its cruise and how the overrides scale it (a move without a path: not at all).
    pub fn rates(&self) -> Rates {
        let (ovr, asked_hz, cap_hz) = match self.path {
            Some(p) => (self.ovr, p.asked_hz, p.cap_hz),
            None => (Ovr::None, 0.0, 0.0),
        };
        Rates { ovr, asked_hz, cap_hz, cruise: self.cruise }
    }

    /// The same move, never overridden (a jog).
    pub fn fixed(mut self) -> Self {
        self.ovr = Ovr::None;
        self
    }

    /// The same move with its geometry, so the look-ahead can join it to its neighbours.
    pub fn with_path(mut self, path: Path) -> Self {
        self.path = Some(path);
        self
    }

    /// Its geometry, if it has one (a move without one starts and ends at rest).
    pub fn path(&self) -> Option<&Path> {
        self.path.as_ref()
    }
}

/// Override percentages: feed, rapid and spindle (100 = as programmed). The realtime bytes that
/// change them are the Grbl front end's (`grbl::overrides`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Overrides {
    pub feed: u8,
    pub rapid: u8,
    pub spindle: u8,
}

impl Overrides {
    /// 100 % everywhere.
    pub const NONE: Overrides = Overrides { feed: 100, rapid: 100, spindle: 100 };

    /// As one word: feed | rapid << 8 | spindle << 16 (how the shared state
    /// stores them).
    pub(crate) const fn pack(self) -> u32 {
        self.feed as u32 | (self.rapid as u32) << 8 | (self.spindle as u32) << 16
    }
}
