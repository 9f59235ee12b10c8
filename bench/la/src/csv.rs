//! Streaming reader for sigrok-cli's `-O csv` output (libsigrok 0.5), one line at a time.
//!
//! Understands the `;` comment header (`; Channels (4/8): X_STEP, ...`, `; Samplerate: 24 MHz`),
//! sigrok-cli's `META samplerate: N` line, a label row of units (`nanoseconds,logic,...`) or of
//! names (`Time,X_STEP,...`) or none, an optional time column (with no header at all, a first
//! field other than 0/1 marks it), and `dedup` (rows only on change).
//!
//! Time: libsigrok writes `sample × floor(unit / sample period)` in the label's unit, so at
//! 24 MHz every row is 41 ns after the last instead of 41.67 ns (1.6 % slow). When the sample
//! rate is known the reader turns the value back into a sample number and uses the exact period;
//! otherwise it takes the value as written. A time column labelled `samples` holds 0 in
//! libsigrok 0.5 and is ignored: rows are then counted, which needs the sample rate (header or
//! `--samplerate`) and a capture without `dedup`.

use std::io::BufRead;

use anyhow::{anyhow, bail, Context, Result};

use super::levels::{CaptureInfo, Format, Sink};

/// How a row's time is found.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Clock {
    /// First column in this many femtoseconds per unit.
    Column { unit_fs: u128 },
    /// No usable time column: row number / sample rate.
    Rows,
}

/// CSV reader, positioned at the first data row.
pub struct CsvReader<R> {
    reader: R,
    info: CaptureInfo,
    clock: Clock,
    /// First column is time (even when ignored).
    time_column: bool,
    first_row: Option<String>,
    line: usize,
}

// femtoseconds per unit of a sigrok time label
fn unit_fs(label: &str) -> Option<u128> {
    Some(match label {
        "seconds" => 1_000_000_000_000_000,
        "milliseconds" => 1_000_000_000_000,
        "microseconds" => 1_000_000_000,
        "nanoseconds" => 1_000_000,
        "picoseconds" => 1_000,
        "femtoseconds" => 1,
        _ => return None,
    })
}

// the unit libsigrok picks for a sample rate: the smallest power of 1000 at or above it
fn sigrok_unit_fs(rate_hz: f64) -> u128 {
    let mut per_second = 1.0;
    let mut unit: u128 = 1_000_000_000_000_000;
    while per_second < rate_hz && unit > 1 {
        per_second *= 1000.0;
        unit /= 1000;
    }
    unit
}

// "24 MHz", "1 kHz", "500 Hz"
pub(super) fn parse_rate(text: &str) -> Option<f64> {
    let mut words = text.split_whitespace();
    let number: f64 = words.next()?.parse().ok()?;
    let scale = match words.next().unwrap_or("Hz") {
        "Hz" => 1.0,
        "kHz" => 1e3,
        "MHz" => 1e6,
        "GHz" => 1e9,
        _ => return None,
    };
    Some(number * scale)
}

impl<R: BufRead> CsvReader<R> {
    // read the header; `sample_rate_hz` overrides the file's
    pub fn new(mut reader: R, sample_rate_hz: Option<f64>) -> Result<Self> {
        let (mut comment_names, mut rate, mut labels, mut first_row) = (None, None, None, None);
        let mut line = 0;
        let mut text = String::new();
        loop {
            text.clear();
            if reader.read_line(&mut text).context("reading CSV")? == 0 {
                break;
            }
            line += 1;
            let row = text.trim();
            if row.is_empty() {
                continue;
            }
            if let Some(comment) = row.strip_prefix(';') {
                let comment = comment.trim();
                if let Some(names) = comment
                    .strip_prefix("Channels")
                    .and_then(|c| c.split_once(':'))
                {
                    comment_names = Some(
                        names
                            .1
                            .split(',')
                            .map(|n| n.trim().to_string())
                            .collect::<Vec<_>>(),
                    );
                } else if let Some(r) = comment.strip_prefix("Samplerate:") {
                    rate = parse_rate(r);
                }
                continue;
            }
            if let Some(r) = row.strip_prefix("META samplerate:") {
                rate = r.trim().parse().ok();
                continue;
            }
            if row.split(',').all(|f| f.trim().parse::<u64>().is_ok()) {
                first_row = Some(row.to_string());
            } else {
                labels = Some(
                    row.split(',')
                        .map(|f| f.trim().to_string())
                        .collect::<Vec<_>>(),
                );
            }
            break;
        }
        let rate = sample_rate_hz.or(rate).filter(|r| *r > 0.0);
        let columns = match (&labels, &first_row) {
            (Some(l), _) => l.len(),
            (None, Some(r)) => r.split(',').count(),
            (None, None) => bail!("CSV has no data rows"),
        };
        let first_is_level = first_row
            .as_deref()
            .and_then(|r| r.split(',').next())
            .is_some_and(|f| matches!(f.trim(), "0" | "1"));
        let (time_label, names) = layout(labels, comment_names, columns, first_is_level)?;
        let clock = match time_label.as_deref() {
            Some(label) => match unit_fs(&label.to_ascii_lowercase()) {
                Some(unit_fs) => Clock::Column { unit_fs },
                None if label.eq_ignore_ascii_case("samples") => Clock::Rows,
                // "Time" (label=channel) or no label row: libsigrok's unit for the rate.
                None => match rate {
                    Some(r) => Clock::Column {
                        unit_fs: sigrok_unit_fs(r),
                    },
                    None => bail!("CSV time column has no unit: pass --samplerate"),
                },
            },
            None => Clock::Rows,
        };
        if clock == Clock::Rows && rate.is_none() {
            bail!("CSV has no time column and no sample rate: export with -O csv:time=true or pass --samplerate");
        }
        Ok(Self {
            reader,
            info: CaptureInfo {
                format: Format::Csv,
                channels: names,
                sample_rate_hz: rate,
            },
            clock,
            time_column: time_label.is_some(),
            first_row,
            line,
        })
    }

