//! Step rate over time: per-bin step counts and step-period statistics of one axis.
//!
//! Bins are 1 ms wide until a capture grows past [`MAX_BINS`]; then every axis merges pairs of
//! bins (exact for counts, min/max and Welford sums), so memory stays bounded whatever the
//! capture length or sample rate. A step period belongs to the bin of the rising edge that
//! ends it. The rate of a bin is `periods / sum of periods` (1 / mean period), which is exact
//! for a constant rate even when it does not divide 1 kHz; a bin with no completed period lies
//! inside one period and takes that period's rate.

use std::ops::Range;

/// Bins are 1 ms wide to start with (the firmware's ramp tables change rate per ms).
pub const BIN_PS: u64 = 1_000_000_000;
/// Past this many bins, bins double in width.
pub const MAX_BINS: usize = 1 << 18;

/// Count, mean, spread and extremes of step periods (Welford, mergeable).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PeriodStats {
    pub n: u64,
    mean: f64,
    m2: f64,
    pub min_ps: u64,
    pub max_ps: u64,
}

impl PeriodStats {
    // add one period
    pub fn add(&mut self, period_ps: u64) {
        let x = period_ps as f64;
        self.n += 1;
        let delta = x - self.mean;
        self.mean += delta / self.n as f64;
        self.m2 += delta * (x - self.mean);
        self.min_ps = if self.n == 1 {
            period_ps
        } else {
            self.min_ps.min(period_ps)
        };
        self.max_ps = self.max_ps.max(period_ps);
    }

    // fold another set of periods into this one (Chan et al.)
    pub fn merge(&mut self, other: &PeriodStats) {
        if other.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *other;
            return;
        }
        let n = (self.n + other.n) as f64;
        let delta = other.mean - self.mean;
        self.m2 += other.m2 + delta * delta * self.n as f64 * other.n as f64 / n;
        self.mean += delta * other.n as f64 / n;
        self.n += other.n;
        self.min_ps = self.min_ps.min(other.min_ps);
        self.max_ps = self.max_ps.max(other.max_ps);
    }

    // mean period, if any
    pub fn mean_ps(&self) -> Option<f64> {
        (self.n > 0).then_some(self.mean)
    }

    // population standard deviation of the periods
    pub fn std_dev_ps(&self) -> Option<f64> {
        (self.n > 0).then(|| (self.m2 / self.n as f64).max(0.0).sqrt())
    }

    // longest minus shortest period
    pub fn spread_ps(&self) -> Option<u64> {
        (self.n > 0).then(|| self.max_ps - self.min_ps)
    }
}

/// One time bin of one axis.
#[derive(Clone, Copy, Debug, Default)]
struct Bin {
    rises: u64,
    periods: PeriodStats,
    /// First period ending in this bin: it also spans the empty bins before.
    first_period_ps: u64,
}

/// Step counts and periods of one axis, binned over capture time.
#[derive(Clone, Debug, Default)]
pub struct RateBins {
    bins: Vec<Bin>,
    last_rise_ps: Option<u64>,
}

impl RateBins {
    // record a rising step edge that falls into bin `index`
    pub fn rise(&mut self, time_ps: u64, index: usize) {
        if self.bins.len() <= index {
            self.bins.resize(index + 1, Bin::default());
        }
        let bin = &mut self.bins[index];
        bin.rises += 1;
        if let Some(last) = self.last_rise_ps {
            let period = time_ps - last;
            if bin.periods.n == 0 {
                bin.first_period_ps = period;
            }
            bin.periods.add(period);
        }
        self.last_rise_ps = Some(time_ps);
    }

    // merge bins pairwise (bin width doubles)
    pub fn coarsen(&mut self) {
        let merged = self
            .bins
            .chunks(2)
            .map(|pair| {
                let mut bin = pair[0];
                if let Some(second) = pair.get(1) {
                    if bin.periods.n == 0 {
                        bin.first_period_ps = second.first_period_ps;
                    }
                    bin.rises += second.rises;
                    bin.periods.merge(&second.periods);
                }
                bin
            })
            .collect();
        self.bins = merged;
    }

