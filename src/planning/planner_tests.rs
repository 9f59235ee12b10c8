//! The planner's tests: the f32 compares on the bits against the operators, and `line_exact` /
//! `junction_speed` bit for bit against their former versions (kept here as the reference).

use super::*;
use proptest::prelude::*;

const EDGES: [u32; 12] = [0, 0x8000_0000, 1, 0x8000_0001, 0x7F80_0000, 0xFF80_0000, 0x7FC0_0000, 0xFFC0_0000, 0x7F80_0001, 0x3089_705F, 0x3089_7060, 0x3F7F_FFEF];

fn check(a: u32, b: u32) {
    let (x, y) = (f32::from_bits(a), f32::from_bits(b));
    assert_eq!(nonzero(x), x != 0.0, "{a:#x}");
    for c in [0.0, 1e-9, 0.999_999] {
        assert_eq!(above(x, c), x > c, "{a:#x} > {c}");
        assert_eq!(above(-x, c), x < -c, "{a:#x} < -{c}");
    }
    assert_eq!(same(x, y), x == y, "{a:#x} == {b:#x}");
    assert_eq!(same(x, x), x == x, "{a:#x}");
}

/// The bit compares answer as the f32 operators, zeros, infinities and NaNs included.
#[test]
fn bit_compares_match_the_operators_at_the_edges() {
    for &a in &EDGES {
        for &b in &EDGES {
            for d in [0, 1, u32::MAX] {
                check(a.wrapping_add(d), b);
            }
        }
    }
}

/// `line_exact` and `junction_speed` as they were before the bit compares and the loops
/// over the moving axes, as the reference.
fn line_exact_ref<const N: usize>(
    this: &mut Planner<N>,
    target: &[f32; N],
    exact: &[Option<Decimal>; N],
    feed: Option<f32>,
    lim: &Limits<N>,
) -> Result<Option<Planned<N>>, Error> {
    let mut to = [0i64; N];
    for i in 0..N {
        let spm = lim.steps_per_mm[i];
        to[i] = match exact[i] {
            Some(d) => d.steps(spm)?,
            None if target[i] == this.mm[i] => this.steps[i],
            None => to_steps(target[i], spm)?,
        };
    }
    let delta: [i64; N] = core::array::from_fn(|i| to[i] - this.steps[i]);
    let master_steps = delta.iter().map(|d| d.unsigned_abs()).max().unwrap_or(0);
    if master_steps == 0 {
        this.mm = *target;
        return Ok(None);
    }
    // Path length from the rounded steps; per-axis unit vector.
    // (Axes that do not move are skipped: soft float costs ~50–200 cycles an operation on
    // the M3 even for zeros. One division for the unit vector.)
    let d: [f32; N] = core::array::from_fn(|i| if delta[i] == 0 { 0.0 } else { f32_of_i64(delta[i]) / lim.steps_per_mm[i] });
    let len = sqrt(d.iter().filter(|v| **v != 0.0).map(|v| v * v).sum());
    let inv_len = 1.0 / len;
    let unit: [f32; N] = core::array::from_fn(|i| if delta[i] == 0 { 0.0 } else { d[i] * inv_len });
    // The path speed and acceleration every moving axis allows (Grbl's limit by axis).
    let mut vmax = f32::MAX;
    let mut accel = f32::MAX;
    for i in 0..N {
        let u = libm::fabsf(unit[i]);
        if delta[i] != 0 && u > 0.0 {
            vmax = vmax.min(lim.max_rate[i] / (60.0 * u));
            accel = accel.min(lim.accel[i] / u);
        }
    }
    // The overrides scale the asked speed later, in the feeder ([`crate::motion::moves::Rates`]).
    let (asked, ovr) = match feed {
        Some(f) => (f / 60.0, Ovr::Feed),
        None => (vmax, Ovr::Rapid),
    };
    let share = f32_of_u64(master_steps) / len;
    let wanted_hz = asked.min(vmax) * share;
    // The step handler's ceiling for this many slave axes, and the ramp table's top.
    let slaves = delta.iter().filter(|d| **d != 0).count() as u32 - 1;
    let top = (lim.timing.max_rate_for(slaves) as f32).min(lim.vmax_hz as f32 * share / lim.per_mm.max(1e-9));
    // max/min, not f32::clamp: its panic message would link float formatting into the firmware.
    // Milli-steps/s: G93 times need more than whole steps/s at low rates.
    let top_millihz = crate::motion::ramp::MAX_RATE_HZ as u64 * 1000;
    let cruise_millihz = crate::num::u64_of(libm::roundf(wanted_hz.max(1.0).min(top) * 1000.0)).min(top_millihz);
    let mut mv = Move::new_millihz(delta, cruise_millihz).map_err(|_| Error::InvalidTarget)?;
    mv.ovr = ovr;
    // Junction deviation only: the look-ahead caps it by both moves' speeds under the
    // overrides in force.
    // And the step path's move change: at most the mode's junction rate on both sides
    // (`Timing::max_junction_rate_for`: DMA mode changes moves inside a buffer fill).
    let junction = match this.prev {
        Some((pu, pshare, pslaves)) => {
            let jcap = lim.timing.max_junction_rate_for(slaves.max(pslaves)) as f32;
            junction_speed_ref(&pu, &unit, &lim.accel, lim.junction_dev).min(jcap / share.max(pshare))
        }
        None => 0.0,
    };
    this.prev = Some((unit, share, slaves));
    let path = Path {
        share: share as f32,
        accel: (accel * lim.ramp_accel).min(1e12),
        asked_hz: (asked * share) as f32,
        cap_hz: (vmax * share).min(top) as f32,
        junction: junction as f32,
    };
    this.mm = *target;
    this.steps = to;
    Ok(Some(Planned { mv: mv.with_path(path), mm_per_step: (len / f32_of_u64(master_steps)) as f32, wanted_hz }))
}


