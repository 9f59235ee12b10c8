//! What `--serve` records for `--vcd` and `--json` while it runs, without keeping the board's
//! pin edges: each turn takes them off the board, writes them to the VCD and folds them into
//! the report's edge figures. For the serve loop (and tests that drive a board the same way).

use std::path::Path;

use anyhow::Result;

use crate::emu::summary::EdgeSummary;
use crate::emu::vcd_out::VcdStream;
use crate::emu::{Board, PinEdge, Report};

/// The VCD being written and the JSON's edge figures, as asked.
pub struct Recorder {
    vcd: Option<VcdStream>,
    sum: Option<EdgeSummary>,
    /// PWM changes already written to the VCD (the board keeps those: one per spindle change).
    pwm_mark: usize,
}

impl Recorder {
    // start recording a board: a VCD at `vcd`, the report's edge figures when `report`
    pub fn new(board: &Board, vcd: Option<&Path>, report: bool) -> Result<Self> {
        Ok(Self { vcd: vcd.map(VcdStream::create).transpose()?, sum: report.then(|| EdgeSummary::new(board.dual_edge)), pwm_mark: 0 })
    }

    // take the edges and move ends the board recorded since the last turn off it, record them,
    // and hand the edges over (the status line counts steps from them)
    pub fn turn(&mut self, board: &mut Board) -> Result<Vec<PinEdge>> {
        let (ends, edges) = (board.take_move_ends(), board.take_edges());
        if let Some(v) = self.vcd.as_mut() {
            v.feed(&edges, &board.pwm_changes()[self.pwm_mark..])?;
            self.pwm_mark = board.pwm_changes().len();
        }
        if let Some(sum) = self.sum.as_mut() {
            sum.move_ends(&ends);
            sum.edges(&edges);
        }
        Ok(edges)
    }

    // close the VCD; the report, when asked
    pub fn finish(mut self, board: &mut Board) -> Result<Option<Report>> {
        self.turn(board)?;
        if let Some(v) = self.vcd {
            v.finish(board.cycles())?;
        }
        Ok(self.sum.map(|s| board.report_from(s)))
    }
}
