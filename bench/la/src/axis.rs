//! One axis's step/dir state: step counts, net position, pulse widths, dir setup and hold.
//! Fed confirmed edges by [`Analyzer`](super::Analyzer); all times in picoseconds.
//!
//! Widths only count between two observed edges: the level a channel starts with is never a
//! pulse, so a capture that starts mid-pulse (or ends mid-pulse) measures nothing for it.
//! Dir setup is the time from a dir change to the next rising step edge; dir hold is the time
//! from the last rising step edge to a dir change. Steps without a dir change before them
//! measure no setup. In dual-edge mode (drivers that step on both edges) every edge of a step
//! line is a step: setup and hold are measured to and from any edge, and the high and low
//! times are the spacing between two toggles.

use super::rate::RateBins;

/// Smallest of an optional minimum and a new value.
fn min_of(current: Option<u64>, value: u64) -> Option<u64> {
    Some(current.map_or(value, |c| c.min(value)))
}

/// Timing minima of one axis, in picoseconds (`None`: never measured).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AxisTiming {
    pub min_high_ps: Option<u64>,
    pub min_low_ps: Option<u64>,
    pub min_dir_setup_ps: Option<u64>,
    pub min_dir_hold_ps: Option<u64>,
}

/// Running state of one axis.
#[derive(Clone, Debug, Default)]
pub struct AxisState {
    dir_invert: bool,
    dual_edge: bool,
    dir: Option<bool>,
    pub rises: u64,
    pub net: i64,
    pub dir_changes: u64,
    last_rise_ps: Option<u64>,
    last_fall_ps: Option<u64>,
    last_step_ps: Option<u64>,
    dir_changed_ps: Option<u64>,
    pub timing: AxisTiming,
    pub bins: RateBins,
}

impl AxisState {
    // create an axis whose dir high means + (or - with `dir_invert`); with `dual_edge` both
    // edges of its step line are steps
    pub fn new(dir_invert: bool, dual_edge: bool) -> Self {
        Self {
            dir_invert,
            dual_edge,
            ..Self::default()
        }
    }

    // take the dir level at capture start
    pub fn initial_dir(&mut self, level: bool) {
        self.dir = Some(level);
    }

    // apply a confirmed dir change
    pub fn dir_edge(&mut self, time_ps: u64, level: bool) {
        self.dir = Some(level);
        self.dir_changes += 1;
        self.dir_changed_ps = Some(time_ps);
        if let Some(step) = self.last_step_ps {
            self.timing.min_dir_hold_ps = min_of(self.timing.min_dir_hold_ps, time_ps - step);
        }
    }

    // apply a confirmed step change; true when it was a step (a rising edge, or any edge in
    // dual-edge mode)
    pub fn step_edge(&mut self, time_ps: u64, level: bool, bin: usize) -> bool {
        if !level {
            if let Some(rise) = self.last_rise_ps {
                self.timing.min_high_ps = min_of(self.timing.min_high_ps, time_ps - rise);
            }
            self.last_fall_ps = Some(time_ps);
            if !self.dual_edge {
                return false;
            }
        } else {
            if let Some(fall) = self.last_fall_ps {
                self.timing.min_low_ps = min_of(self.timing.min_low_ps, time_ps - fall);
            }
            self.last_rise_ps = Some(time_ps);
        }
        if let Some(changed) = self.dir_changed_ps.take() {
            self.timing.min_dir_setup_ps = min_of(self.timing.min_dir_setup_ps, time_ps - changed);
        }
        self.rises += 1;
        // No dir channel (or no level yet) counts as +.
        let positive = self.dir.is_none_or(|d| d != self.dir_invert);
        self.net += if positive { 1 } else { -1 };
        self.last_step_ps = Some(time_ps);
        self.bins.rise(time_ps, bin);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_setup_and_hold() {
        let mut axis = AxisState::new(false, false);
        axis.initial_dir(true);
        assert!(axis.step_edge(1_000, true, 0));
        axis.step_edge(3_000, false, 0); // high 2000
        axis.dir_edge(4_000, false); // hold 3000
        assert!(axis.step_edge(4_500, true, 0)); // low 1500, setup 500
        axis.step_edge(7_000, false, 0); // high 2500
        assert!(axis.step_edge(9_000, true, 0)); // low 2000, no setup
        assert_eq!(axis.rises, 3);
        assert_eq!(axis.net, 1 - 2);
        assert_eq!(
            axis.timing,
            AxisTiming {
                min_high_ps: Some(2_000),
                min_low_ps: Some(1_500),
                min_dir_setup_ps: Some(500),
                min_dir_hold_ps: Some(3_000),
            }
        );
    }

    #[test]
    fn starting_mid_pulse_measures_no_width() {
        let mut axis = AxisState::new(true, false);
        // The channel started high: its first change is a fall, not the end of a pulse.
        assert!(!axis.step_edge(500, false, 0));
        assert_eq!(axis.timing.min_high_ps, None);
        assert!(axis.step_edge(900, true, 0));
        assert_eq!(axis.timing.min_low_ps, Some(400));
        assert_eq!((axis.rises, axis.net), (1, 1), "no dir level: +");
    }

    #[test]
    fn dual_edge_counts_both_edges_and_their_spacing() {
        let mut axis = AxisState::new(false, true);
        axis.initial_dir(true);
        assert!(axis.step_edge(1_000, true, 0));
        assert!(axis.step_edge(1_800, false, 0)); // spacing 800
        axis.dir_edge(2_000, false); // hold 200 after the falling step
        assert!(axis.step_edge(2_300, true, 0)); // spacing 500, setup 300
        assert!(axis.step_edge(3_000, false, 0)); // spacing 700
        assert_eq!((axis.rises, axis.net), (4, 2 - 2));
        assert_eq!(
            axis.timing,
            AxisTiming {
                min_high_ps: Some(700),
                min_low_ps: Some(500),
                min_dir_setup_ps: Some(300),
                min_dir_hold_ps: Some(200),
            }
        );
    }
}