    // channel names and sample rate
    pub fn info(&self) -> &CaptureInfo {
        &self.info
    }

    // stream every change into `sink`; returns the last time in ps
    pub fn stream(&mut self, sink: &mut impl Sink) -> Result<u64> {
        let channels = self.info.channels.len();
        let mut previous: Vec<Option<bool>> = vec![None; channels];
        let mut text = self.first_row.take().unwrap_or_default();
        let mut from_header = !text.is_empty();
        let (mut row_index, mut last_ps) = (0u64, 0u64);
        loop {
            if !from_header {
                text.clear();
                if self.reader.read_line(&mut text).context("reading CSV")? == 0 {
                    break;
                }
                self.line += 1;
            }
            from_header = false;
            let row = text.trim();
            if row.is_empty() || row.starts_with(';') {
                continue;
            }
            let line = self.line;
            let expected = channels + usize::from(self.time_column);
            if row.split(',').count() != expected {
                bail!("line {line}: expected {expected} columns");
            }
            let mut fields = row.split(',').map(str::trim);
            let raw_time = if self.time_column {
                fields.next()
            } else {
                None
            };
            let time_ps = self
                .time_ps(raw_time, row_index)
                .with_context(|| format!("line {line}"))?;
            if time_ps < last_ps {
                bail!("line {line}: time goes backwards");
            }
            for (channel, field) in fields.take(channels).enumerate() {
                let level = match field {
                    "0" => false,
                    "1" => true,
                    other => bail!("line {line}: {other:?} is not a logic level"),
                };
                if previous[channel] != Some(level) {
                    previous[channel] = Some(level);
                    sink.level(time_ps, channel, level);
                }
            }
            sink.advance(time_ps);
            last_ps = time_ps;
            row_index += 1;
        }
        Ok(last_ps)
    }

    // time of a row from its time field or its index
    fn time_ps(&self, raw: Option<&str>, row_index: u64) -> Result<u64> {
        let rate = self.info.sample_rate_hz;
        let from_sample = |sample: u64, rate: f64| (sample as f64 * 1e12 / rate).round() as u64;
        match (self.clock, raw) {
            (Clock::Column { unit_fs }, Some(raw)) => {
                let value: u64 = raw.parse().map_err(|_| anyhow!("bad time {raw:?}"))?;
                let per_second = 1e15 / unit_fs as f64;
                match rate.map(|r| (per_second / r).floor() as u64) {
                    // libsigrok's truncated period: undo it (its first row is sample 1).
                    Some(period) if period >= 1 => Ok(from_sample(
                        (value / period).saturating_sub(1),
                        rate.unwrap_or(1.0),
                    )),
                    _ => Ok(u64::try_from(value as u128 * unit_fs / 1000)
                        .map_err(|_| anyhow!("time overflows"))?),
                }
            }
            _ => Ok(from_sample(
                row_index,
                rate.ok_or_else(|| anyhow!("no sample rate"))?,
            )),
        }
    }
}

// time column label (if any) and channel names from the label row or comment header
fn layout(
    labels: Option<Vec<String>>,
    comment_names: Option<Vec<String>>,
    columns: usize,
    first_is_level: bool,
) -> Result<(Option<String>, Vec<String>)> {
    let is_time = |l: &str| {
        let l = l.to_ascii_lowercase();
        l == "time" || l == "samples" || unit_fs(&l).is_some()
    };
    let default_names = |n: usize| (0..n).map(|i| format!("D{i}")).collect::<Vec<_>>();
    if let Some(mut labels) = labels {
        let time = if labels.first().is_some_and(|l| is_time(l)) {
            Some(labels.remove(0))
        } else {
            None
        };
        let names = if labels.iter().all(|l| l == "logic") {
            match comment_names {
                Some(names) if names.len() == labels.len() => names,
                _ => default_names(labels.len()),
            }
        } else {
            labels
        };
        return Ok((time, names));
    }
    match comment_names {
        Some(names) if columns == names.len() + 1 => Ok((Some("Time".into()), names)),
        Some(names) if columns == names.len() => Ok((None, names)),
        Some(names) => bail!(
            "CSV rows have {columns} columns but the header names {} channels",
            names.len()
        ),
        // No header at all: a first field that is not 0/1 must be time.
        None if !first_is_level => Ok((Some("Time".into()), default_names(columns - 1))),
        None => Ok((None, default_names(columns))),
    }
}
