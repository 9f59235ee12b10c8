//! Slave deviation from the ideal line, in constant memory while streaming.
//!
//! For master axis m with final count M and slave s with final count c, the deviation at the
//! master's k-th step is `s_k - k·c/M`, where `s_k` is the slave count once every edge of that
//! timestamp is applied. `c/M` is only known at the end, so for every ordered axis pair the
//! points `(k, s_k)` are kept as their upper and lower convex hulls (monotone chain: points
//! arrive with increasing k). `max_k (s_k - k·r)` is reached at an upper-hull vertex and
//! `min_k` at a lower-hull vertex for any r, so the answer is exact. A DDA slave lies within
//! one step of a line, so its hulls stay a handful of points.

/// Upper and lower convex hulls of points with increasing x.
#[derive(Clone, Debug, Default)]
struct Hull {
    upper: Vec<(i64, i64)>,
    lower: Vec<(i64, i64)>,
}

// z of (a - o) × (b - o): > 0 for a left turn
fn cross(o: (i64, i64), a: (i64, i64), b: (i64, i64)) -> i128 {
    let (ax, ay) = ((a.0 - o.0) as i128, (a.1 - o.1) as i128);
    let (bx, by) = ((b.0 - o.0) as i128, (b.1 - o.1) as i128);
    ax * by - ay * bx
}

impl Hull {
    // add a point right of every earlier one
    fn push(&mut self, p: (i64, i64)) {
        while self.upper.len() >= 2
            && cross(
                self.upper[self.upper.len() - 2],
                self.upper[self.upper.len() - 1],
                p,
            ) >= 0
        {
            self.upper.pop();
        }
        self.upper.push(p);
        while self.lower.len() >= 2
            && cross(
                self.lower[self.lower.len() - 2],
                self.lower[self.lower.len() - 1],
                p,
            ) <= 0
        {
            self.lower.pop();
        }
        self.lower.push(p);
    }

    // max over points of |y - x·c/m|, in steps
    fn max_abs_offset(&self, c: i64, m: i64) -> f64 {
        let (c, m) = (c as i128, m as i128);
        let scaled = |&(x, y): &(i64, i64)| y as i128 * m - x as i128 * c;
        let above = self.upper.iter().map(scaled).max().unwrap_or(0);
        let below = self.lower.iter().map(scaled).min().unwrap_or(0);
        above.max(-below).max(0) as f64 / m as f64
    }
}

/// Hulls of every ordered (master, slave) pair of axes.
#[derive(Clone, Debug)]
pub struct DeviationTracker {
    axes: usize,
    hulls: Vec<Hull>,
}

impl DeviationTracker {
    // create a tracker for `axes` axes
    pub fn new(axes: usize) -> Self {
        Self {
            axes,
            hulls: vec![Hull::default(); axes * axes],
        }
    }

    // record the counts of every axis at a step of `master`
    pub fn master_step(&mut self, master: usize, counts: &[u64]) {
        let k = counts[master] as i64;
        for (slave, &count) in counts.iter().enumerate().filter(|&(s, _)| s != master) {
            self.hulls[master * self.axes + slave].push((k, count as i64));
        }
    }

    // largest |slave - ideal| over the master's steps, using the final counts
    pub fn max_deviation(&self, master: usize, slave: usize, counts: &[u64]) -> f64 {
        let (m, c) = (counts[master] as i64, counts[slave] as i64);
        if m == 0 {
            return 0.0;
        }
        self.hulls[master * self.axes + slave].max_abs_offset(c, m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // brute-force maximum deviation for a slave sequence
    fn brute(slave: &[i64]) -> f64 {
        let (m, c) = (slave.len() as f64, *slave.last().unwrap_or(&0) as f64);
        slave
            .iter()
            .enumerate()
            .map(|(i, &s)| (s as f64 - (i + 1) as f64 * c / m).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn bresenham_slave_stays_within_one_step() {
        // 5:3 Bresenham, slave steps at the master step where the error wraps.
        let mut tracker = DeviationTracker::new(2);
        let mut slave = Vec::new();
        let (mut s, mut err) = (0u64, 0i64);
        for k in 1..=50u64 {
            err += 3;
            if 2 * err >= 5 {
                err -= 5;
                s += 1;
            }
            slave.push(s as i64);
            tracker.master_step(0, &[k, s]);
        }
        let got = tracker.max_deviation(0, 1, &[50, s]);
        assert!(
            (got - brute(&slave)).abs() < 1e-12,
            "{got} vs {}",
            brute(&slave)
        );
        assert!(got <= 0.5 + 1e-12);
    }

    #[test]
    fn hull_matches_brute_force_on_a_lagging_slave() {
        let slave: Vec<i64> = (1..=40)
            .map(|k: i64| if k < 20 { k / 4 } else { k - 10 })
            .collect();
        let mut tracker = DeviationTracker::new(2);
        for (i, &s) in slave.iter().enumerate() {
            tracker.master_step(0, &[(i + 1) as u64, s as u64]);
        }
        let counts = [40, *slave.last().unwrap() as u64];
        assert!((tracker.max_deviation(0, 1, &counts) - brute(&slave)).abs() < 1e-12);
    }
}
