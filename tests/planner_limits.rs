//! The planner never asks the step interrupt for more than it sustains: the ceiling falls
//! with every slave axis a move adds (`Timing::max_rate_for`).

use ddastep::planning::planner::Planner;
use ddastep::motion::ramp::hz_of_period;
use ddastep::grbl::settings::Settings;

#[test]
fn cruise_is_clamped_to_the_ceiling_for_the_moves_axis_count() {
    let mut s = Settings::BENCH;
    s.set(0, 0.5, 7).unwrap();
    for i in 0..7 {
        s.set(110 + i, 600_000.0, 7).unwrap();
    }
    let t = s.timing();
    let lim = s.planner_limits::<7>(1_000_000);
    for axes in 1..=7usize {
        let mut p = Planner::<7>::new();
        let target: [f32; 7] = core::array::from_fn(|i| if i < axes { 100.0 - i as f32 } else { 0.0 });
        let planned = p.line(&target, Some(1e7), &lim).unwrap().unwrap();
        let hz = hz_of_period(planned.mv.cruise());
        let ceiling = t.max_rate_for(axes as u32 - 1) as f32;
        assert!(hz <= ceiling * 1.0001 && hz >= ceiling * 0.999, "{axes} axes: {hz} Hz vs {ceiling}");
    }
    assert!(t.max_rate_for(6) < t.max_rate_for(0));
}

/// In DMA burst mode a move change runs inside one buffer fill: junctions joined at speed are
/// clamped to the mode's junction rate on both sides (`Timing::max_junction_rate_for`, the
/// more slaves of the two moves), straight on as at a corner; the moves' own cruise keeps the
/// move's cap. Interrupt mode has no junction limit of its own (the moves' caps bind).
#[test]
fn dma_junctions_are_clamped_to_the_junction_rate() {
    use ddastep::motion::timing::{DMA_JUNCTION_BASE_TICKS, DMA_JUNCTION_PER_SLAVE_TICKS};
    for dma in [true, false] {
        let mut s = Settings { dma_burst: dma, ..Settings::BENCH };
        s.set(0, 0.5, 7).unwrap();
        for i in 0..7 {
            s.set(110 + i, 600_000.0, 7).unwrap();
            s.set(120 + i, 1e6, 7).unwrap();
        }
        let t = s.timing();
        for slaves in [0u32, 2, 6] {
            let want = if dma { t.max_rate_for(slaves).min(ddastep::TIMER_HZ / (DMA_JUNCTION_BASE_TICKS + DMA_JUNCTION_PER_SLAVE_TICKS * slaves)) } else { u32::MAX };
            assert_eq!(t.max_junction_rate_for(slaves), want, "dma {dma}, {slaves} slaves");
        }
        let lim = s.planner_limits::<7>(1_000_000);
        for axes in [1usize, 3, 7] {
            let mut p = Planner::<7>::new();
            let mut last = None;
            for k in 1..=3 {
                // Straight on: the same direction three times.
                let pos: [f32; 7] = core::array::from_fn(|i| if i < axes { 20.0 * k as f32 * (1.0 + i as f32 / 10.0) } else { 0.0 });
                last = Some(p.line(&pos, Some(1e7), &lim).unwrap().unwrap());
            }
            let planned = last.unwrap();
            let path = planned.mv.path().unwrap();
            let cruise = hz_of_period(planned.mv.cruise());
            let jcap = t.max_junction_rate_for(axes as u32 - 1) as f32;
            // The master's rate at the junction, from the path speed.
            let at_junction = path.junction * path.share;
            if dma {
                assert!(at_junction <= jcap * 1.0001 && at_junction >= jcap * 0.999, "{axes} axes: junction {at_junction} Hz vs {jcap}");
                assert!(cruise > jcap, "{axes} axes: cruise {cruise} Hz above the junction cap {jcap}");
            } else {
                assert!(at_junction >= cruise * 0.999, "{axes} axes: junction {at_junction} Hz, cruise {cruise}");
            }
        }
    }
}
