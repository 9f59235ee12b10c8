//! Grbl 1.1's numbered errors (`error:N`), the one error type of the library.
//!
//! Who uses it: the Grbl front end replies with it (`grbl::reply::put_error`); the planner,
//! the arc checks and the encoder settings return it. A leaf, so planning and the encoder need
//! not import the front end to return Grbl's numbers.

/// Grbl 1.1 error codes (`error:N`), numbered as in Grbl's `doc/csv/error_codes_en_US.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Error {
    /// A word without its letter (or a byte that is no letter).
    ExpectedCommandLetter = 1,
    /// Missing or malformed number (also: more than 15 significant digits).
    BadNumberFormat = 2,
    /// Unknown or malformed `$` command, or a setting value out of range.
    InvalidStatement = 3,
    /// Negative value where only positive ones make sense.
    NegativeValue = 4,
    /// Homing is not enabled (we have no homing yet).
    SettingDisabled = 5,
    /// Step pulse shorter than the minimum (1 µs here; Grbl says 3 µs).
    StepPulseMin = 6,
    /// The persistent store could not be read (Grbl's EEPROM read failure).
    SettingReadFail = 7,
    /// `$` command that needs the machine idle.
    NotIdle = 8,
    /// G-code locked out in alarm state (`$X` unlocks).
    AlarmLock = 9,
    /// Soft limits need homing.
    SoftLimitNeedsHoming = 10,
    /// Line longer than the line buffer (`grbl::protocol::LINE_LEN`).
    LineOverflow = 11,
    /// `$X`/`$H` with the safety door open.
    CheckDoor = 13,
    /// A `$N`/`$I=` line longer than the store keeps.
    LineLengthExceeded = 14,
    /// A jog target beyond the soft limits.
    TravelExceeded = 15,
    /// A `$J=` line with a word jogging does not take.
    InvalidJogCommand = 16,
    /// G/M code or word we do not support.
    UnsupportedCommand = 20,
    /// Two commands of one modal group in a block.
    ModalGroupViolation = 21,
    /// G1 without a feed rate.
    UndefinedFeedRate = 22,
    /// G/M command needs an integer value.
    CommandValueNotInteger = 23,
    /// Two commands that both use the axis words.
    AxisCommandConflict = 24,
    /// A word given twice in a block.
    WordRepeated = 25,
    /// A command that needs axis words has none.
    NoAxisWords = 26,
    /// Line number out of range.
    InvalidLineNumber = 27,
    /// A command misses its value word (G4 without P).
    ValueWordMissing = 28,
    /// G10 P beyond the six coordinate systems.
    UnsupportedCoordSys = 29,
    /// G53 without G0 or G1 in force.
    G53InvalidMotionMode = 30,
    /// Axis words with no command to use them.
    AxisWordsExist = 31,
    /// G2/G3 without an axis word in the selected plane.
    NoAxisWordsInPlane = 32,
    /// Target out of range (beyond ±1e6 mm or ±(2^31 - 1) steps).
    InvalidTarget = 33,
    /// G2/G3 R form: the radius is shorter than half the chord.
    ArcRadiusError = 34,
    /// G2/G3 IJK form without an offset in the selected plane.
    NoOffsetsInPlane = 35,
    /// Value words no command uses.
    UnusedWords = 36,
    /// G43.1 without Z, or with another axis.
    G43DynamicAxisError = 37,
    /// A value beyond its maximum (tool number > 255).
    MaxValueExceeded = 38,
    /// The chip check at boot failed (grblHAL's code): a line that would move, unlock or
    /// write flash on a part with too little flash (`crate::grbl::chip`).
    SelfTestFailed = 49,
}
