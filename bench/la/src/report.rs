//! The checker's result: one [`Report`] per capture, printed for people (`Display`) or as JSON
//! (serde). Times are nanoseconds, rates hertz, deviations steps; `null` means not measured.

use std::fmt;

use serde::Serialize;

/// Everything the checker found in one capture.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// From the first to the last reported time.
    pub duration_ns: f64,
    /// Width of the rate bins (1 ms unless the capture is very long).
    pub bin_ms: f64,
    pub axes: Vec<AxisReport>,
    /// Index into `axes` of the axis with the most steps.
    pub master: Option<usize>,
    /// Rising-edge counts reduced by their gcd, in axis order.
    pub ratio: Vec<u64>,
    pub expect: Option<Expectation>,
    pub cruise: Option<Cruise>,
    /// Pulses dropped as glitches, all channels.
    pub glitches: u64,
    /// Per-bin curves for plotting (not in JSON).
    #[serde(skip)]
    pub series: Series,
}

/// Result of one axis.
#[derive(Clone, Debug, Serialize)]
pub struct AxisReport {
    pub name: String,
    /// Rising step edges.
    pub steps: u64,
    /// Steps signed by the dir level (high = +, unless inverted).
    pub net_steps: i64,
    pub dir_changes: u64,
    /// Highest per-bin step rate.
    pub max_rate_hz: f64,
    /// Mean step rate over the cruise window.
    pub cruise_rate_hz: Option<f64>,
    /// Standard deviation of step periods over the cruise window.
    pub jitter_std_ns: Option<f64>,
    /// Longest minus shortest step period over the cruise window.
    pub jitter_pp_ns: Option<f64>,
    pub min_high_ns: Option<f64>,
    pub min_low_ns: Option<f64>,
    pub min_dir_setup_ns: Option<f64>,
    pub min_dir_hold_ns: Option<f64>,
    /// Largest |slave - ideal| at the master's steps; `None` for the master.
    pub max_deviation_steps: Option<f64>,
    /// Pulses dropped as glitches on this axis's step and dir channels.
    pub glitches: u64,
}

/// The `--expect` check.
#[derive(Clone, Debug, Serialize)]
pub struct Expectation {
    pub expected: Vec<u64>,
    /// The axes compared, in order: all mapped axes when the ratio has a term for each, else
    /// those with steps.
    pub axes: Vec<String>,
    pub pass: bool,
    /// Set when the terms do not fit the axes that stepped: what to change (the `la` binary
    /// exits 2 with it).
    pub mapping_error: Option<String>,
}

/// The longest run of bins where the master's rate is within 1 % of its maximum.
#[derive(Clone, Debug, Serialize)]
pub struct Cruise {
    pub start_ms: f64,
    pub end_ms: f64,
    /// Master's mean step rate in the window.
    pub rate_hz: f64,
}

/// Curves over time, one value per bin.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// Step rate in Hz, per axis.
    pub rate_hz: Vec<Vec<f64>>,
    /// Slave minus ideal count at the end of each bin, per axis (empty for the master).
    pub deviation_steps: Vec<Vec<f64>>,
}

impl Report {
    // true when every requested check passed
    pub fn passed(&self) -> bool {
        self.expect.as_ref().is_none_or(|e| e.pass)
    }

