//! What the report needs of the pin edges, kept while they stream: the `la` checker's per-axis
//! figures, the slave deviation per move and the tool pins' rises, in memory that does not grow
//! with the edges. `Board::report` feeds it every edge at once; `--serve` feeds it each slice's
//! edges and forgets them.
//!
//! Slave deviation per move: the engine's moves are straight lines, each with its own ratio,
//! so the deviation is measured per move (a job of many moves, arcs above all, is no straight
//! line). The bench learns where a move ends from the firmware itself: the step half's
//! `finish` runs in the tick that prepares a move's last step (`Board::move_ends`), and that
//! step's edges go out at the next update event, so a move ends with the first step edges
//! after its `finish`; a pause of 50 ms without steps ends one too (a move a stop dropped never
//! finishes). In DMA burst mode the fill runs the engine ahead of the pins, so this
//! does not hold: there the figure is left out when the run has more than one move.

use super::clock::HZ;
use super::gpio::PinEdge;
use super::pinmap::{AXES, DIR_LOW_IS_POSITIVE, DIR_PINS, STEP_PINS, TOOL_PINS};
use crate::la::{Analyzer, AxisChannels, Config, DeviationTracker, Report as LaReport};

// picoseconds of a modeled cycle count
pub(crate) fn ps(cycles: u64) -> u64 {
    (cycles as u128 * 1_000_000_000_000 / HZ as u128) as u64
}

/// The slave deviation of each move, folded into the run's largest.
struct MoveDeviation {
    /// Steps per axis in the running move, and their (master, slave) hulls.
    counts: [u64; 7],
    tracker: DeviationTracker,
    /// Move ends (`finish` cycles) by the step interrupt not yet reached by the pins; all
    /// move ends, and those from another context (DMA's fill: not placed on the pins).
    ends: std::collections::VecDeque<u64>,
    all_ends: u64,
    ahead: u64,
    /// Cycle of the last steps.
    last: u64,
    moves: u64,
    max: f64,
}

/// No step for this long (50 ms) ends a run of steps.
const PAUSE: u64 = HZ / 20;

impl MoveDeviation {
    fn new() -> Self {
        Self { counts: [0; 7], tracker: DeviationTracker::new(7), ends: Default::default(), all_ends: 0, ahead: 0, last: 0, moves: 0, max: 0.0 }
    }

    // one timestamp's steps (`stepped`: axes with a step at `cycle`)
    fn steps(&mut self, cycle: u64, stepped: [bool; 7]) {
        let mut ended = false;
        while self.ends.front().is_some_and(|&f| f < cycle) {
            self.ends.pop_front();
            ended = true;
        }
        // A pause also ends a run of steps: a move dropped by a stop (Ctrl-X, a jog cancel)
        // never finishes, and must not join the next one. (A feed hold splits a move in two,
        // each part within a step of its own line.)
        if !ended && cycle.saturating_sub(self.last) > PAUSE {
            self.close();
        }
        self.last = cycle;
        for (c, s) in self.counts.iter_mut().zip(stepped) {
            *c += s as u64;
        }
        for (axis, _) in stepped.iter().enumerate().filter(|(_, &s)| s) {
            self.tracker.master_step(axis, &self.counts);
        }
        if ended {
            self.close();
        }
    }

    // the running move is over: its deviation into the maximum, then start the next
    fn close(&mut self) {
        let c = &self.counts;
        if c.iter().any(|&n| n > 0) {
            // The master: the axis with the most steps, the first of equals (as `la`'s).
            let master = (0..7).max_by(|&a, &b| c[a].cmp(&c[b]).then(b.cmp(&a))).unwrap_or(0);
            let dev = (0..7).filter(|&s| s != master).map(|s| self.tracker.max_deviation(master, s, c)).fold(0.0, f64::max);
            self.max = self.max.max(dev);
            self.moves += 1;
        }
        self.counts = [0; 7];
        self.tracker = DeviationTracker::new(7);
    }

