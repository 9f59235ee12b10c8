//! Firmware in the loop, continuous motion: look-ahead junctions on the release ELF.

mod firmware_rig;

use ddastep_bench::emu::{gcode_lines, HZ};
use firmware_rig::*;

/// Path speed (mm/s at 100 steps/mm) over each 10 ms window between `from` and `to` cycles.
fn speeds(s: &[Step], from: u64, to: u64) -> Vec<f64> {
    let w = HZ / 100;
    let n = ((to - from) / w) as usize + 1;
    let mut d = vec![[0i64; 2]; n];
    for st in s.iter().filter(|st| st.cycle >= from && st.cycle < to && st.axis < 2) {
        d[((st.cycle - from) / w) as usize][st.axis] += 1;
    }
    d.iter().map(|c| ((c[0] * c[0] + c[1] * c[1]) as f64).sqrt() / 100.0 / 0.01).collect()
}

#[test]
fn circle_of_360_segments_runs_near_its_feed() {
    let mut b = boot();
    // (From rest: the settings and the move to the start point come first.)
    let s = circle360_steps(&mut b);
    let (first, last) = (s[0].cycle, s[s.len() - 1].cycle);
    let took = (last - first) as f64 / HZ as f64;
    // Ideal: the polygon's length at F3000 plus one acceleration and one deceleration at 500 mm/s².
    let len = 360.0 * 2.0 * 20.0 * (std::f64::consts::PI / 360.0).sin();
    let ideal = len / 50.0 + 50.0 / 500.0;
    let v = speeds(&s, first, last);
    eprintln!("circle: {took:.3} s, ideal {ideal:.3} s ({:.3}x); speeds per 10 ms: {:?}", took / ideal,
        v.iter().map(|x| x.round() as i64).collect::<Vec<_>>());
    assert_eq!(&net(&steps(&b))[..2], &[2000, 0]);
    assert!(took <= 1.1 * ideal, "circle took {took:.3} s, ideal {ideal:.3} s");
    assert_eq!(b.report().overruns, 0);
}

#[test]
fn fast_532_reaches_200_khz_on_the_seven_axis_firmware() {
    let mut b = boot();
    let g = std::fs::read_to_string(ddastep_bench::emu::repo_root().join("bench/demo/fast_532.gcode")).unwrap();
    for l in gcode_lines(&g) {
        ok(&mut b, &l);
    }
    wait_idle(&mut b, 3.0);
    let s = steps(&b);
    eprintln!("{} | overruns {} | {}", status(&mut b), b.report().overruns, (0..3).map(|a| s.iter().filter(|s| s.axis == a).count().to_string()).collect::<Vec<_>>().join(","));
    assert_eq!(s.iter().filter(|s| s.axis == 0).count(), 10_000);
    assert_eq!(net(&s), [0; 7]);
    // Cruise: X at 200 kHz (± 0.5 %) over 1000 master steps in the middle of the first move.
    let x: Vec<u64> = s.iter().filter(|s| s.axis == 0).map(|s| s.cycle).collect();
    let rate = 1000.0 * HZ as f64 / (x[3000] - x[2000]) as f64;
    assert!((rate - 200_000.0).abs() < 1_000.0, "cruise {rate} Hz");
    // `$0=1`: every pulse and every low time between two pulses at least 1 µs, move changes
    // and deceleration triggers included.
    let r = b.report();
    for (name, a) in &r.axes.0[..3] {
        assert!(a.min_high_ns.is_some_and(|h| h >= 1000.0) && a.min_low_ns.is_some_and(|l| l >= 1000.0), "{name}: {a:?}");
    }
    assert_eq!(r.overruns, 0);
}

#[test]
fn streamed_short_segments_never_starve() {
    let mut b = boot();
    let r = ddastep_bench::emu::stream::stream_segments(&mut b, 150, 7).unwrap();
    assert_eq!(r.starved_windows, 0, "{r:?}");
    assert_eq!(b.report().overruns, 0);
}

/// Back-to-back moves at the `$I` rate cap (the sweep's settings: 0.5 µs pulses, the shortest
/// the cap allows least room for a long tick): a long move, then 12 short ones joined at
/// speed, on 1 axis collinear, on 3 and 7 axes with Y reversing at every junction (a direction
/// change at speed). Every step reaches the pins and no timer update is missed; the step ISR's
/// longest run (a move change) is printed beside its mean (bench/RESULTS.md has the same
/// measure, `ddastep_bench::emu::changes`).
#[test]
fn back_to_back_moves_at_the_rate_cap_keep_every_step() {
    // The sweep's 0.5 µs pulses, and 2 µs ones (where the low time after a long handler's
    // falling edge binds the cap).
    for (axes, pulse_us) in [(1usize, 0.5), (3, 0.5), (7, 0.5), (1, 2.0), (3, 2.0)] {
        let mut b = boot();
        // The cap for this move's slaves, from the firmware's own timing (as `$I` prints the
        // single-axis one).
        let mut s = ddastep::grbl::settings::Settings::BENCH;
        s.set(0, pulse_us as f32, 3).unwrap();
        let cap = s.timing().max_rate_for(axes as u32 - 1);
        let r = ddastep_bench::emu::changes::back_to_back_at(&mut b, axes, cap as f64 * 0.995, pulse_us).unwrap();
        let info = reply(&mut b, "$I");
        assert!(info.contains(&format!("[MSG:max step rate {} Hz]", s.timing().max_rate_hz())), "{info}");
        wait_idle(&mut b, 1.0);
        eprintln!(
            "{axes} axes, $0={pulse_us}, at {:.0} Hz (cap {cap}): step ISR mean {:.1} / max {} (a move change: {} on its last step, {} on the next move's first; not at speed {}, the end {}) modeled cycles ({} runs), overruns {}",
            r.hz, r.mean, r.max, r.max_last, r.max_first, r.max_start, r.max_end, r.runs, b.report().overruns
        );
        assert!(r.max_change > 0 && r.runs > 1000, "{r:?}");
        assert_eq!(net(&steps(&b)), r.want, "{axes} axes");
        assert_eq!(steps(&b).len() as i64, r.rising, "{axes} axes: rising edges");
        assert_eq!(b.report().overruns, 0, "{axes} axes");
        // Every pulse and every low time at least `$0`, on every axis that stepped.
        for (name, a) in &b.report().axes.0 {
            if let (Some(hi), Some(lo)) = (a.min_high_ns, a.min_low_ns) {
                eprintln!("  {name}: high ≥ {hi:.0} ns, low ≥ {lo:.0} ns");
                assert!(hi >= pulse_us * 1e3 && lo >= pulse_us * 1e3, "{axes} axes, {name}: high {hi} ns, low {lo} ns");
            }
        }
    }
}