    // "X:Y:Z = 5000:3000:2000 = 5:3:2 exact, cruise 50.0 kHz, ..."
    pub fn summary(&self) -> String {
        // Axes that never stepped are listed apart, so a 7-axis bench VCD of a 3-axis move
        // reads "X:Y:Z = 5000:3000:2000 = 5:3:2".
        let (moved, idle): (Vec<&AxisReport>, Vec<&AxisReport>) =
            self.axes.iter().partition(|a| a.steps > 0);
        let shown = if moved.is_empty() { self.axes.iter().collect() } else { moved };
        let names: Vec<_> = shown.iter().map(|a| a.name.as_str()).collect();
        let counts: Vec<_> = shown.iter().map(|a| a.steps).collect();
        let mut line = format!(
            "{} = {} = {}",
            names.join(":"),
            join(&counts),
            join(&super::ratio::reduce(&counts))
        );
        if let Some(expect) = &self.expect {
            if expect.pass {
                line += " exact";
            } else {
                line += &format!(", expected {}: MISMATCH", join(&expect.expected));
            }
        }
        if let Some(cruise) = &self.cruise {
            line += &format!(", cruise {}", hz(cruise.rate_hz));
        }
        let min = |f: fn(&AxisReport) -> Option<f64>| {
            self.axes
                .iter()
                .filter_map(f)
                .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.min(v))))
        };
        line += &format!(", min pulse {}", ns(min(|a| a.min_high_ns)));
        line += &format!(", dir setup {}", ns(min(|a| a.min_dir_setup_ns)));
        if self.glitches > 0 {
            line += &format!(", {} glitches dropped", self.glitches);
        }
        if !idle.is_empty() && idle.len() < self.axes.len() {
            let names: Vec<_> = idle.iter().map(|a| a.name.as_str()).collect();
            line += &format!(", no steps on {}", names.join(", "));
        }
        line
    }
}

// "5:3:2"
fn join(values: &[u64]) -> String {
    values
        .iter()
        .map(u64::to_string)
        .collect::<Vec<_>>()
        .join(":")
}

// a rate in Hz or kHz
fn hz(rate: f64) -> String {
    if rate >= 1000.0 {
        format!("{:.1} kHz", rate / 1000.0)
    } else {
        format!("{rate:.1} Hz")
    }
}

// a time in ns, µs or ms, or "-"
fn ns(time: Option<f64>) -> String {
    match time {
        None => "-".into(),
        Some(t) if t >= 1e9 => format!("{:.3} s", t / 1e9),
        Some(t) if t >= 1e6 => format!("{:.3} ms", t / 1e6),
        Some(t) if t >= 1e3 => format!("{:.3} µs", t / 1e3),
        Some(t) => format!("{t:.0} ns"),
    }
}

impl fmt::Display for Report {
    // summary line, then one row per axis
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}", self.summary())?;
        write!(f, "capture {}", ns(Some(self.duration_ns)))?;
        match &self.cruise {
            Some(c) => writeln!(f, ", cruise {:.1}..{:.1} ms", c.start_ms, c.end_ms)?,
            None => writeln!(f, ", no cruise")?,
        }
        writeln!(
            f,
            "{:<6} {:>9} {:>9} {:>5} {:>10} {:>10} {:>9} {:>9} {:>9} {:>9} {:>8} {:>16}",
            "axis",
            "steps",
            "net",
            "dirs",
            "max rate",
            "cruise",
            "min high",
            "min low",
            "setup",
            "hold",
            "dev",
            "jitter σ / p-p"
        )?;
        for (i, a) in self.axes.iter().enumerate() {
            let dev = match a.max_deviation_steps {
                _ if self.master == Some(i) => "master".to_string(),
                Some(d) => format!("{d:.2}"),
                None => "-".to_string(),
            };
            let jitter = match (a.jitter_std_ns, a.jitter_pp_ns) {
                (Some(s), Some(p)) => format!("{} / {}", ns(Some(s)), ns(Some(p))),
                _ => "-".to_string(),
            };
            writeln!(
                f,
                "{:<6} {:>9} {:>+9} {:>5} {:>10} {:>10} {:>9} {:>9} {:>9} {:>9} {:>8} {:>16}",
                a.name,
                a.steps,
                a.net_steps,
                a.dir_changes,
                hz(a.max_rate_hz),
                a.cruise_rate_hz.map_or("-".into(), hz),
                ns(a.min_high_ns),
                ns(a.min_low_ns),
                ns(a.min_dir_setup_ns),
                ns(a.min_dir_hold_ns),
                dev,
                jitter,
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_read_naturally() {
        assert_eq!(hz(50_000.0), "50.0 kHz");
        assert_eq!(hz(400.0), "400.0 Hz");
        assert_eq!(ns(Some(4_125.0)), "4.125 µs");
        assert_eq!(ns(Some(41.7)), "42 ns");
        assert_eq!(ns(None), "-");
        assert_eq!(ns(Some(1e10)), "10.000 s");
        assert_eq!(join(&[5, 3, 2]), "5:3:2");
    }
}
