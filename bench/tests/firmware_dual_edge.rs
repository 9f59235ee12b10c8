//! Firmware in the loop, dual-edge step mode (`$580=1`): every step toggles its pin (drivers
//! that step on both edges, TMC22xx `dedge`). Counts are every edge of a step pin.

mod firmware_rig;

use ddastep::grbl::settings::Settings;
use ddastep_bench::emu::{gcode_lines, HZ};
use firmware_rig::*;

/// Steps per axis from the pins.
fn counts(s: &[Step]) -> [usize; 7] {
    let mut c = [0; 7];
    for st in s {
        c[st.axis] += 1;
    }
    c
}

/// Shortest time between two edges of one step pin, per axis (modeled cycles; `u64::MAX`: fewer
/// than two edges).
fn min_spacing(s: &[Step]) -> [u64; 7] {
    let mut last = [None::<u64>; 7];
    let mut min = [u64::MAX; 7];
    for st in s {
        if let Some(l) = last[st.axis] {
            min[st.axis] = min[st.axis].min(st.cycle - l);
        }
        last[st.axis] = Some(st.cycle);
    }
    min
}

/// The `$0` pulse in modeled cycles (72 per µs).
fn pulse_cycles(us: f64) -> u64 {
    (us * 72.0).ceil() as u64
}

#[test]
fn paper_532_toggles_exactly_with_the_papers_pattern() {
    let mut b = boot_dual(Settings::BENCH);
    ok(&mut b, "G91");
    ok(&mut b, "G1 X50 Y30 Z20 F36986.484");
    wait_idle(&mut b, 2.0);
    let s = toggles(&b);
    assert_eq!(net(&s), [5000, 3000, 2000, 0, 0, 0, 0]);
    assert_eq!(counts(&s)[..3], [5000, 3000, 2000]);
    // Half of each axis's steps are rising edges: the pins toggle, they never pulse.
    assert_eq!(steps(&b).len(), 2500 + 1500 + 1000);
    // The paper's pattern, one edge per step.
    assert_eq!(assert_paper_pattern(&s), 5000);
    // Cruise at 50 kHz; the checker's dual-edge count agrees, and two toggles of a pin are ≥ $0
    // (3 µs) apart.
    let r = assert_paper_cruise(&b, &s, 3000.0);
    assert!(min_spacing(&s)[..3].iter().all(|&m| m >= pulse_cycles(3.0)));
    assert_eq!(r.overruns, 0);
    assert!(r.max_slave_deviation_steps.is_some_and(|d| d <= 0.5), "{:?}", r.max_slave_deviation_steps);
}

#[test]
fn fast_532_toggles_exactly_at_200_khz() {
    let mut b = boot_dual(Settings::BENCH);
    let g = std::fs::read_to_string(ddastep_bench::emu::repo_root().join("bench/demo/fast_532.gcode")).unwrap();
    for l in gcode_lines(&g) {
        ok(&mut b, &l);
    }
    wait_idle(&mut b, 3.0);
    let s = toggles(&b);
    assert_eq!(counts(&s)[..3], [10_000, 6_000, 4_000]);
    assert_eq!(net(&s), [0; 7]);
    let x: Vec<u64> = s.iter().filter(|s| s.axis == 0).map(|s| s.cycle).collect();
    let rate = 1000.0 * HZ as f64 / (x[3000] - x[2000]) as f64;
    assert!((rate - 200_000.0).abs() < 1_000.0, "cruise {rate} Hz");
    // `$0=2`: toggles of one pin ≥ 2 µs apart; `$29` (5 µs) before the first toggle after the
    // reversal.
    assert!(min_spacing(&s)[..3].iter().all(|&m| m >= pulse_cycles(2.0)), "{:?}", min_spacing(&s));
    let r = b.report();
    for (name, a) in &r.axes.0[..3] {
        assert!(a.min_dir_setup_ns.unwrap() >= 5000.0, "{name}: {a:?}");
    }
    assert_eq!(r.overruns, 0);
}

