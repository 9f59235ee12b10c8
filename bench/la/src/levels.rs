//! What every capture reader produces: the header facts ([`CaptureInfo`]) and a stream of
//! level reports into a [`Sink`]. Shared by the readers (`csv.rs`, `vcd.rs`) and `capture.rs`,
//! which re-exports it.

use serde::Serialize;

/// Receiver of a capture's level reports, in time order.
pub trait Sink {
    /// `channel` is at `level` at `time_ps` (repeats allowed).
    fn level(&mut self, time_ps: u64, channel: usize, level: bool);
    /// Time has reached `time_ps`.
    fn advance(&mut self, time_ps: u64);
}

/// Every report kept in memory, for tests and small files.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Recorded {
    pub levels: Vec<(u64, usize, bool)>,
    pub end_ps: u64,
}

impl Sink for Recorded {
    // keep the report
    fn level(&mut self, time_ps: u64, channel: usize, level: bool) {
        self.levels.push((time_ps, channel, level));
    }

    // keep the latest time
    fn advance(&mut self, time_ps: u64) {
        self.end_ps = self.end_ps.max(time_ps);
    }
}

/// Capture file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    Vcd,
    Csv,
}

/// What a capture's header says.
#[derive(Clone, Debug, Serialize)]
pub struct CaptureInfo {
    pub format: Format,
    /// Channel names, indexed by the channel numbers the reader reports.
    pub channels: Vec<String>,
    pub sample_rate_hz: Option<f64>,
}
