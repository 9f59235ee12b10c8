//! The Grbl 1.1 front end: the serial line protocol, G-code, `$` settings, reports and the
//! controller that ties them to the planner, the shell's realtime dispatch and idle step, and
//! the chip check at boot.

pub mod chip;
pub mod controller;
pub mod coords;
pub mod gcode;
pub mod jog;
pub mod limits;
pub mod overrides;
pub mod packet;
pub mod protocol;
pub mod reply;
pub mod report;
pub mod settings;
pub mod shell;
pub mod spindle;
pub mod store;
