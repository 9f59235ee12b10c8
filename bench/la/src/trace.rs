//! The mapped axes' step and dir lines kept in memory, for the pictures ([`crate::pulses`]
//! waveforms, [`crate::path`] the XY path): each step line's level changes and each rising
//! step edge with its direction. A second pass over a capture, after the checker's.

use crate::analysis::AxisChannels;
use crate::levels::Sink;

/// One axis's lines.
#[derive(Clone, Debug, Default)]
pub struct AxisTrace {
    pub name: String,
    /// Step line level changes (time in ps, new level), the first entry the initial level.
    pub step_levels: Vec<(u64, bool)>,
    /// Rising step edges (time in ps, +1 or -1 from the dir line).
    pub steps: Vec<(u64, i8)>,
    dir: bool,
}

/// Every mapped axis, in ratio order.
#[derive(Clone, Debug)]
pub struct Trace {
    pub axes: Vec<AxisTrace>,
    channels: Vec<AxisChannels>,
    dir_invert: bool,
    pub end_ps: u64,
}

impl Trace {
    // an empty trace of `channels`; `dir_invert`: dir low means +
    pub fn new(channels: &[AxisChannels], dir_invert: bool) -> Self {
        let axes = channels.iter().map(|c| AxisTrace { name: c.name.clone(), ..AxisTrace::default() }).collect();
        Trace { axes, channels: channels.to_vec(), dir_invert, end_ps: 0 }
    }

    /// Time of the first rising step edge of any axis.
    pub fn first_step_ps(&self) -> Option<u64> {
        self.axes.iter().filter_map(|a| a.steps.first().map(|s| s.0)).min()
    }
}

impl Sink for Trace {
    // keep step level changes and rising edges; follow dir
    fn level(&mut self, time_ps: u64, channel: usize, level: bool) {
        for (a, c) in self.axes.iter_mut().zip(&self.channels) {
            if c.dir == Some(channel) {
                a.dir = level;
            }
            if c.step != channel {
                continue;
            }
            match a.step_levels.last() {
                Some(&(_, was)) if was == level => {}
                Some(_) => {
                    a.step_levels.push((time_ps, level));
                    if level {
                        let plus = a.dir != self.dir_invert || c.dir.is_none();
                        a.steps.push((time_ps, if plus { 1 } else { -1 }));
                    }
                }
                None => a.step_levels.push((time_ps, level)),
            }
        }
    }

    // keep the latest time
    fn advance(&mut self, time_ps: u64) {
        self.end_ps = self.end_ps.max(time_ps);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rising_edges_take_the_dir_level_and_the_first_level_is_no_edge() {
        let mut t = Trace::new(&[AxisChannels::new("X", 0, Some(1))], true);
        t.level(0, 0, true); // initial level: no step
        t.level(0, 1, true); // dir high: minus with dir_invert
        t.level(10, 0, false);
        t.level(20, 0, true);
        t.level(20, 0, true); // a repeat is no edge
        t.level(25, 1, false);
        t.level(30, 0, false);
        t.level(40, 0, true);
        assert_eq!(t.axes[0].steps, vec![(20, -1), (40, 1)]);
        assert_eq!(t.axes[0].step_levels.len(), 5);
        assert_eq!(t.first_step_ps(), Some(20));
    }
}