fn junction_speed_ref<const N: usize>(a: &[f32; N], b: &[f32; N], axis_accel: &[f32; N], dev: f32) -> f32 {
    let mut cos = 0.0f32;
    let mut ju = [0.0f32; N];
    for i in 0..N {
        if a[i] != 0.0 || b[i] != 0.0 {
            cos -= a[i] * b[i];
            ju[i] = b[i] - a[i];
        }
    }
    if cos > 0.999_999 {
        return 0.0;
    }
    if cos < -0.999_999 {
        return f32::MAX;
    }
    let inv_n = 1.0 / sqrt(ju.iter().filter(|v| **v != 0.0).map(|v| v * v).sum::<f32>());
    let mut acc = f32::MAX;
    for i in 0..N {
        let u = libm::fabsf(ju[i]) * inv_n;
        if u > 1e-9 {
            acc = acc.min(axis_accel[i] / u);
        }
    }
    let sin_d2 = sqrt(0.5 * (1.0 - cos));
    sqrt(acc * dev * sin_d2 / (1.0 - sin_d2))
}


fn limits(spm: [f32; 4], rate: [f32; 4], accel: [f32; 4]) -> Limits<4> {
    Limits {
        steps_per_mm: spm,
        max_rate: rate,
        accel,
        ramp_accel: 1.0,
        vmax_hz: 100_000,
        per_mm: spm.iter().fold(0.0f32, |m, v| m.max(*v)),
        junction_dev: JUNCTION_DEVIATION_MM,
        timing: Timing::DEFAULT,
    }
}

proptest! {
    #[test]
    fn bit_compares_match_the_operators(a: u32, b: u32) {
        check(a, b);
    }

    /// Chains of moves (some axes still, some steps below one, G0 and G1) plan the same
    /// moves, junctions and positions as the reference, bit for bit.
    #[test]
    fn lines_match_the_reference(
        spm in prop::array::uniform4(1.0f32..400.0),
        rate in prop::array::uniform4(100.0f32..20_000.0),
        accel in prop::array::uniform4(10.0f32..5_000.0),
        moves in prop::collection::vec((prop::array::uniform4(prop::option::weighted(0.6, -50.0f32..50.0)), prop::option::weighted(0.8, 1.0f32..10_000.0)), 1..20),
    ) {
        let lim = limits(spm, rate, accel);
        let (mut p, mut r) = (Planner::<4>::new(), Planner::<4>::new());
        for (axes, feed) in moves {
            let target: [f32; 4] = core::array::from_fn(|i| axes[i].unwrap_or(p.mm[i]));
            let got = p.line_exact(&target, &[None; 4], feed, &lim);
            let want = line_exact_ref(&mut r, &target, &[None; 4], feed, &lim);
            prop_assert_eq!(got.map(|m| m.map(|m| (m.mv, m.mm_per_step.to_bits(), m.wanted_hz.to_bits()))), want.map(|m| m.map(|m| (m.mv, m.mm_per_step.to_bits(), m.wanted_hz.to_bits()))));
            prop_assert_eq!(p.mm.map(f32::to_bits), r.mm.map(f32::to_bits));
            prop_assert_eq!(p.steps, r.steps);
            prop_assert_eq!(p.prev.map(|(u, s, n)| (u.map(f32::to_bits), s.to_bits(), n)), r.prev.map(|(u, s, n)| (u.map(f32::to_bits), s.to_bits(), n)));
        }
    }

    /// Junction speeds of random direction pairs (some axes zero in one or both) as the
    /// reference, bit for bit.
    #[test]
    fn junctions_match_the_reference(
        a in prop::array::uniform4(prop::option::weighted(0.6, -1.0f32..1.0)),
        b in prop::array::uniform4(prop::option::weighted(0.6, -1.0f32..1.0)),
        accel in prop::array::uniform4(10.0f32..5_000.0),
    ) {
        let unit = |v: [Option<f32>; 4]| {
            let v = v.map(|x| x.unwrap_or(0.0));
            let n = sqrt(v.iter().map(|x| x * x).sum::<f32>());
            v.map(|x| if n > 0.0 { x / n } else { 0.0 })
        };
        let (a, b) = (unit(a), unit(b));
        prop_assert_eq!(junction_speed(&a, &b, &accel, 0.01).to_bits(), junction_speed_ref(&a, &b, &accel, 0.01).to_bits());
        prop_assert_eq!(junction_speed(&a, &a, &accel, 0.01).to_bits(), junction_speed_ref(&a, &a, &accel, 0.01).to_bits());
    }
}
