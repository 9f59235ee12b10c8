//! Glitch filter: turns raw level reports into confirmed edges, in time order. Used by
//! [`Analyzer`](super::Analyzer) only; the rules below are what makes a capture check the same
//! way every time.
//!
//! - A channel's first reported level is its level at capture start, never an edge. A capture
//!   that starts mid-pulse therefore counts neither a rising edge nor a pulse width for it.
//! - Reporting the level a channel already has is ignored (CSV rows, VCD `$dumpvars`, repeats).
//! - A pulse narrower than `min_width_ps` is a glitch: both of its edges are dropped and
//!   counted per channel. `min_width_ps` is at least 1 ps, so a change and back at the same
//!   timestamp (narrower than one sample) is always a glitch; wider pulses are glitches only
//!   when `--min-glitch-ns` asks for it.
//! - An edge is confirmed once input time has moved `min_width_ps` past it; confirmed edges
//!   leave in time order, edges of one timestamp in the order they were reported.

use std::collections::VecDeque;

/// A confirmed level change of one channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    pub time_ps: u64,
    pub channel: usize,
    pub level: bool,
}

/// What one level report did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Observed {
    /// First level of the channel: its state at capture start.
    Initial,
    /// Same level as before: nothing happened.
    Repeat,
    /// A change, waiting for confirmation.
    Queued,
    /// A change back within `min_width_ps`: the pulse was dropped.
    Glitch,
}

/// One channel's latest level and whether its last change is still unconfirmed.
#[derive(Clone, Copy, Default)]
struct Line {
    level: Option<bool>,
    pending: bool,
}

/// Per-channel deglitching with one time-ordered queue of unconfirmed edges.
pub struct GlitchFilter {
    min_width_ps: u64,
    lines: Vec<Line>,
    queue: VecDeque<Edge>,
    glitches: Vec<u64>,
}

impl GlitchFilter {
    // create a filter for `channels` channels, all levels unknown
    pub fn new(channels: usize, min_width_ps: u64) -> Self {
        Self {
            min_width_ps: min_width_ps.max(1),
            lines: vec![Line::default(); channels],
            queue: VecDeque::new(),
            glitches: vec![0; channels],
        }
    }

    // take one level report; the caller has confirmed everything up to `time_ps` first
    pub fn observe(&mut self, time_ps: u64, channel: usize, level: bool) -> Observed {
        let line = &mut self.lines[channel];
        match line.level {
            None => {
                line.level = Some(level);
                Observed::Initial
            }
            Some(old) if old == level => Observed::Repeat,
            Some(_) => {
                line.level = Some(level);
                if line.pending {
                    // The queued edge is younger than the minimum width: drop both edges.
                    line.pending = false;
                    if let Some(i) = self.queue.iter().rposition(|e| e.channel == channel) {
                        self.queue.remove(i);
                    }
                    self.glitches[channel] += 1;
                    Observed::Glitch
                } else {
                    line.pending = true;
                    self.queue.push_back(Edge {
                        time_ps,
                        channel,
                        level,
                    });
                    Observed::Queued
                }
            }
        }
    }

    // move edges that are at least the minimum width old at `now_ps` to `out`
    pub fn confirm(&mut self, now_ps: u64, out: &mut Vec<Edge>) {
        while let Some(&edge) = self.queue.front() {
            if now_ps.saturating_sub(edge.time_ps) < self.min_width_ps {
                break;
            }
            self.confirm_front(edge, out);
        }
    }

    // move every queued edge to `out` (end of capture)
    pub fn confirm_all(&mut self, out: &mut Vec<Edge>) {
        while let Some(&edge) = self.queue.front() {
            self.confirm_front(edge, out);
        }
    }

    // number of dropped pulses on `channel`
    pub fn glitches(&self, channel: usize) -> u64 {
        self.glitches.get(channel).copied().unwrap_or(0)
    }

    // pop the queue front into `out`
    fn confirm_front(&mut self, edge: Edge, out: &mut Vec<Edge>) {
        self.queue.pop_front();
        self.lines[edge.channel].pending = false;
        out.push(edge);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // run reports through a filter, confirming as time passes, and return the edges
    fn run(min_width_ps: u64, reports: &[(u64, usize, bool)]) -> (Vec<Edge>, u64) {
        let mut filter = GlitchFilter::new(2, min_width_ps);
        let mut out = Vec::new();
        for &(t, ch, level) in reports {
            filter.confirm(t, &mut out);
            filter.observe(t, ch, level);
        }
        filter.confirm_all(&mut out);
        (out, filter.glitches(0) + filter.glitches(1))
    }

    #[test]
    fn first_level_is_not_an_edge() {
        let (edges, glitches) = run(0, &[(0, 0, true), (10, 0, false), (20, 0, false)]);
        assert_eq!(
            edges,
            vec![Edge {
                time_ps: 10,
                channel: 0,
                level: false
            }]
        );
        assert_eq!(glitches, 0);
    }

    #[test]
    fn change_and_back_at_one_timestamp_is_a_glitch() {
        let (edges, glitches) = run(
            0,
            &[(0, 0, false), (5, 0, true), (5, 0, false), (9, 0, true)],
        );
        assert_eq!(
            edges,
            vec![Edge {
                time_ps: 9,
                channel: 0,
                level: true
            }]
        );
        assert_eq!(glitches, 1);
    }

    #[test]
    fn pulses_narrower_than_min_width_are_dropped_in_time_order() {
        let reports = [
            (0, 0, false),
            (0, 1, false),
            (100, 0, true),
            (120, 1, true), // 10 ps pulse: glitch at min width 50
            (130, 1, false),
            (200, 0, false), // 100 ps pulse: kept
        ];
        let (edges, glitches) = run(50, &reports);
        let times: Vec<_> = edges
            .iter()
            .map(|e| (e.time_ps, e.channel, e.level))
            .collect();
        assert_eq!(times, vec![(100, 0, true), (200, 0, false)]);
        assert_eq!(glitches, 1);
    }
}
