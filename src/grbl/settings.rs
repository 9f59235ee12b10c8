//! Grbl-numbered settings (`$N=value`), their flash image, and what the engine derives from
//! them: the step timing and the ramp table.
//!
//! Who uses it: the controller (`$$`, `$N=`), the firmware shell (flash load/save via
//! [`Settings::from_bytes`] / [`Settings::to_bytes`]).
//!
//! One ramp table serves every move. It is in path units: its rate is the path speed times the
//! largest `$100+i` (or less, where a 1 MHz top would stop a coarser axis short of its own
//! cap: `Settings::per_mm`), its acceleration twice the largest `$120+i` in those units, its top the
//! fastest path speed all axes allow together (capped by what fits in the table's 1.024 s).
//! Each move walks it at its own acceleration's fraction (from the axes it moves) and scales
//! it to its master's share of the path, so axes that do not move never slow a move down.
//!
//! Files: [`values`] (the struct, defaults, setting numbers), [`table`] (`$$` and `$N=`: ranges,
//! decimals, image offsets), [`profile`] (timing, ramp table, planner limits), [`image`] (the
//! flash image), [`layout`] (the image's offsets, byte helpers, CRC); host-only, [`docs`] (each
//! setting's name, unit, range and text for docs/settings.md, none of it in the firmware). This file re-exports
//! their public items (`settings::Settings`, …); they name nothing of it.

#[cfg(not(target_os = "none"))]
pub mod docs;
pub mod image;
pub mod layout;
pub mod profile;
pub mod table;
pub mod values;

pub(crate) use layout::{copy_bytes, put4};
pub use layout::{crc32, SETTINGS_LEN};
pub use profile::{Ramped, ISR_FLOOR_TICKS};
pub use values::*;
