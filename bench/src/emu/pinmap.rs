//! The firmware's pin map as the bench's outputs name it (`ddastep::board`): step X..U =
//! PB9..PB15, dir X..U = PB0, PB1, PB3, PB4, PB5, PB6, PB7, enable = PB8; spindle PWM = PA8
//! (TIM1 CH1, recorded as a duty cycle), spindle enable = PA15, spindle direction = PA5, flood
//! = PA4, mist = PA3. For the report, its edge summary and the VCD writer.

use ddastep::board as pins;

/// Axis names in channel order.
pub const AXES: [&str; 7] = ["X", "Y", "Z", "A", "B", "C", "U"];
/// GPIOB step and dir pins per axis: the firmware's pin map.
pub use ddastep::board::{DIR_PINS, STEP_PINS};
/// GPIOB shared enable pin.
pub const EN_PIN: u8 = pins::ENABLE_PIN;
/// GPIOA pins of the spindle and coolant outputs, with their VCD names.
pub const TOOL_PINS: [(u8, &str); 4] = [
    (pins::SPINDLE_ENABLE_PIN, "SPINDLE_EN"),
    (pins::SPINDLE_DIR_PIN, "SPINDLE_DIR"),
    (pins::COOLANT_FLOOD_PIN, "FLOOD"),
    (pins::COOLANT_MIST_PIN, "MIST"),
];
/// Dir pin low = positive motion (Grbl's convention with `$3=0`; a `$3` mask would flip axes,
/// which the report does not follow).
pub const DIR_LOW_IS_POSITIVE: bool = true;
