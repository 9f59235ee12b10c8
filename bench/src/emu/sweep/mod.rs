//! The step-rate sweep: for each axis count, the highest master rate the firmware sustains on
//! the emulated board, and its CPU load at a few fixed rates. For `cargo sim -- --sweep` and
//! `cargo bench --bench sweep`; the numbers go to bench/RESULTS.md.
//!
//! One point = a fresh board (reset), the sweep settings, one `G1` on `axes` axes with the
//! steps in the ratio 10:6:4:8:2:7:5 (X is the master) and F chosen for the target master rate,
//! long enough for `cruise_ms` of measured cruise plus margins. The measured stretch is the
//! whole 1 ms load windows from 2 ms after the ramp's end; every window in it must have X
//! within 1 % of the target (rate from the first and last X edge of the window), else the
//! point reports "no cruise". A point is sustainable when it has no timer overrun in the move,
//! every axis made exactly its steps (rising edges and net count), cruise was reached and no
//! measured window is busier than `max_load`.
//!
//! Step-ISR figures (entries, cycles, BSRR offsets) cover the measured stretch only, so the
//! move's load (refill, 1 000-cycle `Engine::load`) and the ramp walk stay out of them.
//!
//! `setup.rs` (ratio, settings, mode), `measure.rs` (one point), `point.rs` (its verdict and
//! text), `search.rs` (the rate search and the sweep), `markdown.rs` (table and RESULTS.md),
//! `stamp.rs` (date, git commit, flash size).

mod markdown;
mod measure;
mod point;
mod search;
pub(crate) mod setup;
mod stamp;

pub use markdown::{isr_cost_fit, results_markdown};
pub use measure::{boot, run_point};
pub use point::{point_line, point_text, verdict_text, Point, Verdict};
pub use search::{sweep, Bracket, Options, Row, Sweep};
pub use setup::{settings_lines, Mode, PULSE_US, RATIO};
pub use stamp::{firmware_commit, image_sizes};
