//! Firmware in the loop, S-curves (`$41=1`): every move's own S from its entry speed to its
//! cruise and on to its exit, on the release ELF.

mod firmware_rig;

use ddastep_bench::emu::HZ;
use firmware_rig::*;

/// X's step times (cycles) for `G91 G1 X60 F3000` at `$120=2000` with `$41` = `shape`.
fn x60(shape: u8) -> Vec<u64> {
    let mut b = boot();
    for l in ["$100=100", "$110=36000", "$120=2000", &format!("$41={shape}"), "G91", "G1 X60 F3000"] {
        ok(&mut b, l);
    }
    wait_idle(&mut b, 5.0);
    let s = steps(&b);
    assert_eq!(net(&s), [6000, 0, 0, 0, 0, 0, 0], "$41={shape}");
    s.iter().filter(|s| s.axis == 0).map(|s| s.cycle).collect()
}

/// The ramp up as (time since the first step, rate) at each step period's middle, s and Hz,
/// up to the first period within 0.2 % of the cruise `hz`.
fn ramp_up(x: &[u64], hz: f64) -> Vec<(f64, f64)> {
    let mut v = Vec::new();
    for w in x.windows(2) {
        let (t, r) = ((w[0] + w[1]) as f64 / 2.0 - x[0] as f64, HZ as f64 / (w[1] - w[0]) as f64);
        v.push((t / HZ as f64, r));
        if r >= hz * 0.998 {
            break;
        }
    }
    v
}

/// The rate at time `t` on the ramp, linear between samples.
fn rate_at(v: &[(f64, f64)], t: f64) -> f64 {
    match v.iter().position(|p| p.0 >= t) {
        Some(0) => v[0].1,
        Some(i) => {
            let (a, b) = (v[i - 1], v[i]);
            a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
        }
        None => v[v.len() - 1].1,
    }
}

#[test]
fn one_move_ramps_up_as_an_s_at_its_own_acceleration() {
    let s = ramp_up(&x60(1), 5000.0);
    let t = ramp_up(&x60(0), 5000.0);
    let (ts, tt) = (s[s.len() - 1].0, t[t.len() - 1].0);
    // Acceleration by tenths of the S's ramp, as fractions of the steepest tenth.
    let acc: Vec<f64> = (0..10).map(|i| (rate_at(&s, ts * (i + 1) as f64 / 10.0) - rate_at(&s, ts * i as f64 / 10.0)) / (ts / 10.0)).collect();
    let peak = acc.iter().cloned().fold(0.0, f64::max);
    let frac: Vec<f64> = acc.iter().map(|a| (a / peak * 100.0).round() / 100.0).collect();
    // The steepest acceleration over 4 ms windows: the move's own (2000 mm/s², 200 kHz/s), as
    // the trapezoid's constant one measures the same way.
    let steepest = |v: &[(f64, f64)], end: f64| {
        (0..((end / 0.001) as usize).saturating_sub(4))
            .map(|i| (rate_at(v, (i + 4) as f64 * 0.001) - rate_at(v, i as f64 * 0.001)) / 0.004)
            .fold(0.0, f64::max)
    };
    let (ss, st) = (steepest(&s, ts), steepest(&t, tt));
    eprintln!("S ramp {:.1} ms, trapezoid {:.1} ms ({:.2}x); tenths {frac:?}; steepest {ss:.0} Hz/s, trapezoid {st:.0} Hz/s", ts * 1e3, tt * 1e3, ts / tt);
    assert!(frac[0] <= 0.35 && frac[9] <= 0.35, "first and last tenths: {frac:?}");
    assert!(ts <= 3.5 * tt, "S ramp {ts} s, trapezoid {tt} s");
    assert!(ss <= st * 1.05 && ss >= 150_000.0, "steepest {ss} Hz/s, trapezoid {st} Hz/s");
}