    // the largest per-move deviation and the moves; None when the move ends could not be
    // placed on the pins (some came from DMA's fill, and there were several)
    fn finish(mut self) -> (Option<f64>, u64) {
        self.close();
        if self.ahead > 0 && self.all_ends > 1 {
            return (None, self.all_ends);
        }
        (Some(self.max), self.moves)
    }
}

/// The report's edge-derived figures, kept incrementally.
pub struct EdgeSummary {
    la: Analyzer,
    dev: MoveDeviation,
    dual_edge: bool,
    /// The step timestamp being gathered: its cycle and the axes that stepped.
    batch: Option<(u64, [bool; 7])>,
    /// Rising edges of the tool pins (SPINDLE_EN, SPINDLE_DIR, FLOOD, MIST).
    pub tool_rises: [u64; 4],
}

/// What the summary gives the report.
pub struct EdgeFigures {
    pub la: LaReport,
    /// Largest slave deviation of any move (None: not computable, see the module docs).
    pub max_slave_deviation_steps: Option<f64>,
    /// Moves seen on the pins.
    pub moves: u64,
    pub tool_rises: [u64; 4],
}

impl EdgeSummary {
    // an empty summary (all pins low at cycle 0); `dual_edge`: both edges of a step pin are steps
    pub fn new(dual_edge: bool) -> Self {
        let channels = AXES.iter().enumerate().map(|(i, name)| AxisChannels::new(name, 2 * i, Some(2 * i + 1))).collect();
        let mut config = Config::new(channels);
        config.dir_invert = DIR_LOW_IS_POSITIVE;
        config.dual_edge = dual_edge;
        let mut la = Analyzer::new(config).expect("fixed channel map");
        for ch in 0..14 {
            la.edge(0, ch, false);
        }
        Self { la, dev: MoveDeviation::new(), dual_edge, batch: None, tool_rises: [0; 4] }
    }

    // the engine's move ends up to now (`Board::take_move_ends`), before the edges up to now
    pub fn move_ends(&mut self, ends: &[(u64, bool)]) {
        for &(cycle, by_step_isr) in ends {
            self.dev.all_ends += 1;
            match by_step_isr {
                true => self.dev.ends.push_back(cycle),
                false => self.dev.ahead += 1,
            }
        }
    }

    // pin edges in cycle order
    pub fn edges(&mut self, edges: &[PinEdge]) {
        for e in edges {
            match e.port {
                0 => {
                    if let (Some(i), true) = (TOOL_PINS.iter().position(|(p, _)| *p == e.pin), e.level) {
                        self.tool_rises[i] += 1;
                    }
                }
                1 => self.pin_b(e),
                _ => {}
            }
        }
    }

    fn pin_b(&mut self, e: &PinEdge) {
        let step = STEP_PINS.iter().position(|&p| p == e.pin);
        let ch = step.map(|a| 2 * a).or_else(|| DIR_PINS.iter().position(|&p| p == e.pin).map(|a| 2 * a + 1));
        let Some(ch) = ch else { return };
        self.la.edge(ps(e.cycle), ch, e.level);
        let Some(axis) = step else { return };
        if !(e.level || self.dual_edge) {
            return;
        }
        if self.batch.is_some_and(|(c, _)| c != e.cycle) {
            self.flush();
        }
        self.batch.get_or_insert((e.cycle, [false; 7])).1[axis] = true;
    }

    // apply the gathered timestamp's steps
    fn flush(&mut self) {
        if let Some((cycle, stepped)) = self.batch.take() {
            self.dev.steps(cycle, stepped);
        }
    }

    // the figures at cycle `now`
    pub fn finish(mut self, now: u64) -> EdgeFigures {
        self.flush();
        self.la.advance(ps(now));
        let (max_slave_deviation_steps, moves) = self.dev.finish();
        EdgeFigures { la: self.la.finish(), max_slave_deviation_steps, moves, tool_rises: self.tool_rises }
    }
}
