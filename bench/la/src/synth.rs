//! Synthetic step/dir traces written as bench-style VCDs (`$timescale 1 ns`, `X_STEP`, `X_DIR`,
//! ..., `EN`, vcd crate writer): known inputs for the checker's tests, property tests and
//! throughput benchmark. Not used by the checker itself.

use std::io::{self, Write};

use vcd::{IdCode, TimescaleUnit, Value};

/// One step pulse.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pulse {
    pub rise_ns: u64,
    pub width_ns: u64,
}

/// Step and dir activity of one axis.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AxisTrace {
    pub name: String,
    /// Dir level at time 0.
    pub dir_start: bool,
    /// Times at which dir toggles.
    pub dir_toggles_ns: Vec<u64>,
    /// Pulses in time order, not overlapping.
    pub pulses: Vec<Pulse>,
}

// a coordinated move: the axis with most steps steps every `period_ns` from `start_ns`, the
// others step at the same instants by Bresenham (accumulator starting at half the master count)
pub fn dda_move(
    names: &[&str],
    counts: &[u64],
    start_ns: u64,
    period_ns: u64,
    width_ns: u64,
) -> Vec<AxisTrace> {
    let master = counts.iter().copied().max().unwrap_or(0);
    let mut accumulators = vec![master / 2; counts.len()];
    let mut axes: Vec<AxisTrace> = names
        .iter()
        .map(|n| AxisTrace {
            name: n.to_string(),
            dir_start: true,
            ..AxisTrace::default()
        })
        .collect();
    for k in 0..master {
        let rise_ns = start_ns + k * period_ns;
        for (i, &count) in counts.iter().enumerate() {
            accumulators[i] += count;
            if accumulators[i] >= master {
                accumulators[i] -= master;
                axes[i].pulses.push(Pulse { rise_ns, width_ns });
            }
        }
    }
    axes
}

// write `axes` as a bench VCD that ends at `end_ns`
pub fn write_vcd(axes: &[AxisTrace], end_ns: u64, out: impl Write) -> io::Result<()> {
    let mut w = vcd::Writer::new(io::BufWriter::new(out));
    w.timescale(1, TimescaleUnit::NS)?;
    w.add_module("ddastep")?;
    let mut ids: Vec<(IdCode, IdCode)> = Vec::new();
    for axis in axes {
        ids.push((
            w.add_wire(1, &format!("{}_STEP", axis.name))?,
            w.add_wire(1, &format!("{}_DIR", axis.name))?,
        ));
    }
    let enable = w.add_wire(1, "EN")?;
    w.upscope()?;
    w.enddefinitions()?;

    let mut events: Vec<(u64, IdCode, bool)> = Vec::new();
    for (axis, &(step, dir)) in axes.iter().zip(&ids) {
        for p in &axis.pulses {
            events.push((p.rise_ns, step, true));
            events.push((p.rise_ns + p.width_ns, step, false));
        }
        let mut level = axis.dir_start;
        for &t in &axis.dir_toggles_ns {
            level = !level;
            events.push((t, dir, level));
        }
    }
    events.sort_by_key(|e| e.0);

    w.timestamp(0)?;
    w.begin(vcd::SimulationCommand::Dumpvars)?;
    for (axis, &(step, dir)) in axes.iter().zip(&ids) {
        w.change_scalar(step, Value::V0)?;
        w.change_scalar(dir, if axis.dir_start { Value::V1 } else { Value::V0 })?;
    }
    w.change_scalar(enable, Value::V0)?;
    w.end()?;
    let mut now = 0;
    for (t, id, level) in events {
        if t != now {
            w.timestamp(t)?;
            now = t;
        }
        w.change_scalar(id, if level { Value::V1 } else { Value::V0 })?;
    }
    if end_ns > now {
        w.timestamp(end_ns)?;
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dda_move_spreads_slave_steps() {
        let axes = dda_move(&["X", "Y", "Z"], &[5, 3, 2], 0, 10, 2);
        let rises = |i: usize| axes[i].pulses.iter().map(|p| p.rise_ns).collect::<Vec<_>>();
        assert_eq!(rises(0), vec![0, 10, 20, 30, 40]);
        assert_eq!(rises(1), vec![0, 20, 40]);
        assert_eq!(rises(2), vec![10, 30]);
    }
}
