//! Logic-analyzer checker: proves step/dir pulse trains from a sigrok capture (fx2lafw at
//! 24 MHz, VCD or CSV) or from the virtual bench. For the `la` binary and for the emulator,
//! which feeds pin changes straight into an [`Analyzer`].
//!
//! Per axis it reports rising step edges, net steps signed by dir, the reduced step ratio
//! (checked against an expected ratio), the slave's largest deviation from the ideal line of
//! the master (the axis with most steps), step rate per ms and its maximum, minimum pulse high
//! and low time, minimum dir setup and hold, and step-period jitter during cruise (the longest
//! run of ms where the master's rate is within 1 % of its maximum).
//!
//! # Using it without files (virtual bench)
//!
//! ```
//! use ddastep_la::{Analyzer, AxisChannels, Config};
//!
//! // Channels are plain indices: here 0 = X step, 1 = X dir, 2 = Y step.
//! let mut config = Config::new(vec![AxisChannels::new("X", 0, Some(1)), AxisChannels::new("Y", 2, None)]);
//! config.expect = Some(vec![2, 1]);
//! let mut la = Analyzer::new(config)?;
//! for channel in 0..3 {
//!     la.edge(0, channel, false); // levels at reset: a first level is never an edge
//! }
//! la.edge(1_000_000, 1, true); // dir + at 1 µs (times in picoseconds)
//! for k in 0..4u64 {
//!     let t = 10_000_000 + k * 20_000_000; // 50 kHz
//!     la.edge(t, 0, true);
//!     if k % 2 == 1 {
//!         la.edge(t, 2, true);
//!     }
//!     la.edge(t + 2_000_000, 0, false); // 2 µs pulses
//!     la.edge(t + 2_000_000, 2, false);
//! }
//! la.advance(100_000_000); // end of capture
//! let report = la.finish();
//! assert_eq!((report.axes[0].steps, report.axes[1].steps), (4, 2));
//! assert!(report.passed());
//! assert_eq!(report.axes[0].min_dir_setup_ns, Some(9_000.0));
//! println!("{report}");
//! # Ok::<(), anyhow::Error>(())
//! ```
//!
//! # Rules
//!
//! - Time is picoseconds (`u64`) from any origin, non-decreasing; an earlier time counts as
//!   the latest time seen. A 10 s capture is 10¹³ ps.
//! - A channel's first reported level is its level at capture start: never an edge and never
//!   a pulse width, so a capture starting mid-pulse does not count that pulse. The bench reports
//!   every pin's reset level at time 0 before the first change.
//! - Several changes of one channel at one timestamp: only the last level counts; a pulse that
//!   starts and ends at one timestamp (shorter than one sample) is dropped as a glitch. Pulses
//!   narrower than `Config::min_glitch_ps` are dropped too. Both are counted per axis.
//! - At one timestamp, dir changes apply before step edges (0 ns setup, new direction), and all
//!   edges apply before deviation is sampled (simultaneous master and slave steps agree).
//! - Memory is bounded: rate bins are 1 ms until a capture passes 2¹⁸ bins (4.4 minutes), then
//!   they widen; deviation needs only convex hulls of the (master, slave) count pairs.

mod analysis;
mod axis;
pub mod capture;
mod csv;
mod deviation;
mod glitch;
mod levels;
pub mod map;
pub mod path;
pub mod plot;
pub mod pulses;
mod rate;
mod ratio;
mod report;
pub mod synth;
pub mod trace;
mod vcd;

pub use analysis::{Analyzer, AxisChannels, Config, CRUISE_FRACTION};
pub use deviation::DeviationTracker;
pub use capture::{open, Capture, CaptureInfo, Format};
pub use ratio::reduce;
pub use report::{AxisReport, Cruise, Expectation, Report, Series};
