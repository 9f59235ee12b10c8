//! The planner's position and rates: absolute-step rounding, the feed and axis limits, and
//! targets out of range.

use ddastep::error::Error;
use ddastep::grbl::settings::Settings;
use ddastep::motion::ramp::period_of_hz;
use ddastep::planning::planner::{Limits, Planner};


/// The bench settings with the table top the firmware would build for 3 axes.
fn lim() -> Limits<3> {
    let s = Settings::BENCH;
    s.planner_limits(s.ramp_config(3, &s.timing()).vmax)
}

#[test]
fn many_small_moves_never_accumulate_rounding() {
    let mut p = Planner::<3>::new();
    let l = lim();
    let mut steps = [0i64; 3];
    let mut mm = [0.0f32; 3];
    for _ in 0..1000 {
        mm[0] += 0.001;
        mm[1] -= 0.0049;
        if let Some(pl) = p.line(&mm, Some(100.0), &l).unwrap() {
            for (s, d) in steps.iter_mut().zip(pl.mv.steps()) {
                *s += *d as i64;
            }
        }
    }
    assert_eq!(steps, [100, -490, 0]);
    assert_eq!(p.position_steps(), &steps);
}

#[test]
fn g1_rate_follows_the_feed_and_axis_limits() {
    let mut p = Planner::<3>::new();
    let l = lim();
    // 50:30:20 mm at F = 600·√3800 mm/min: X runs 500 mm/s = 50 kHz.
    let f = 600.0 * libm::sqrtf(3800.0);
    let pl = p.line(&[50.0, 30.0, 20.0], Some(f), &l).unwrap().unwrap();
    assert_eq!(pl.mv.steps(), &[5000, 3000, 2000]);
    assert_eq!(pl.mv.cruise(), period_of_hz(50_000));
    // A feed above X's 36 000 mm/min limit: X is held at 60 kHz.
    let pl = p.line(&[150.0, 30.0, 20.0], Some(1e9), &l).unwrap().unwrap();
    assert_eq!(pl.mv.cruise(), period_of_hz(60_000));
    // G0 on one axis: its max rate.
    let pl = p.line(&[150.0, 40.0, 20.0], None, &l).unwrap().unwrap();
    assert_eq!(pl.mv.cruise(), period_of_hz(60_000));
    // A table that tops out lower clamps the cruise (documented in $I).
    let slow = Limits { vmax_hz: 20_000, ..l };
    let pl = p.line(&[0.0, 40.0, 20.0], None, &slow).unwrap().unwrap();
    assert_eq!(pl.mv.cruise(), period_of_hz(20_000));
    assert!(pl.wanted_hz > 59_000.0);
    // Very slow feeds stop at 1 step/s.
    let pl = p.line(&[0.01, 40.0, 20.0], Some(1e-6), &l).unwrap().unwrap();
    assert_eq!(pl.mv.cruise(), period_of_hz(1));
}

#[test]
fn out_of_range_targets_change_nothing() {
    let mut p = Planner::<3>::new();
    let l = lim();
    assert_eq!(p.line(&[3e7, 0.0, 0.0], None, &l), Err(Error::InvalidTarget));
    assert_eq!(p.line(&[f32::NAN, 0.0, 0.0], None, &l), Err(Error::InvalidTarget));
    assert_eq!(p.position_steps(), &[0, 0, 0]);
    assert_eq!(p.line(&[0.004, 0.0, 0.0], None, &l), Ok(None));
    assert_eq!(p.position_mm(), &[0.004, 0.0, 0.0]);
    assert_eq!(p.set_position(&[None, Some(-2.0), None], &l), Ok([0, -200, 0]));
    assert_eq!(p.position_mm(), &[0.004, -2.0, 0.0]);
}