#[test]
fn circle_of_360_segments_runs_near_its_feed_in_s_mode() {
    let mut b = boot();
    ok(&mut b, "$41=1");
    let s = circle360_steps(&mut b);
    let took = (s[s.len() - 1].cycle - s[0].cycle) as f64 / HZ as f64;
    // Ideal: the polygon's length at F3000 plus one S up and one S down peaking at 500 mm/s²
    // (each as long as the trapezoid at 500 / k, k = 2.075 for `$582=4`).
    let len = 360.0 * 2.0 * 20.0 * (std::f64::consts::PI / 360.0).sin();
    let ideal = len / 50.0 + 2.0746 * 50.0 / 500.0;
    eprintln!("circle in S mode: {took:.3} s, ideal {ideal:.3} s ({:.3}x)", took / ideal);
    assert_eq!(&net(&steps(&b))[..2], &[2000, 0]);
    assert!(took <= 1.1 * ideal, "circle took {took:.3} s, ideal {ideal:.3} s");
    assert_eq!(b.report().overruns, 0);
}

#[test]
fn paper_532_in_s_mode_keeps_its_exact_pattern() {
    let mut b = boot();
    // At the bench's 10 000 mm/s² the S's ramps (2.075 times the trapezoid's distance) do not
    // fit in 5000 steps: the move would peak below 50 kHz. At 25 000 mm/s² it cruises.
    for l in ["$41=1", "$120=25000", "$121=25000", "$122=25000", "G91"] {
        ok(&mut b, l);
    }
    ok(&mut b, "G1 X50 Y30 Z20 F36986.484");
    wait_idle(&mut b, 2.0);
    let s = steps(&b);
    assert_eq!(net(&s), [5000, 3000, 2000, 0, 0, 0, 0]);
    assert_eq!(assert_paper_pattern(&s), 5000);
    let x: Vec<u64> = s.iter().filter(|s| s.axis == 0).map(|s| s.cycle).collect();
    let rate = 1000.0 * HZ as f64 / (x[3000] - x[2000]) as f64;
    assert!((rate - 50_000.0).abs() < 250.0, "cruise {rate} Hz");
    assert_eq!(b.report().overruns, 0);
}

#[test]
fn short_moves_after_a_long_one_each_get_their_own_s() {
    // Each 3 mm move at F6000 after the first is a triangle from rest (S up to its peak, S down): 86 ms with `$120=2000`
    // (63 ms as trapezoids). None may crawl at the table's bottom (a peak planned from the
    // previous move's step count did: 200 ms).
    let mut b = boot();
    for l in ["$100=100", "$110=36000", "$120=2000", "$41=1", "G91", "G1 X60 F3000"] {
        ok(&mut b, l);
    }
    for _ in 0..10 {
        ok(&mut b, "G1 X3 F6000");
        ok(&mut b, "G1 X-3 F6000");
    }
    wait_idle(&mut b, 10.0);
    let s = steps(&b);
    assert_eq!(net(&s), [6000, 0, 0, 0, 0, 0, 0]);
    let x: Vec<u64> = s.iter().filter(|s| s.axis == 0).map(|s| s.cycle).collect();
    assert_eq!(x.len(), 12_000);
    let ms: Vec<f64> = (0..20).map(|i| (x[6000 + 300 * i + 299] - x[6000 + 300 * i]) as f64 / HZ as f64 * 1e3).collect();
    eprintln!("short moves, ms: {:?}", ms.iter().map(|m| m.round()).collect::<Vec<_>>());
    // (The first joins the long move at speed: shorter.)
    assert!(ms[0] <= 95.0 && ms[1..].iter().all(|&m| (75.0..=95.0).contains(&m)), "{ms:?}");
}

#[test]
fn paper_532_in_s_mode_with_dma_keeps_its_exact_pattern() {
    // DMA burst mode (`$581=1`): the fill runs the same ramp half ahead of the pins.
    let base = ddastep::grbl::settings::Settings { shape: ddastep::motion::ramp::Shape::SCurve, ..ddastep::grbl::settings::Settings::BENCH };
    let mut b = boot_dma(base, false);
    for l in ["$120=25000", "$121=25000", "$122=25000", "G91", "G1 X50 Y30 Z20 F36986.484"] {
        ok(&mut b, l);
    }
    wait_idle(&mut b, 2.0);
    let s = steps(&b);
    assert_eq!(net(&s), [5000, 3000, 2000, 0, 0, 0, 0]);
    assert_eq!(assert_paper_pattern(&s), 5000);
    assert_paper_cruise(&b, &s, 1000.0);
}
