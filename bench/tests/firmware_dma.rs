//! Firmware in the loop, DMA burst step output (`$581=1`): TIM2 paces every edge and DMA stores
//! the words the engine buffered. Exact counts and the paper's pattern, pulse and low time,
//! direction setup, moves at the mode's cap, feed hold and stop latency within the buffers'
//! bound, and the setting itself.

mod firmware_rig;

use ddastep::grbl::settings::Settings;
use ddastep_bench::emu::{gcode_lines, HZ};
use firmware_rig::*;

/// The late fills `$I`'s `step fill` line reports (`…, late N]`).
fn late_fills(info: &str) -> Option<u32> {
    info.split(", late ").nth(1)?.split(']').next()?.parse().ok()
}

/// Steps per axis from the pins.
fn counts(s: &[Step]) -> [usize; 7] {
    let mut c = [0; 7];
    for st in s {
        c[st.axis] += 1;
    }
    c
}

/// Master-step (X) rising-edge cycles.
fn x_times(s: &[Step]) -> Vec<u64> {
    s.iter().filter(|s| s.axis == 0).map(|s| s.cycle).collect()
}

#[test]
fn paper_532_is_exact_with_the_papers_pattern() {
    let mut b = boot_dma(Settings::BENCH, false);
    assert!(reply(&mut b, "$I").contains(" Hz DMA]"));
    ok(&mut b, "G91");
    ok(&mut b, "G1 X50 Y30 Z20 F36986.484");
    wait_idle(&mut b, 2.0);
    // One move, one end (the bench once counted a `finish` twice when it stopped the
    // emulator before that block for an event and entered it again).
    assert_eq!(b.move_ends().len(), 1, "{:?}", b.move_ends());
    let s = steps(&b);
    assert_eq!(net(&s), [5000, 3000, 2000, 0, 0, 0, 0]);
    assert_eq!(assert_paper_pattern(&s), 5000);
    let r = assert_paper_cruise(&b, &s, 3000.0);
    for (name, a) in &r.axes.0[..3] {
        assert!(a.min_dir_setup_ns.is_none_or(|d| d >= 5000.0), "{name}: {a:?}");
    }
    assert_eq!(r.overruns, 0);
    assert!(r.max_slave_deviation_steps.is_some_and(|d| d <= 0.5), "{:?}", r.max_slave_deviation_steps);
}

#[test]
fn slave_deviation_is_left_out_with_several_moves() {
    // The fill runs the engine ahead of the pins: its move ends cannot split the pin edges.
    let mut b = boot_dma(Settings::BENCH, false);
    ok(&mut b, "G91");
    ok(&mut b, "G1 X5 Y3 Z2 F6000");
    ok(&mut b, "G1 X-3 Y5 Z1");
    wait_idle(&mut b, 2.0);
    let r = b.report();
    assert_eq!(r.max_slave_deviation_steps, None, "{r}");
    assert!(r.to_string().contains("max slave deviation: not computed (DMA burst mode"), "{r}");
}

#[test]
fn fast_532_is_exact_at_200_khz_in_both_edge_modes() {
    let g = std::fs::read_to_string(ddastep_bench::emu::repo_root().join("bench/demo/fast_532.gcode")).unwrap();
    for dual in [false, true] {
        let mut b = boot_dma(Settings::BENCH, dual);
        for l in gcode_lines(&g) {
            ok(&mut b, &l);
        }
        wait_idle(&mut b, 3.0);
        let s = if dual { toggles(&b) } else { steps(&b) };
        assert_eq!(counts(&s)[..3], [10_000, 6_000, 4_000], "dual {dual}");
        assert_eq!(net(&s), [0; 7]);
        let x = x_times(&s);
        let rate = 1000.0 * HZ as f64 / (x[3000] - x[2000]) as f64;
        assert!((rate - 200_000.0).abs() < 1_000.0, "cruise {rate} Hz");
        let r = b.report();
        let pulse_ns = 1000.0; // the demo's `$0=1`
        for (name, a) in &r.axes.0[..3] {
            assert!(a.min_high_ns.unwrap() >= pulse_ns && a.min_low_ns.unwrap() >= pulse_ns, "{name}: {a:?}");
            assert!(a.min_dir_setup_ns.unwrap() >= 5000.0, "{name}: {a:?}");
        }
        assert_eq!(r.overruns, 0, "dual {dual}");
    }
}

