//! What the shell and the reports read from the controller, and the inputs the shell sets
//! between polls (RX room, limit pins, a `?`).
//!
//! Who uses it: the firmware shell and the test rigs (`crate::grbl::shell`).

use super::Controller;
use crate::grbl::coords::Offsets;
use crate::grbl::gcode::Modal;
use crate::grbl::protocol::RX_BUFFER_LEN;
use crate::grbl::settings::{Ramped, Settings};
use crate::grbl::store::{Stored, IMAGE_LEN, STARTUP_LINES};

impl<const N: usize> Controller<'_, N> {
    /// The settings in force.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// What flash should hold (after [`Actions::save`](crate::grbl::controller::Actions::save)).
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

    /// Line bytes waiting in the shell's RX ring (not yet taken by [`Self::byte`]), for `Bf:`
    /// in status reports: as Grbl's `serial_get_rx_buffer_available`, the announced 128-byte
    /// buffer less the bytes waiting (never below 0; the ring itself holds 256). The line being
    /// carried out has left the ring and does not count, as in Grbl.
    pub fn set_rx_waiting(&mut self, n: usize) {
        // (Signed, clamped at 0: this form keeps the idle loop's code size a multiple of 8
        // bytes, so the flash-resident step and DMA fill code keeps its modeled fetch timing.)
        self.rx_free = (RX_BUFFER_LEN as i32 - n as i32).max(0) as u32;
    }

    /// The limit inputs as the shell read them (GPIOA's input register), for `Pn:` in status
    /// reports; `$5` applies here.
    pub fn set_limit_inputs(&mut self, gpioa_idr: u32) {
        self.limit_pins = crate::grbl::limits::active_pins(gpioa_idr, self.settings.limit_invert);
    }

    /// `?` arrived: a status report goes out at the next `poll`.
    pub fn status_request(&mut self) {
        self.status_wanted = true;
    }
}