    // step rate in Hz of each of the first `len` bins
    pub fn rates_hz(&self, len: usize) -> Vec<f64> {
        let mut rates = vec![0.0; len];
        // Walk backwards so an empty bin can take the period that spans it.
        let mut spanning: Option<u64> = None;
        for i in (0..len).rev() {
            let Some(bin) = self.bins.get(i) else {
                continue;
            };
            rates[i] = match bin.periods.mean_ps() {
                Some(mean) => 1e12 / mean,
                None => spanning.map_or(0.0, |p| 1e12 / p as f64),
            };
            if bin.periods.n > 0 {
                spanning = Some(bin.first_period_ps);
            }
            if bin.rises > 0 && bin.periods.n == 0 {
                // The first step of a run: nothing before it spans back.
                spanning = None;
            }
        }
        rates
    }

    // period statistics over a range of bins
    pub fn stats(&self, range: Range<usize>) -> PeriodStats {
        let mut stats = PeriodStats::default();
        for bin in self.bins.iter().take(range.end).skip(range.start) {
            stats.merge(&bin.periods);
        }
        stats
    }

    // rising edges counted up to the end of each of the first `len` bins
    pub fn cumulative_rises(&self, len: usize) -> Vec<u64> {
        let mut total = 0;
        (0..len)
            .map(|i| {
                total += self.bins.get(i).map_or(0, |b| b.rises);
                total
            })
            .collect()
    }

    // number of bins in use
    pub fn len(&self) -> usize {
        self.bins.len()
    }
}

/// Longest run of bins whose rate is at least `fraction` of the highest rate.
pub fn cruise_bins(rates: &[f64], fraction: f64) -> Option<Range<usize>> {
    let max = rates.iter().copied().fold(0.0, f64::max);
    if max <= 0.0 {
        return None;
    }
    let floor = max * fraction;
    let mut best: Option<Range<usize>> = None;
    let mut start = None;
    for (i, &rate) in rates.iter().chain(std::iter::once(&0.0)).enumerate() {
        match (rate >= floor, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                if best.as_ref().is_none_or(|b| i - s > b.len()) {
                    best = Some(s..i);
                }
                start = None;
            }
            _ => {}
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_merge_matches_one_pass() {
        let periods = [20_000u64, 20_100, 19_900, 20_000, 20_300, 19_700];
        let mut all = PeriodStats::default();
        periods.iter().for_each(|&p| all.add(p));
        let (mut a, mut b) = (PeriodStats::default(), PeriodStats::default());
        periods[..2].iter().for_each(|&p| a.add(p));
        periods[2..].iter().for_each(|&p| b.add(p));
        a.merge(&b);
        assert_eq!(a.n, 6);
        assert!((a.std_dev_ps().unwrap() - all.std_dev_ps().unwrap()).abs() < 1e-6);
        assert_eq!(a.spread_ps(), Some(600));
    }

    #[test]
    fn rate_is_exact_for_a_rate_that_does_not_divide_1khz() {
        // 30 kHz: 33_333_333 ps period, 30 or 31 steps per bin.
        let mut bins = RateBins::default();
        for k in 0..300u64 {
            let t = k * 33_333_333;
            bins.rise(t, (t / BIN_PS) as usize);
        }
        let rates = bins.rates_hz(9);
        assert!(
            rates[1..].iter().all(|r| (r - 30_000.0).abs() < 0.01),
            "{rates:?}"
        );
    }

    #[test]
    fn empty_bins_take_the_spanning_period() {
        // 400 Hz: one step every 2.5 ms.
        let mut bins = RateBins::default();
        for k in 0..5u64 {
            let t = k * 2_500_000_000;
            bins.rise(t, (t / BIN_PS) as usize);
        }
        let rates = bins.rates_hz(12);
        assert!(
            rates[..11].iter().all(|r| (r - 400.0).abs() < 1e-6),
            "{rates:?}"
        );
        assert_eq!(rates[11], 0.0);
    }

    #[test]
    fn cruise_is_the_longest_run_near_the_top() {
        let rates = [1.0, 50.0, 49.8, 10.0, 50.0, 50.0, 49.9, 49.0, 0.0];
        assert_eq!(cruise_bins(&rates, 0.99), Some(4..7));
        assert_eq!(cruise_bins(&[0.0, 0.0], 0.99), None);
    }
}