/// Back-to-back moves (12 segments joined at speed, Y reversing at every junction) on 1, 3 and 7
/// axes at 99.5 % of the DMA cap `$I` prints: every step reaches the pins, pulses and low
/// times ≥ `$0`, direction setup ≥ `$29`, no DMA half refilled late.
#[test]
fn back_to_back_moves_at_the_dma_cap_keep_every_step() {
    use ddastep_bench::emu::sweep::{settings_lines, RATIO};
    // Full pulses and dual-edge (each step one toggle: its own cap, counted on both edges).
    // The sender waits `wait` cycles before each line: where the moves' ramp work and the
    // serial bytes land against the halves (late fills showed at some alignments only).
    for (axes, dual, wait) in [(1usize, false, 0u64), (3, false, 0), (7, false, 0), (1, true, 0), (3, true, 0), (7, true, 0), (1, false, 40_000), (3, false, 40_000), (7, false, 40_000), (1, false, 88_000), (7, false, 96_000), (7, false, 20_000)] {
        let mut b = boot_dma(Settings::BENCH, dual);
        for l in settings_lines() {
            ok(&mut b, &l);
        }
        let info = reply(&mut b, "$I");
        let mut s = Settings { dma_burst: true, dual_edge: dual, ..Settings::BENCH };
        s.set(0, ddastep_bench::emu::sweep::PULSE_US as f32, 3).unwrap();
        let cap = s.timing().max_rate_for(axes as u32 - 1);
        let name = if dual { "dual-edge DMA" } else { "DMA" };
        assert!(info.contains(&format!("[MSG:max step rate {} Hz {name}]", s.timing().max_rate_hz())), "{info}");
        let hz = cap as f64 * 0.995;
        ok(&mut b, "G91");
        eprintln!("rx overruns {}", b.usart_rx_overruns());
        let mut want = [0i64; 7];
        for k in 0..12 {
            let mut steps: Vec<i64> = RATIO[..axes].iter().map(|&r| 200 * r as i64).collect();
            if axes > 1 {
                steps[1] = if k % 2 == 0 { 200 } else { -200 };
            }
            for (w, s) in want.iter_mut().zip(&steps) {
                *w += s;
            }
            let l = ddastep_bench::emu::changes::g1_line(&steps, hz);
            b.run_for(wait).unwrap();
            let r = reply(&mut b, &l);
            assert!(r.contains("ok"), "{l}: {r}; rx overruns {}", b.usart_rx_overruns());
        }
        wait_idle(&mut b, 3.0);
        let st = if dual { toggles(&b) } else { steps(&b) };
        let r = b.report();
        let late = late_fills(&reply(&mut b, "$I"));
        eprintln!("{axes} axes{} at {hz:.0} Hz (DMA cap {cap}), the sender waiting {wait} cycles a line: overruns {}, late fills {late:?}", if dual { " dual-edge" } else { "" }, r.overruns);
        assert_eq!(late, Some(0), "{axes} axes: the firmware's late fills");
        assert_eq!(net(&st), want, "{axes} axes");
        for (name, a) in &r.axes.0[..axes] {
            assert!(a.min_high_ns.unwrap() >= 500.0 && a.min_low_ns.unwrap() >= 500.0, "{name}: {a:?}");
            assert!(a.min_dir_setup_ns.is_none_or(|d| d >= 5000.0), "{name}: {a:?}");
        }
        assert_eq!(r.overruns, 0, "{axes} axes");
    }
}

