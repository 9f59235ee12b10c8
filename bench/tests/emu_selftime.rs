//! The firmware's self-measurement (`$I`'s `[MSG:step isr ...]` line, DWT CYCCNT around the
//! step handler's body) against the bench's own measurement of the same handler (exception
//! entry to the end of its return), over the paper demo.
//!
//! The two differ by a fixed frame: exception entry and return plus the instructions before
//! the first CYCCNT read and after the second. So the means differ by that frame, and the
//! spread (max - mean) is the same on both sides; the entry counts agree.

use ddastep_bench::emu::{firmware_elf, gcode_lines, repo_root, Board, HZ};

/// (min, mean, max, load %, peak load %) from `[MSG:step isr 190/191.4/220 cycles min/mean/max, load 1.2 % peak 3.4 %]`.
fn parse(info: &str) -> (f64, f64, f64, f64, f64) {
    let line = info.lines().find(|l| l.starts_with("[MSG:step isr ")).unwrap_or_else(|| panic!("no step isr line in {info:?}"));
    let nums: Vec<f64> = line
        .split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .filter(|s| !s.is_empty() && *s != ".")
        .map(|s| s.parse().unwrap())
        .collect();
    assert_eq!(nums.len(), 5, "{line}");
    (nums[0], nums[1], nums[2], nums[3], nums[4])
}

#[test]
fn self_report_matches_the_bench_measurement_of_the_handler() {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    b.run_seconds(0.05).unwrap();
    // Start both windows together: `$I` restarts the firmware's.
    b.send_line_wait_ok("$I").unwrap();
    b.reset_step_isr_stats();
    let start = b.cycles();
    let text = std::fs::read_to_string(repo_root().join("bench/demo/paper_532.gcode")).unwrap();
    for line in gcode_lines(&text) {
        b.send_line_wait_ok(&line).unwrap();
    }
    assert!(b.run_until_quiet(HZ / 20, 10 * HZ).unwrap(), "motion did not end");
    let bench = b.report().step_isr;
    let info = b.send_line_wait_ok("$I").unwrap();
    let (min, mean, max, load, peak) = parse(&info);
    println!("firmware: {min}/{mean}/{max} cycles, load {load} % peak {peak} %");
    println!("bench:    {}/{:.1}/{} cycles over {} entries", bench.min_cycles, bench.mean_cycles, bench.max_cycles, bench.entries);

    // The frame outside the body: entry 14 + return 12 at 2 wait states, plus the prologue up
    // to the first read and the epilogue from the second (RTIC's BASEPRI, the statistics).
    let frame = bench.mean_cycles - mean;
    assert!((26.0..120.0).contains(&frame), "frame {frame:.1}");
    assert!(min <= bench.min_cycles as f64 && max <= bench.max_cycles as f64);
    let spread = |hi: f64, lo: f64| hi - lo;
    let d = spread(max, mean) - spread(bench.max_cycles as f64, bench.mean_cycles);
    assert!(d.abs() <= 20.0, "max - mean: firmware {} vs bench {}", spread(max, mean), spread(bench.max_cycles as f64, bench.mean_cycles));

    // Load: body cycles over elapsed time; the bench's includes the frame, so it is higher.
    let elapsed = (b.cycles() - start) as f64;
    let bench_load = 100.0 * bench.total_cycles as f64 / elapsed;
    assert!(load > 0.0 && load <= bench_load * 1.05, "firmware {load} % vs bench {bench_load:.2} %");
    assert!(load >= bench_load * (1.0 - frame / bench.mean_cycles) * 0.9, "firmware {load} % vs bench {bench_load:.2} %");
    assert!(peak >= load, "peak {peak} load {load}");
}
