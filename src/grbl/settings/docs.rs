//! What each `$N` setting means, for people: name, unit, accepted range, a description and how
//! it differs from Grbl 1.1. Host-only (`#[cfg(not(target_os = "none"))]`), so none of this text
//! is in the firmware image; `tests/settings_docs.rs` writes `docs/settings.md` and
//! `docs/settings.csv` from it and from `$$`, and checks that every setting of [`Settings::ids`]
//! has an entry here and no entry names a setting the firmware lacks.
//!
//! Who uses it: the docs generator (`UPDATE_DOCS=1 cargo test --test settings_docs`).

use super::values::*;
use crate::encoder;
use crate::motion::ramp::{FLEX_MAX, FLEX_MIN};
use crate::motion::rate::MAX_RATE_HZ;
use crate::{AXIS_NAMES, MAX_AXES};

extern crate alloc;

use alloc::format;
use alloc::string::{String, ToString};

/// One setting's documentation.
#[derive(Clone, Debug)]
pub struct Doc {
    /// The setting number (`$id`).
    pub id: u16,
    /// Short name, as Grbl's `setting_codes_en_US.csv` writes it.
    pub name: String,
    /// Unit, in Grbl's CSV words (`microseconds`, `mask`, `boolean`, `mm/min`, …).
    pub unit: &'static str,
    /// Lowest and highest value `$N=` accepts (flags: any value, nonzero is 1).
    pub range: (f32, f32),
    /// What it does (Markdown).
    pub text: &'static str,
    /// How it differs from Grbl 1.1 (Markdown; "same meaning." when it does not).
    pub grbl: &'static str,
}

/// An entry of [`LOW`]: number, name, unit, range, text, difference from Grbl.
type Low = (u16, &'static str, &'static str, (f32, f32), &'static str, &'static str);

const fn doc(id: u16, name: &'static str, unit: &'static str, range: (f32, f32), text: &'static str, grbl: &'static str) -> Low {
    (id, name, unit, range, text, grbl)
}

const BOOL: (f32, f32) = (0.0, 1.0);
const MASK: (f32, f32) = (0.0, 255.0);
const SAME: &str = "same meaning.";