/// Feed hold and a stop reach the pins within the buffers' bound: the time from the realtime
/// byte to the first step at a lower rate (hold) or to the last step (stop) exceeds interrupt
/// mode's by at most the buffered time (1 ms), and positions stay exact.
#[test]
fn hold_and_stop_latency_stay_within_the_buffer_bound() {
    let mut lat = [[0f64; 2]; 2];
    for (m, dma) in [false, true].into_iter().enumerate() {
        for (k, byte) in [b'!', 0x18u8].into_iter().enumerate() {
            let mut b = if dma { boot_dma(Settings::BENCH, false) } else { boot() };
            ok(&mut b, "G91");
            b.serial_send(b"G1 X500 F6000\n");
            b.run_seconds(0.3).unwrap();
            let mark = b.edges().len();
            let t0 = b.cycles();
            b.serial_send_urgent(&[byte]);
            b.run_seconds(0.3).unwrap();
            let s: Vec<u64> = steps(&b).iter().filter(|s| s.axis == 0 && s.cycle > t0).map(|s| s.cycle).collect();
            assert!(b.edges().len() > mark);
            // Cruise period before the byte: 10 kHz.
            let period = HZ as f64 / 10_000.0;
            let t = if byte == b'!' {
                // First gap clearly longer than cruise: the walk down has begun.
                let i = s.windows(2).position(|w| (w[1] - w[0]) as f64 > period * 1.02).expect("slows down");
                s[i]
            } else {
                *s.last().unwrap_or(&t0)
            };
            lat[m][k] = (t - t0) as f64 / HZ as f64 * 1e3;
            let p = status(&mut b);
            eprintln!("dma {dma} byte {byte:#x}: {:.3} ms; {p}", lat[m][k]);
        }
    }
    for k in 0..2 {
        assert!(lat[1][k] <= lat[0][k] + 1.0 + 0.05, "DMA {:.3} ms vs interrupt {:.3} ms", lat[1][k], lat[0][k]);
    }
}

/// `$581` is a setting like `$580`: changing it rebuilds the step output in place (no MCU reset,
/// no banner), `$$` lists it, `$I` names the mode; a pulse the buffers' layout cannot hold
/// rebuilds it with a layout that can.
#[test]
fn switching_to_dma_in_place_keeps_working() {
    let mut b = boot();
    assert!(reply(&mut b, "$$").contains("$581=0\r\n"));
    let banners = b.serial_output().matches("Grbl").count();
    ok(&mut b, "$581=1");
    b.run_seconds(0.1).unwrap();
    assert_eq!(b.serial_output().matches("Grbl").count(), banners, "a banner after $581=1");
    assert!(reply(&mut b, "$$").contains("$581=1\r\n"));
    assert!(reply(&mut b, "$I").contains(" Hz DMA]"));
    assert!(stored(&mut b).unwrap().settings.dma_burst);
    ok(&mut b, "G91 G1 X0.03 F600");
    wait_idle(&mut b, 1.0);
    assert_eq!(steps(&b).len(), 3);
    // 20 µs pulses need longer entries: a new layout, in place, and they hold.
    ok(&mut b, "$0=20");
    b.run_seconds(0.1).unwrap();
    assert_eq!(b.serial_output().matches("Grbl").count(), banners, "a banner after $0=20");
    let mark = b.edges().len();
    ok(&mut b, "G91 G1 X0.03 F600");
    wait_idle(&mut b, 1.0);
    let x: Vec<(u64, bool)> = b.edges()[mark..].iter().filter(|e| e.port == 1 && e.pin == ddastep::board::STEP_PINS[0]).map(|e| (e.cycle, e.level)).collect();
    assert_eq!(x.len(), 6);
    for w in x.chunks(2) {
        assert!(w[0].1 && !w[1].1 && w[1].0 - w[0].0 >= 20 * 72, "{x:?}");
    }
    assert!(b.system_resets().is_empty(), "MCU reset at {:?}", b.system_resets());
}

