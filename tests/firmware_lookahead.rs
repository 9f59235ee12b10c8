//! Firmware in the loop, continuous motion: look-ahead junctions on the release ELF.

mod fil;

use ddastep_bench::emu::{gcode_lines, HZ};
use fil::*;

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
    let g = std::fs::read_to_string(ddastep_bench::emu::repo_root().join("bench/demo/circle360.gcode")).unwrap();
    let lines: Vec<String> = gcode_lines(&g);
    // Settings and the move to the start point, then wait, so the circle starts from rest.
    let start = lines.iter().position(|l| l.starts_with("G1")).unwrap();
    for l in &lines[..=start] {
        ok(&mut b, l);
    }
    wait_idle(&mut b, 2.0);
    let t0 = b.cycles();
    for l in &lines[start + 1..] {
        ok(&mut b, l);
    }
    wait_idle(&mut b, 10.0);
    let s: Vec<Step> = steps(&b).into_iter().filter(|s| s.cycle >= t0).collect();
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
    assert_eq!(b.report().overruns, 0);
}

#[test]
fn streamed_short_segments_never_starve() {
    let mut b = boot();
    let r = ddastep_bench::emu::stream::stream_segments(&mut b, 150, 7).unwrap();
    assert_eq!(r.starved_windows, 0, "{r:?}");
    assert_eq!(b.report().overruns, 0);
}

/// Back-to-back moves at the `$I` rate cap (the sweep's settings: 0.5 µs pulses, the shortest
/// the cap allows least room for a long tick): 12 segments joined at speed, on 1 axis
/// collinear, on 3 and 7 axes with Y reversing at every junction (a direction change at
/// speed). Every step reaches the pins, no timer update is missed, and the step ISR's longest
/// run (a ramp piece or a move change) is printed beside its mean.
#[test]
fn back_to_back_moves_at_the_rate_cap_keep_every_step() {
    use ddastep_bench::emu::sweep::{settings_lines, RATIO};
    for axes in [1usize, 3, 7] {
        let mut b = boot();
        for l in settings_lines() {
            ok(&mut b, &l);
        }
        let info = reply(&mut b, "$I");
        // The cap for this move's slaves, from the firmware's own timing (as `$I` prints the
        // single-axis one).
        let mut s = ddastep::settings::Settings::BENCH;
        s.set(0, ddastep_bench::emu::sweep::PULSE_US, 3).unwrap();
        let cap = s.timing().max_rate_for(axes as u32 - 1);
        assert!(info.contains(&format!("[MSG:max step rate {} Hz]", s.timing().max_rate_hz())), "{info}");
        let hz = cap as f64 * 0.995;
        ok(&mut b, "G91");
        let mut want = [0i64; 7];
        let mut rising = 0i64;
        b.set_isr_log(true);
        b.set_profile(true);
        for k in 0..12 {
            // A long first move, so the short ones after it are all queued before it ends
            // (each is shorter than its line takes on the serial line).
            let len = if k == 0 { 8000 } else { 200 };
            let mut steps: Vec<i64> = RATIO[..axes].iter().map(|&r| len * r as i64).collect();
            if axes > 1 {
                steps[1] = if k % 2 == 0 { 200 } else { -200 };
            }
            for (w, s) in want.iter_mut().zip(&steps) {
                *w += s;
                rising += s.abs();
            }
            let mm: Vec<f64> = steps.iter().map(|&s| s as f64 / 100.0).collect();
            let path = mm.iter().map(|m| m * m).sum::<f64>().sqrt();
            let feed = path / (steps[0] as f64 / hz) * 60.0;
            let words: String = "XYZABCU".chars().zip(&mm).map(|(a, m)| format!(" {a}{m}")).collect();
            ok(&mut b, &format!("G1{words} F{feed:.3}"));
        }
        wait_idle(&mut b, 3.0);
        // At speed: runs whose update event was followed by the next within 1.5 cap periods.
        let near = 72_000_000 / cap as u64 * 3 / 2;
        let log = b.isr_log();
        let ups: Vec<u64> = log.iter().filter_map(|r| r.update).collect();
        let fast: Vec<u64> = log
            .iter()
            .filter_map(|r| Some((r.update?, r.cycles)))
            .filter(|&(u, _)| ups.iter().find(|&&n| n > u).is_some_and(|&n| n - u < near))
            .map(|(_, c)| c)
            .collect();
        let mean = fast.iter().sum::<u64>() as f64 / fast.len() as f64;
        let max = fast.iter().max().unwrap();
        {
            let thr = (mean * 1.3) as u64;
            let mut h: std::collections::BTreeMap<String, (u64, u64)> = Default::default();
            let last_fin = log.iter().filter(|r| r.blocks.iter().any(|&a| b.symbol(a).is_some_and(|(n, _)| n.ends_with("finish")))).map(|r| r.start).max().unwrap_or(0);
            for r in log.iter().filter(|r| r.update.is_some() && r.cycles > thr) {
                let mut fns: Vec<String> = r.blocks.iter().filter_map(|&a| b.symbol(a).map(|(n, _)| n.rsplit("::").next().unwrap().to_string())).collect();
                fns.dedup();
                let idle = r.start == last_fin;
                let e = h.entry(format!("{}{}", fns.join(">"), if idle { " (idle)" } else { "" })).or_default();
                e.0 += 1;
                e.1 = e.1.max(r.cycles);
            }
            for (k, v) in &h { eprintln!("  long {} max {}: {}", v.0, v.1, k); }
            let prof: std::collections::HashMap<String, (u64,u64,u64)> = b.profile_blocks(16 + 28).into_iter().map(|(n, c)| (n.split_whitespace().next().unwrap().to_string(), (c.runs, c.cycles, c.insns))).collect();
            if let Some(r) = log.iter().filter(|r| r.update.is_some() && r.start != last_fin).max_by_key(|r| r.cycles) {
                eprintln!("  longest run {} cycles:", r.cycles);
                for a in &r.blocks {
                    let k = format!("0x{a:08x}");
                    let (runs, cyc, ins) = prof.get(&k).copied().unwrap_or((1,0,0));
                    eprintln!("    {k} {:?} ~{} cyc {} insn", b.symbol(*a), cyc / runs.max(1), ins / runs.max(1));
                }
            }
        }
        eprintln!("{axes} axes at {hz:.0} Hz (cap {cap}): step ISR at speed mean {mean:.1} / max {max} modeled cycles ({} runs), overruns {}", fast.len(), b.report().overruns);
        assert_eq!(net(&steps(&b)), want, "{axes} axes");
        assert_eq!(steps(&b).len() as i64, rising, "{axes} axes: rising edges");
        assert_eq!(b.report().overruns, 0, "{axes} axes");
    }
}