/// The settings below 100 and `$580`–`$582`, in numeric order.
const LOW: [Low; 36] = [
    doc(0, "Step pulse time", "microseconds", (0.2, 100.0),
        "Length of each step pulse. In dual-edge mode (`$580=1`) the shortest time between two toggles of a step pin. \
         It also caps the step rate: `$I` prints the cap in force ([internals](internals.md#how-a-moves-speed-is-limited)). \
         Below 0.2: `error:6`.",
        "Grbl's minimum is 3 µs; here 0.2 µs, for drivers such as the TMC2209 (t_SH ≥ 100 ns)."),
    doc(1, "Step idle delay", "milliseconds", MASK,
        "How long the drivers stay enabled after motion stops; 255 keeps them enabled.", SAME),
    doc(2, "Step pulse invert", "mask", MASK,
        "Bit i inverts the step pin of axis i (X Y Z A B C U: bits 0-6). Applied in place at rest: the step pins go to \
         their new idle level. Does not apply in dual-edge mode (`$580=1`).",
        "same meaning, with a bit for each of up to 7 axes."),
    doc(3, "Step direction invert", "mask", MASK,
        "Bit i inverts the direction pin of axis i. Positive motion has DIR low, as in Grbl. Applied in place at rest.",
        "same meaning, with a bit for each of up to 7 axes."),
    doc(4, "Invert step enable pin", "boolean", BOOL,
        "0: EN (PB8) is high while the drivers are off (active-low enable inputs: A4988, DRV8825, TMC2209); \
         1 inverts it (a TB6600 wired common-anode, [wiring](wiring.md#en-polarity)).", SAME),
    doc(5, "Invert limit pins", "boolean", BOOL,
        "1 for normally-closed limit switches: `Pn:`, hard limits and homing follow it.", SAME),
    doc(6, "Invert probe pin", "boolean", BOOL, "1 for a normally-closed probe: `Pn:P` and G38 follow it.", SAME),
    doc(STATUS_MASK, "Status report options", "mask", MASK,
        "Bit 0: `MPos:` in status reports (else `WPos:`); bit 1: `Bf:` (free planner blocks, free RX bytes). \
         Higher bits are dropped.", SAME),
    doc(11, "Junction deviation", "millimeters", (0.010, 0.010),
        "The look-ahead's junction deviation, shown fixed at 0.010 mm; any other value is `error:3`.",
        "Settable in Grbl; fixed here."),
    doc(12, "Arc tolerance", "millimeters", (1e-4, 1000.0),
        "Largest distance of a G2/G3 chord from its arc.",
        "same meaning; Grbl's own chord count can exceed it slightly."),
    doc(13, "Report in inches", "boolean", (0.0, 0.0),
        "Reports are in millimeters; only 0 is accepted (else `error:3`).", "Settable in Grbl; fixed at 0 here."),
    doc(20, "Soft limits enable", "boolean", BOOL,
        "A G-code target outside the travel box (machine −`$130+i` … 0) is `ALARM:2` (then `[MSG:Reset to continue]`, Ctrl-X, `$X`), a jog \
         target `error:15`. Needs `$22=1` (else `error:10`).", SAME),
    doc(21, "Hard limits enable", "boolean", BOOL,
        "A limit input going active stops all step output at once, then `ALARM:1` ([safety](safety.md#hard-limits)). \
         A switch's release and its bounce do not trip.", SAME),
    doc(22, "Homing cycle enable", "boolean", BOOL,
        "`$H` works (else `error:5`) and power-up is in the alarm state (`$H` or `$X` unlocks); `$22=0` also clears \
         `$20` ([homing](safety.md#homing)).", SAME),
    doc(23, "Homing direction invert", "mask", MASK,
        "Bit i set homes axis i toward its min end (negative); clear: toward its max end.", SAME),
    doc(24, "Homing locate feed rate", "mm/min", (1e-3, 1e8), "Feed of the slow pass that locates the switch.", SAME),
    doc(25, "Homing search seek rate", "mm/min", (1e-3, 1e8), "Rate of the fast pass that finds the switch.", SAME),
    doc(26, "Homing switch debounce delay", "milliseconds", (0.0, 65_535.0),
        "Pause after each homing pass (and after a switch stops one, before the pins are read).", SAME),
    doc(27, "Homing switch pull-off distance", "millimeters", (0.0, 1e6),
        "Distance moved off the switch after it closed; `$H` refuses a pull-off ≥ `$130+i` (`error:3`).", SAME),
    doc(DIR_SETUP, "Direction setup time", "microseconds", (0.0, 1000.0),
        "Time from a direction change to the next step edge (the driver's direction setup).",
        "Not in Grbl 1.1 (fixed at build time there); grblHAL's number."),
    doc(30, "Maximum spindle speed", "RPM", (0.0, 1e6), "S at full PWM duty (laser: S units).", SAME),
    doc(31, "Minimum spindle speed", "RPM", (0.0, 1e6), "S at the lowest non-zero PWM duty (one count).", SAME),
    doc(32, "Laser-mode enable", "boolean", BOOL,
        "S rides along with each move (motion does not stop for it), G0 is dark, M4 scales the power with the speed \
         ([commands](commands.md#spindle-laser-and-coolant)).", SAME),
    doc(SPINDLE_PWM_HZ, "Spindle PWM frequency", "Hz", (1.0, 100_000.0), "Frequency of the spindle/laser PWM on PA8.",
        "Not in Grbl 1.1 (fixed at build time there); grblHAL's number."),
    doc(RAMP_START, "Ramp start rate", "steps/s", (1.0, MAX_RATE_HZ as f32),
        "Where the ramp table starts: a start speed in steps/s of the axis with the most steps/mm.", "Not in Grbl."),
    doc(RAMP_SHAPE, "Ramp shape", "integer", (0.0, 1.0),
        "0: trapezoid; 1: S-curve: every acceleration and deceleration of every move (entry to cruise, cruise to exit, \
         holds, overrides, homing) is its own logistic S (seeds 000/002, steepness `$582`), peaking at the move's \
         acceleration; a ramp then takes k = 2.07 times the trapezoid's (`$582=4`); distances and G93 times stay exact.",
        "Not in Grbl (trapezoid only)."),
    doc(AXIS_COUNT, "Axes", "integer", (3.0, MAX_AXES as f32),
        "Axes the machine has: 3 = X Y Z gantry … 7 = X Y Z A B C U. Status reports, `$#`, `$$` and G-code follow it. \
         A 4th to 7th axis takes the pins of mist, flood, spindle direction and spindle PWM ([wiring](wiring.md)).",
        "Not in Grbl (fixed at build time there)."),
    doc(encoder::AXIS, "Encoder axis", "integer", (0.0, MAX_AXES as f32),
        "The axis the encoder watches: 0 none, 1 = X … 7 = U, at most `$42` ([step-loss detection]\
         (safety.md#step-loss-detection-encoder-feedback)).", "Not in Grbl."),
    doc(encoder::COUNTS_PER_STEP, "Encoder counts per step", "counts", (1.0 / 65_536.0, 64.0),
        "Encoder counts (x4: every A and B edge) per motor step; from 1/65 536 (its fixed point) to 64.", "Not in Grbl."),
    doc(encoder::INVERT, "Encoder direction invert", "boolean", BOOL,
        "1 when the encoder counts down while the axis moves in +.", "Not in Grbl."),
    doc(encoder::THRESHOLD, "Step-loss threshold", "steps", (0.0, 1e6),
        "Steps the measured position may trail the commanded one, on top of one step, one count and the lag allowance.",
        "Not in Grbl."),
    doc(encoder::ACTION, "Step-loss action", "integer", (0.0, 1.0),
        "On step loss: 0 feed hold, 1 alarm (`ALARM:17`).", "Not in Grbl."),
    doc(encoder::LAG, "Motor lag allowance", "milliseconds", (0.0, 1000.0),
        "The threshold grows by the measured speed × this time (the rotor trailing its field).", "Not in Grbl."),
    doc(DUAL_EDGE, "Dual-edge step mode", "boolean", BOOL,
        "Each step toggles its step pin, for drivers that step on both edges (TMC22xx with `dedge` set over UART). \
         `$0` is then the shortest time between two toggles, `$29` the direction setup before a toggle; `$2` does not \
         apply. Applied in place at rest (the pins toggle on from their levels; leaving the mode puts them at `$2`'s \
         idle level). A reset or a hard limit's stop drives the step pins low: an axis whose pin was high then takes one \
         step the position does not count, so home again after one.",
        "Not in Grbl or grblHAL; listed after the axis settings."),
    doc(DMA_BURST, "DMA burst step output", "boolean", BOOL,
        "TIM2 still paces every edge but DMA stores the step words and periods the engine buffered: no interrupt per \
         edge, higher rates, far less CPU per step. A feed hold or stop reaches the pins after at most the buffered \
         1.33 ms. Works with `$580`. Applied in place at rest ([internals](internals.md#dma-burst-mode-5811)).",
        "Not in Grbl or grblHAL; listed after the axis settings."),
    doc(S_FLEX, "S-curve steepness (Flexible)", "integer", (FLEX_MIN as f32, FLEX_MAX as f32),
        "With `$41=1`: the seeds' logistic over ±Flexible, normalised to start and end exactly at the two speeds of a \
         ramp; 1 gentle (a ramp takes k = 1.08 times the trapezoid's) to 12 steep (k = 6.0); 4: k = 2.07.",
        "Not in Grbl or grblHAL; listed after the axis settings."),
];