/// One axis at the DMA cap with full pulses (`$0=0.2`, a TMC driver's 100 ns with room: the
/// fill's cost binds, not the pulse): every step, high and low ≥ 200 ns, no overrun, and the
/// modeled CPU ≤ 95 % busy over the cruise (the fill's share printed).
#[test]
fn one_axis_runs_at_the_dma_cap() {
    use ddastep_bench::emu::sweep::settings_lines;
    let mut b = boot_dma(Settings::BENCH, false);
    for l in settings_lines() {
        ok(&mut b, &l);
    }
    ok(&mut b, "$0=0.2");
    let info = reply(&mut b, "$I");
    let mut s = Settings { dma_burst: true, ..Settings::BENCH };
    s.set(0, 0.2, 3).unwrap();
    let cap = s.timing().max_rate_hz();
    assert!(info.contains(&format!("[MSG:max step rate {cap} Hz DMA]")), "{info}");
    assert_eq!(cap, 1_000_000);
    ok(&mut b, "G91");
    ok(&mut b, &format!("G1 X400 F{:.3}", cap as f64 * 0.6));
    // (No status polls during the move: `wait_idle` asks every 10 ms, a sender every 125+.)
    b.run_seconds(0.06).unwrap();
    wait_idle(&mut b, 1.0);
    let st: Vec<Step> = steps(&b).into_iter().filter(|s| s.axis == 0).collect();
    assert_eq!(net(&st)[0], 40_000);
    let x: Vec<u64> = st.iter().map(|s| s.cycle).collect();
    let mid = x.len() / 2;
    let rate = 10_000.0 * HZ as f64 / (x[mid + 5_000] - x[mid - 5_000]) as f64;
    let (w0, w1) = (x[mid - 5_000].div_ceil(72_000), x[mid + 5_000] / 72_000);
    let cpu = b.window_loads(w0..w1).into_iter().fold(0.0, f64::max);
    let fill = b.window_isr_loads(w0..w1).into_iter().fold(0.0, f64::max);
    eprintln!("1 axis: cruise {rate:.0} Hz (cap {cap}), busiest ms: CPU {:.1} %, the fill {:.1} % (modeled, DMA bus cycles included)", cpu * 100.0, fill * 100.0);
    assert!((rate - cap as f64).abs() < cap as f64 * 0.01, "cruise {rate} Hz");
    assert!(cpu <= 0.95, "CPU {cpu}");
    let r = b.report();
    let a = &r.axes.0[0].1;
    assert!(a.min_high_ns.unwrap() >= 200.0 && a.min_low_ns.unwrap() >= 200.0, "{a:?}");
    assert_eq!(r.overruns, 0);
    // The firmware's own count of late fills agrees: none.
    let info = reply(&mut b, "$I");
    assert!(info.contains(", late 0]"), "{info}");
}

/// A fill that comes late (its interrupt held back longer than a half plays) is counted by the
/// firmware and reported by `$I`; on time, none is.
#[test]
fn a_late_fill_is_counted_and_reported() {
    use ddastep_bench::emu::dma::IRQ_CHANNEL1;
    for held_us in [0u64, 1200] {
        let mut b = boot_dma(Settings::BENCH, false);
        ok(&mut b, "$110=60000");
        ok(&mut b, "$120=100000");
        ok(&mut b, "G91");
        // One axis at 1000 mm/s · 100 steps/mm = 100 kHz cruise from 5 mm on; both halves
        // play in at most 1 ms at any rate, so a fill held 1.2 ms is late.
        ok(&mut b, "G1 X100 F60000");
        b.run_seconds(0.05).unwrap();
        b.hold_irq(IRQ_CHANNEL1, true);
        b.run_for(held_us * HZ / 1_000_000).unwrap();
        b.hold_irq(IRQ_CHANNEL1, false);
        wait_idle(&mut b, 1.0);
        let info = reply(&mut b, "$I");
        let late = late_fills(&info).unwrap_or_else(|| panic!("no late count: {info}"));
        eprintln!("fill interrupt held {held_us} µs: late {late}, the bench's DMA overruns {}", b.dma_overruns());
        if held_us == 0 {
            assert_eq!(late, 0, "{info}");
        } else {
            assert!(late >= 1, "{info}");
        }
    }
}
