//! The planner never asks the step interrupt for more than it sustains: the ceiling falls
//! with every slave axis a move adds (`Timing::max_rate_for`).

use ddastep::planner::{Limits, Planner};
use ddastep::ramp::hz_of_period;
use ddastep::settings::Settings;

#[test]
fn cruise_is_clamped_to_the_ceiling_for_the_moves_axis_count() {
    let mut s = Settings::BENCH;
    s.set(0, 0.5, 7).unwrap();
    for i in 0..7 {
        s.set(110 + i, 600_000.0, 7).unwrap();
    }
    let t = s.timing();
    let lim = Limits::<7>::new(&s, 1_000_000);
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
