//! The summary `cargo sim` prints, held against what the firmware measures of itself (`$I`'s
//! DWT self-report of the step interrupt) on the paper demo, and its slave deviation on a job
//! of many moves.

use ddastep_bench::emu::{firmware_elf, gcode_lines, repo_root, Board, Report, DIR_PINS, HZ, STEP_PINS};
use ddastep_bench::la::{Analyzer, AxisChannels, Config};

// the largest slave deviation of the whole run taken as one straight line (the summary's
// figure before it went per move)
fn one_line_deviation(b: &Board) -> f64 {
    let channels = (0..7).map(|i| AxisChannels::new(&i.to_string(), 2 * i, Some(2 * i + 1))).collect();
    let mut la = Analyzer::new(Config::new(channels)).unwrap();
    for e in b.edges().iter().filter(|e| e.port == 1) {
        let ch = STEP_PINS.iter().position(|&p| p == e.pin).map(|a| 2 * a).or_else(|| DIR_PINS.iter().position(|&p| p == e.pin).map(|a| 2 * a + 1));
        if let Some(ch) = ch {
            la.edge(e.cycle * 1_000_000 / 72, ch, e.level);
        }
    }
    la.finish().axes.iter().filter_map(|a| a.max_deviation_steps).fold(0.0, f64::max)
}

// boot, stream a demo job like `cargo sim` does, run until the pins are quiet for 50 ms
fn run_job(path: &str) -> Board {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    b.run_seconds(0.05).unwrap();
    let text = std::fs::read_to_string(repo_root().join(path)).expect("demo G-code");
    for line in gcode_lines(&text) {
        b.send_line_wait_ok(&line).unwrap_or_else(|e| panic!("{line}: {e}"));
    }
    assert!(b.run_until_quiet(HZ / 20, 60 * HZ).unwrap(), "motion did not end");
    b
}

// the first percentage on the summary's first line that starts with "peak"
fn headline_load(r: &Report) -> f64 {
    let text = r.to_string();
    let line = text.lines().find(|l| l.starts_with("peak")).expect("a peak load line");
    let pct = line.split(':').nth(1).and_then(|t| t.trim().split(' ').next()).expect("a figure");
    pct.parse::<f64>().unwrap_or_else(|_| panic!("{line}")) / 100.0
}

// `$I`'s step-interrupt line: (mean body cycles, peak load) of the run so far
fn self_report(b: &mut Board) -> (f64, f64) {
    let info = b.send_line_wait_ok("$I").unwrap();
    let line = info.lines().find(|l| l.contains("step isr")).unwrap_or_else(|| panic!("{info}"));
    // [MSG:step isr 30/101.8/489 cycles min/mean/max, load 4.9 % peak 14.0 %]
    let mean = line.split("step isr ").nth(1).and_then(|t| t.split('/').nth(1)).and_then(|t| t.parse().ok()).unwrap_or_else(|| panic!("{line}"));
    let peak = line.split("peak ").nth(1).and_then(|t| t.split(' ').next()).and_then(|t| t.parse::<f64>().ok()).unwrap_or_else(|| panic!("{line}"));
    (mean, peak / 100.0)
}

#[test]
fn headline_load_agrees_with_the_firmware_self_report() {
    let mut b = run_job("bench/demo/paper_532.gcode");
    let r = b.report();
    let (fw_mean, fw_peak) = self_report(&mut b);
    let head = headline_load(&r);
    // `$I` times the step interrupt's body; the bench counts every handler from exception entry
    // to return. So the headline is at least `$I`'s peak, and at most that peak scaled by the
    // step interrupt's entry-to-return cycles over its body's (same entries), plus 5 points for
    // the other handlers (the engine's ramp half in TIM4's vector, SysTick's 1 kHz tick,
    // USART1; 2.8 points on this job).
    let scaled = fw_peak * r.step_isr.mean_cycles / fw_mean;
    eprintln!("headline {head:.4}, step ISR {:.4}, $I peak {fw_peak:.4} (scaled {scaled:.4}), not asleep {:.4}", r.step_isr_load_peak, r.cpu_load_peak);
    assert!(head >= fw_peak && head <= scaled + 0.05, "summary's peak load {head} vs `$I` peak {fw_peak} (scaled to entry-to-return {scaled})\n{r}");
    // The step interrupt alone, within 5 % of `$I`'s peak scaled the same way.
    assert!((r.step_isr_load_peak - scaled).abs() <= 0.05 * scaled, "step ISR peak {} vs {scaled}", r.step_isr_load_peak);
    assert!(r.interrupt_load_peak >= r.step_isr_load_peak && r.cpu_load_peak >= r.interrupt_load_peak);
}

#[test]
fn slave_deviation_is_per_move() {
    // 361 moves round a circle: as one straight line the slaves would be thousands of steps
    // off it; each move against its own line is within one step.
    let b = run_job("bench/demo/circle360.gcode");
    let r = b.report();
    let dev = r.max_slave_deviation_steps.expect("computed in interrupt mode");
    assert!(dev <= 1.0, "max slave deviation {dev} steps over {} moves\n{r}", r.moves);
    assert!(r.moves >= 361, "{} moves", r.moves);
    // The figure before: the whole run against one line (the `la` checker over every edge).
    let whole = one_line_deviation(&b);
    assert!(whole > 100.0, "as one line: {whole} steps");
    eprintln!("circle360: per move {dev:.3} steps over {} moves; as one line {whole:.1} steps", r.moves);
    // The paper demo (two moves, 5:3:2) keeps its figure.
    let r = run_job("bench/demo/paper_532.gcode").report();
    assert_eq!(r.max_slave_deviation_steps.map(|d| (d * 1000.0).round() / 1000.0), Some(0.4), "{r}");
    assert!(r.to_string().contains("max slave deviation (each move against its own line, 2 moves): 0.400 steps"), "{r}");
}

#[test]
fn a_move_a_jog_cancel_dropped_does_not_join_the_next() {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    b.run_seconds(0.05).unwrap();
    // A diagonal jog cancelled halfway (its move never finishes), then an X-only move.
    b.send_line_wait_ok("$J=G91 X20 Y20 F600").unwrap();
    b.run_seconds(0.5).unwrap();
    b.serial_send_urgent(&[0x85]);
    assert!(b.run_until_quiet(HZ / 20, 2 * HZ).unwrap());
    b.run_seconds(0.1).unwrap();
    b.send_line_wait_ok("G91 G1 X2 F600").unwrap();
    assert!(b.run_until_quiet(HZ / 20, 5 * HZ).unwrap());
    let r = b.report();
    let y = r.axes.0[1].1.rising_edges;
    assert!(y > 100 && y < 5000, "the jog was cut: Y {y}\n{r}");
    let dev = r.max_slave_deviation_steps.unwrap();
    assert!(dev <= 1.0, "{dev} steps: the dropped move joined the next\n{r}");
}