/// The axis families: first number, name after the axis letter, unit, range, text.
const FAMILIES: [(u16, &str, &str, (f32, f32), &str); 4] = [
    (100, "travel resolution", "step/mm", (1e-3, 1e5), "Steps per millimeter (per degree on a rotary axis)."),
    (110, "maximum rate", "mm/min", (1e-3, 1e8),
        "Highest rate of this axis, also G0's. A move's path speed is at most the lowest of its moving axes' rates."),
    (120, "acceleration", "mm/sec^2", (1e-3, 1e8),
        "Acceleration of this axis. A move's acceleration is at most the lowest of its moving axes'."),
    (130, "maximum travel", "millimeters", (0.0, 1e6),
        "With `$20=1` the axis stays within machine −`$130+i` … 0 (machine zero is the homed corner); homing seeks at \
         most 1.5 × this."),
];

/// A number's digits in groups of three from the right, as the docs write numbers:
/// `"63280"` → `"63 280"` (the settings pages, and the figures `bench/figures` writes).
pub fn grouped(digits: &str) -> String {
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

/// Every setting's documentation, in numeric order (axis settings for all 7 axes).
pub fn docs() -> impl Iterator<Item = Doc> {
    let low = |hi: bool| {
        LOW.into_iter().filter(move |d| (d.0 > 139) == hi).map(|(id, name, unit, range, text, grbl)| Doc {
            id,
            name: name.to_string(),
            unit,
            range,
            text,
            grbl,
        })
    };
    let axes = FAMILIES.into_iter().flat_map(|(first, name, unit, range, text)| {
        AXIS_NAMES.into_iter().enumerate().map(move |(i, letter)| Doc {
            id: first + i as u16,
            name: format!("{letter}-axis {name}"),
            unit,
            range,
            text,
            grbl: if i < 3 { SAME } else { "Grbl has X, Y and Z only." },
        })
    });
    low(false).chain(axes).chain(low(true))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_setting_has_one_doc_and_every_doc_a_setting() {
        let ids: alloc::vec::Vec<u16> = Settings::ids(MAX_AXES).collect();
        let documented: alloc::vec::Vec<u16> = docs().map(|d| d.id).collect();
        assert_eq!(ids, documented);
    }
}
