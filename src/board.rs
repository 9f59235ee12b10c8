//! The Blue Pill pin map as plain numbers (no HAL types): shared by the firmware, the virtual
//! bench's documentation and host tests.
//!
//! Every step and direction pin is on GPIOB, so one BSRR store sets all of them at once.

use crate::MAX_AXES;

/// GPIOB pins of the step outputs, X Y Z A B C U.
pub const STEP_PINS: [u8; MAX_AXES] = [9, 10, 11, 12, 13, 14, 15];
/// GPIOB pins of the direction outputs, X Y Z A B C U (PB2 is BOOT1, so it is skipped;
/// PB3/PB4 need JTAG off, which the firmware does).
pub const DIR_PINS: [u8; MAX_AXES] = [0, 1, 3, 4, 5, 6, 7];
/// GPIOB pin of the shared driver enable (active low, as on A4988/DRV8825/TMC2209 boards).
pub const ENABLE_PIN: u8 = 8;
/// GPIOA pins of the limit-switch inputs, X Y Z A B C U (pull-up, switch to ground).
/// PA6/PA7 are the TIM3 encoder inputs ([`ENCODER_PINS`]), PA9/PA10 are USART1, PA11/PA12 USB, PA13/PA14 SWD.
pub const LIMIT_PINS: [u8; MAX_AXES] = [0, 1, 2, 3, 4, 5, 8];
/// GPIOA pin of the spindle/laser PWM: TIM1 channel 1. It is also U's limit input, so it gives
/// way to the spindle (the limit input of a wired U axis would need another pin).
pub const SPINDLE_PWM_PIN: u8 = 8;
/// GPIOA pin of the spindle enable (high = on); free once JTAG is off.
pub const SPINDLE_ENABLE_PIN: u8 = 15;
/// GPIOA pin of the spindle direction (high = M4); C's limit input.
pub const SPINDLE_DIR_PIN: u8 = 5;
/// GPIOA pin of flood coolant (M8, high = on); B's limit input.
pub const COOLANT_FLOOD_PIN: u8 = 4;
/// GPIOA pin of mist coolant (M7, high = on); A's limit input.
pub const COOLANT_MIST_PIN: u8 = 3;
/// GPIOA pins that stay limit inputs with the spindle and coolant outputs in use (X Y Z).
pub const LIMIT_INPUTS: u32 = 1 << LIMIT_PINS[0] | 1 << LIMIT_PINS[1] | 1 << LIMIT_PINS[2];
/// GPIOA pins of the quadrature encoder, A and B (TIM3 channels 1 and 2; pulled up).
pub const ENCODER_PINS: [u8; 2] = [6, 7];
/// The encoder inputs as a GPIOA mask.
pub const ENCODER_INPUTS: u32 = 1 << ENCODER_PINS[0] | 1 << ENCODER_PINS[1];

/// GPIOC pin of the probe input (pull-up, probe to ground; `$6` inverts): EXTI line 14. Every
/// GPIOA/GPIOB pin is taken (PB2 is BOOT1 and its EXTI line 2 is Z's limit), PC14 is on the
/// header and free when no 32 kHz crystal runs.
pub const PROBE_PIN: u8 = 14;

/// GPIOC pin of the safety door input (pull-up, switch to ground when the door opens; Grbl's
/// door: `Pn:D`). Read by the idle loop.
pub const DOOR_PIN: u8 = 15;

/// GPIOC pin of the on-board LED (active low).
pub const LED_PIN: u8 = 13;

/// The pin map for the first `N` axes with Grbl's `$2` (step) and `$3` (dir) invert masks.
pub const fn pin_map<const N: usize>(step_invert: u8, dir_invert: u8) -> PinMap<N> {
    let mut step = [0u8; N];
    let mut dir = [0u8; N];
    let mut i = 0;
    while i < N {
        step[i] = STEP_PINS[i];
        dir[i] = DIR_PINS[i];
        i += 1;
    }
    PinMap::new(step, dir, step_invert, dir_invert)
}

/// Where each axis's pins are on the step port, as BSRR bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PinMap<const N: usize> {
    /// BSRR bits that make each axis's step pin active (set half, or reset half if inverted).
    pub step_on: [u32; N],
    /// BSRR word that makes every step pin inactive: written at the compare event.
    pub step_off: u32,
    /// BSRR bits that make each axis's direction pin say "negative".
    pub dir_neg: [u32; N],
    /// BSRR bits that make each axis's direction pin say "positive".
    pub dir_pos: [u32; N],
    /// Dual-edge stepping ([`PinMap::dual_edge`]).
    pub dual: bool,
}

impl<const N: usize> PinMap<N> {
    /// Pin map from pin numbers on one port and Grbl-style invert masks (bit i = axis i).
    /// Positive motion has the direction pin low unless inverted, as in Grbl.
    pub const fn new(step_pins: [u8; N], dir_pins: [u8; N], step_invert: u8, dir_invert: u8) -> Self {
        let mut m = PinMap { step_on: [0; N], step_off: 0, dir_neg: [0; N], dir_pos: [0; N], dual: false };
        let mut i = 0;
        while i < N {
            let s = 1u32 << step_pins[i];
            let d = 1u32 << dir_pins[i];
            if step_invert >> i & 1 == 0 {
                m.step_on[i] = s;
                m.step_off |= s << 16;
            } else {
                m.step_on[i] = s << 16;
                m.step_off |= s;
            }
            if dir_invert >> i & 1 == 0 {
                m.dir_neg[i] = d;
                m.dir_pos[i] = d << 16;
            } else {
                m.dir_neg[i] = d << 16;
                m.dir_pos[i] = d;
            }
            i += 1;
        }
        m
    }

    /// The same pins in dual-edge mode (`$580`): every step toggles its pin, so `step_on` holds
    /// each pin's bit in the set half whatever `$2` says (the engine turns it into a set or a
    /// reset from its shadow of the pins' level) and there is no falling-edge word.
    pub const fn dual_edge(mut self) -> Self {
        let mut i = 0;
        while i < N {
            let b = self.step_on[i];
            self.step_on[i] = (b | b >> 16) & 0xFFFF;
            i += 1;
        }
        self.step_off = 0;
        self.dual = true;
        self
    }

    /// The BSRR word that puts every step pin at its idle level before this map runs: inactive
    /// (`step_off`); none in dual-edge mode, where either level is idle (the engine takes the
    /// pins' levels as they are, so no edge is made: `Engine::rebuild`).
    pub const fn idle_word(&self) -> u32 {
        self.step_off
    }
}