/// Back-to-back moves (12 segments joined at speed, Y reversing at every junction on 3 and 7
/// axes) at the dual-edge cap `$I` prints, which is above the full-pulse cap for the same
/// pulse (3 µs, a TB6600's: full pulses are then limited by the pulse and its low time, one
/// toggle per step by the handler's cost): every step reaches the pins, no timer update is
/// missed, toggles of a pin stay ≥ `$0` apart and direction changes lead the next toggle by
/// `$29`.
#[test]
fn back_to_back_moves_above_the_full_pulse_cap_keep_every_step() {
    use ddastep_bench::emu::sweep::{settings_lines, RATIO};
    const PULSE_US: f64 = 3.0;
    for axes in [1usize, 3, 7] {
        let mut b = boot_dual(Settings::BENCH);
        for l in settings_lines() {
            ok(&mut b, &l);
        }
        ok(&mut b, &format!("$0={PULSE_US}"));
        let info = reply(&mut b, "$I");
        let mut s = Settings::BENCH;
        s.set(0, PULSE_US as f32, 3).unwrap();
        let single = s.timing().max_rate_for(axes as u32 - 1);
        s.dual_edge = true;
        let cap = s.timing().max_rate_for(axes as u32 - 1);
        assert!(info.contains(&format!("[MSG:max step rate {} Hz dual-edge]", s.timing().max_rate_hz())), "{info}");
        let hz = cap as f64 * 0.995;
        assert!(hz > single as f64 * 1.2, "{axes} axes: dual-edge {hz} Hz vs full pulses {single} Hz");
        ok(&mut b, "G91");
        let mut want = [0i64; 7];
        let mut total = 0usize;
        for k in 0..12 {
            let mut steps: Vec<i64> = RATIO[..axes].iter().map(|&r| 200 * r as i64).collect();
            if axes > 1 {
                steps[1] = if k % 2 == 0 { 200 } else { -200 };
            }
            for (w, s) in want.iter_mut().zip(&steps) {
                *w += s;
                total += s.unsigned_abs() as usize;
            }
            ok(&mut b, &ddastep_bench::emu::changes::g1_line(&steps, hz));
        }
        wait_idle(&mut b, 3.0);
        let t = toggles(&b);
        let r = b.report();
        eprintln!("{axes} axes at {hz:.0} Hz (dual-edge cap {cap}, full-pulse cap {single}): overruns {}, min spacing {:?} cycles", r.overruns, &min_spacing(&t)[..axes]);
        assert_eq!(net(&t), want, "{axes} axes");
        assert_eq!(t.len(), total, "{axes} axes: toggles");
        assert!(min_spacing(&t)[..axes].iter().all(|&m| m >= pulse_cycles(PULSE_US)), "{axes} axes");
        for (name, a) in &r.axes.0[..axes] {
            assert!(a.min_dir_setup_ns.is_none_or(|d| d >= 5000.0), "{name}: {a:?}");
        }
        assert_eq!(r.overruns, 0, "{axes} axes");
    }
}

/// `$580` is a setting like `$2`: changing it rebuilds the step output in place, no MCU reset
/// (the step pins are driven low first, so the engine's shadow of their level is right), `$$`
/// lists it, an image without it runs single-edge.
#[test]
fn switching_the_mode_in_place_starts_with_the_pins_low() {
    let mut b = boot();
    assert!(reply(&mut b, "$$").contains("$580=0\r\n"));
    ok(&mut b, "G91 G1 X0.03 F600");
    wait_idle(&mut b, 1.0);
    assert_eq!(steps(&b).len(), 3, "single-edge: three pulses");
    assert_eq!(toggles(&b).len(), 6);
    let banners = b.serial_output().matches("Grbl").count();
    ok(&mut b, "$580=1");
    b.run_seconds(0.1).unwrap();
    assert_eq!(b.serial_output().matches("Grbl").count(), banners, "a banner after $580=1");
    assert!(b.system_resets().is_empty(), "MCU reset at {:?}", b.system_resets());
    assert!(reply(&mut b, "$$").contains("$580=1\r\n"));
    assert!(reply(&mut b, "$I").contains(" Hz dual-edge]"));
    let mark = b.edges().len();
    ok(&mut b, "G91 G1 X0.03 F600");
    wait_idle(&mut b, 1.0);
    let x: Vec<bool> = b.edges()[mark..].iter().filter(|e| e.port == 1 && e.pin == ddastep::board::STEP_PINS[0]).map(|e| e.level).collect();
    assert_eq!(x, [true, false, true], "three toggles from low");
    // The mode is in the stored image (it holds after a power cycle).
    assert!(stored(&mut b).unwrap().settings.dual_edge);
}
