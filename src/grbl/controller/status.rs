//! The `?` status report with Grbl 1.1's fields and refresh rules: `WCO:` every 10th report
//! while idle (30th while busy) and in the next report after an offset changes; `Ov:` every
//! 10th (20th) and after an override changes, but never in the same report as `WCO:`.

use super::{Controller, Jogging, FEED_RING};
use crate::grbl::reply::Out;
use crate::motion::shared::State;
use crate::grbl::report::{self, Status};

/// Reports between `WCO:` refreshes: idle, busy.
const WCO_REFRESH: (u8, u8) = (10, 30);
/// Reports between `Ov:` refreshes: idle, busy.
const OVR_REFRESH: (u8, u8) = (10, 20);

impl<const N: usize> Controller<'_, N> {
    /// The state word of a status report, and whether it counts as busy for the refresh
    /// rates (all but Idle, Alarm, Check and Sleep, which return at once).
    fn state_name(&self) -> (&'static [u8], bool) {
        let moving = self.feeder.pending() > 0;
        let name: &'static [u8] = match self.shared.state() {
            _ if self.homing.is_some() => b"Home",
            _ if self.alarm => return (b"Alarm", false),
            _ if self.sleep => return (b"Sleep", false),
            _ if self.check => return (b"Check", false),
            _ if self.door_active() => self.door_state(),
            _ if self.jog != Jogging::Off && (moving || self.shared.state() != State::Idle) => b"Jog",
            State::Run => b"Run",
            State::Holding => b"Hold:1",
            State::Held => b"Hold:0",
            State::Idle if moving => b"Run",
            State::Idle => return (b"Idle", false),
        };
        (name, true)
    }

    /// `<State|MPos:…|FS:feed,0|WCO:…|Ov:…>`: feed from the master rate and the running move's
    /// mm/step; positions per `$10`.
    #[inline(never)]
    pub(super) fn status(&mut self, out: &mut impl Out) {
        let (state, busy) = self.state_name();
        let pick = |r: (u8, u8)| if busy { r.1 - 1 } else { r.0 - 1 };
        let ov = self.shared.overrides();
        if ov != self.ov_seen {
            self.ov_seen = ov;
            self.ovr_count = 0;
        }
        let show_wco = match self.wco_count {
            0 => {
                self.wco_count = pick(WCO_REFRESH);
                if self.ovr_count == 0 {
                    self.ovr_count = 1;
                }
                true
            }
            _ => {
                self.wco_count -= 1;
                false
            }
        };
        let show_ov = match self.ovr_count {
            0 => {
                self.ovr_count = pick(OVR_REFRESH);
                true
            }
            _ => {
                self.ovr_count -= 1;
                false
            }
        };
        let n = self.axes;
        let steps = self.shared.positions();
        let wco = self.offsets.wco(self.modal.coord);
        let mpos_only = self.settings.status_mask & 1 != 0;
        let pos: [f32; N] = core::array::from_fn(|i| {
            let m = steps[i] as f32 / self.limits.steps_per_mm[i];
            if mpos_only {
                m
            } else {
                m - wco[i]
            }
        });
        let rate = self.shared.rate_hz() as f32;
        let per_step = self.feed_ring[self.shared.moves_done() as usize % FEED_RING];
        let blocks = (self.feeder.capacity() as u32).saturating_sub(self.feeder.pending());
        let (speed, acc, n_acc) = self.accessories();
        report::status(
            out,
            &Status {
                state,
                pos: pos.get(..n).unwrap_or_default(),
                mpos: mpos_only,
                bf: (self.settings.status_mask & 2 != 0).then_some((blocks, self.rx_free)),
                feed: rate * per_step * 60.0,
                speed,
                acc: &acc[..n_acc],
                pins: self.limit_pins | if self.probe_pin { report::PIN_PROBE } else { 0 } | if self.door_pin { report::PIN_DOOR } else { 0 },
                wco: show_wco.then_some(wco.get(..n).unwrap_or_default()),
                ov: show_ov.then_some(ov),
                enc: self.encoder_status(),
            },
        );
    }
}
