//! The Grbl 1.1 front end: the serial line protocol, G-code, `$` settings, reports and the
//! controller that ties them to the planner, and the shell's realtime dispatch and idle step.

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
