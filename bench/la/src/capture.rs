//! Opening a capture file: format detection, and the readers behind one [`Capture`] (the level
//! stream they produce is `levels.rs`, re-exported here). Used by the `la` binary and by tests; the virtual bench skips files and
//! calls [`Analyzer`] directly.

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;

use anyhow::{bail, Context, Result};

use super::analysis::Analyzer;
use super::csv::CsvReader;
pub use super::levels::{CaptureInfo, Format, Recorded, Sink};
use super::vcd::VcdReader;

impl Sink for Analyzer {
    // forward a level report
    fn level(&mut self, time_ps: u64, channel: usize, level: bool) {
        self.edge(time_ps, channel, level);
    }

    // forward the passing of time
    fn advance(&mut self, time_ps: u64) {
        Analyzer::advance(self, time_ps);
    }
}

/// An opened capture, header read.
pub enum Capture {
    Vcd(VcdReader<Box<dyn BufRead>>),
    Csv(CsvReader<Box<dyn BufRead>>),
}

impl Capture {
    // read a capture's header from any reader; `format` None sniffs the first byte
    pub fn from_reader(
        reader: Box<dyn BufRead>,
        format: Option<Format>,
        sample_rate_hz: Option<f64>,
    ) -> Result<Self> {
        let mut reader = reader;
        let format = match format {
            Some(f) => f,
            None => sniff(&mut reader)?,
        };
        Ok(match format {
            Format::Vcd => Capture::Vcd(VcdReader::new(reader)?),
            Format::Csv => Capture::Csv(CsvReader::new(reader, sample_rate_hz)?),
        })
    }

    // header facts
    pub fn info(&self) -> &CaptureInfo {
        match self {
            Capture::Vcd(r) => r.info(),
            Capture::Csv(r) => r.info(),
        }
    }

    // stream all level changes into `sink`; returns the last time in ps
    pub fn stream(&mut self, sink: &mut impl Sink) -> Result<u64> {
        match self {
            Capture::Vcd(r) => r.stream(sink),
            Capture::Csv(r) => r.stream(sink),
        }
    }
}

// open a capture file; the format comes from `format`, the extension, or the first byte
pub fn open(path: &Path, format: Option<Format>, sample_rate_hz: Option<f64>) -> Result<Capture> {
    let file = File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let by_extension = match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("vcd") => Some(Format::Vcd),
        Some("csv") => Some(Format::Csv),
        _ => None,
    };
    let reader: Box<dyn BufRead> = Box::new(BufReader::with_capacity(1 << 16, file));
    Capture::from_reader(reader, format.or(by_extension), sample_rate_hz)
        .with_context(|| format!("cannot read {}", path.display()))
}

// VCD starts with `$` (after sigrok-cli's `META` lines), anything else is taken as CSV
fn sniff(reader: &mut Box<dyn BufRead>) -> Result<Format> {
    let mut buf = reader.fill_buf().context("reading capture")?;
    while buf.starts_with(b"META ") {
        buf = buf
            .iter()
            .position(|&b| b == b'\n')
            .map_or(&[][..], |i| &buf[i + 1..]);
    }
    match buf.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'$') => Ok(Format::Vcd),
        Some(_) => Ok(Format::Csv),
        None => bail!("empty capture"),
    }
}

// read a capture held in a string (tests, small inputs)
pub fn from_text(
    text: &str,
    format: Option<Format>,
    sample_rate_hz: Option<f64>,
) -> Result<Capture> {
    let bytes = text.as_bytes().to_vec();
    Capture::from_reader(
        Box::new(std::io::Cursor::new(bytes)),
        format,
        sample_rate_hz,
    )
}
