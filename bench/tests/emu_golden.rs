//! Golden trace (STYLE #9): the release firmware runs the paper demo (bench/demo/paper_532.gcode)
//! on the virtual bench and its pin numbers are compared with bench/golden/paper_532.json, so a
//! change that moves a pulse shows up in review.
//!
//! Compared exactly: rising edges and net steps per axis, replies, overruns. Within a tolerance:
//! max rate per axis (0.5 %; a slave also one master period per 1 ms bin), slave deviation (≤ golden + 0.1 step), step-ISR mean/max modeled
//! cycles (±25 %: they follow code size and layout). Checked against the settings, not the
//! golden: step high ≥ 3 µs (`$0` default), dir setup ≥ 5 µs (`$29` default). Timings that
//! legitimately move with the code (pulse widths, BSRR offsets) are recorded in the file for
//! review but not compared.
//!
//! After an intended change: `UPDATE_GOLDEN=1 cargo test -p ddastep-bench --test emu_golden`
//! rewrites the file; commit it with the change. Every run prints the differences.

use ddastep_bench::emu::{firmware_elf, gcode_lines, repo_root, Board, Report, HZ};
use serde_json::{json, Value};

const DEMO: &str = "bench/demo/paper_532.gcode";
const GOLDEN: &str = "bench/golden/paper_532.json";

/// Settings defaults the demo runs with: `$0` = 3 µs, `$29` = 5 µs.
const MIN_HIGH_NS: f64 = 3_000.0;
const MIN_DIR_SETUP_NS: f64 = 5_000.0;
const RATE_TOLERANCE: f64 = 0.005;
const ISR_TOLERANCE: f64 = 0.25;

// a board after reset with its whole welcome line received
fn boot() -> Board {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    let banner = |b: &Board| b.serial_output().split_once("Grbl").is_some_and(|(_, rest)| rest.contains('\n'));
    assert!(b.run_until(HZ / 2, banner).unwrap(), "no banner: {:?}", b.serial_output());
    b
}

// boot, stream the demo like a sender, run until the pins are quiet for 50 ms
fn run_demo() -> (Report, Vec<String>) {
    let mut b = boot();
    let text = std::fs::read_to_string(repo_root().join(DEMO)).expect("demo G-code");
    let mut replies = Vec::new();
    for line in gcode_lines(&text) {
        let r = b.send_line_wait_ok(&line).unwrap_or_else(|e| panic!("{line}: {e}"));
        replies.push(format!("{line} -> {}", r.trim_end().replace("\r\n", " | ")));
    }
    assert!(b.run_until_quiet(HZ / 20, 10 * HZ).unwrap(), "motion did not end");
    (b.report(), replies)
}

// `v` rounded to `step` (float noise stays out of the file)
fn round(v: Option<f64>, step: f64) -> Option<f64> {
    v.map(|v| (v / step).round() * step)
}

// the fields the golden file keeps
fn golden_of(r: &Report, replies: &[String]) -> Value {
    let axes: serde_json::Map<String, Value> = r
        .axes
        .0
        .iter()
        .filter(|(_, a)| a.rising_edges > 0)
        .map(|(name, a)| {
            (name.clone(), json!({
                "rising_edges": a.rising_edges,
                "net_steps": a.net_steps,
                "max_rate_hz": round(Some(a.max_rate_hz), 0.1),
                "min_high_ns": round(a.min_high_ns, 1.0),
                "min_low_ns": round(a.min_low_ns, 1.0),
                "min_dir_setup_ns": round(a.min_dir_setup_ns, 1.0),
            }))
        })
        .collect();
    json!({
        "gcode": DEMO,
        "replies": replies,
        "axes": axes,
        "max_slave_deviation_steps": round(r.max_slave_deviation_steps, 0.001),
        "overruns": r.overruns,
        "step_isr": {
            "entries": r.step_isr.entries,
            "mean_cycles": (r.step_isr.mean_cycles * 10.0).round() / 10.0,
            "max_cycles": r.step_isr.max_cycles,
            "bsrr_offset_min_cycles": r.step_isr.bsrr_offset_min_cycles,
            "bsrr_offset_max_cycles": r.step_isr.bsrr_offset_max_cycles,
        },
    })
}

// every leaf that differs, as "path: golden -> now"
fn diff(path: &str, want: &Value, got: &Value, out: &mut Vec<String>) {
    match (want, got) {
        (Value::Object(a), Value::Object(b)) => {
            for k in a.keys().chain(b.keys().filter(|k| !a.contains_key(*k))) {
                diff(&format!("{path}.{k}"), a.get(k).unwrap_or(&Value::Null), b.get(k).unwrap_or(&Value::Null), out);
            }
        }
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                diff(&format!("{path}[{i}]"), x, y, out);
            }
        }
        _ if want != got => out.push(format!("{path}: {want} -> {got}")),
        _ => {}
    }
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

#[test]
fn paper_demo_matches_the_golden_trace() {
    let (report, replies) = run_demo();
    let got = golden_of(&report, &replies);
    let path = repo_root().join(GOLDEN);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::write(&path, serde_json::to_string_pretty(&got).unwrap() + "\n").unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let want: Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("golden file (UPDATE_GOLDEN=1 writes it)")).unwrap();
    let mut changes = Vec::new();
    diff("", &want, &got, &mut changes);
    if !changes.is_empty() {
        eprintln!("differences from {GOLDEN} (golden -> now):\n  {}", changes.join("\n  "));
    }

    let mut failures = Vec::new();
    let mut check = |ok: bool, what: String| {
        if !ok {
            failures.push(what);
        }
    };
    check(want["replies"] == got["replies"], format!("replies: {} -> {}", want["replies"], got["replies"]));
    check(want["overruns"] == got["overruns"], format!("overruns {}", got["overruns"]));
    let (wa, ga) = (want["axes"].as_object().unwrap(), got["axes"].as_object().unwrap());
    check(wa.keys().eq(ga.keys()), format!("moving axes {:?} -> {:?}", wa.keys().collect::<Vec<_>>(), ga.keys().collect::<Vec<_>>()));
    // The master's rate: the fastest axis's.
    let master_hz = wa.values().map(|w| f(&w["max_rate_hz"])).fold(0.0, f64::max);
    for (name, w) in wa {
        let g = &got["axes"][name];
        for key in ["rising_edges", "net_steps"] {
            check(w[key] == g[key], format!("{name}.{key}: {} -> {}", w[key], g[key]));
        }
        let (wr, gr) = (f(&w["max_rate_hz"]), f(&g["max_rate_hz"]));
        // A slave's periods are whole master periods (2 or 3 for Z at 5:2), so the mean over a
        // 1 ms bin moves by up to a master period per bin with where the bin's edges fall (the
        // code's placement shifts them): that much more room for slaves.
        let tol = if wr < master_hz { RATE_TOLERANCE + 1000.0 / master_hz } else { RATE_TOLERANCE };
        check((gr - wr).abs() <= tol * wr, format!("{name}.max_rate_hz: {wr} -> {gr} (±{:.1} %)", tol * 100.0));
        check(f(&g["min_high_ns"]) >= MIN_HIGH_NS, format!("{name}.min_high_ns {} < {MIN_HIGH_NS}", g["min_high_ns"]));
        check(f(&g["min_dir_setup_ns"]) >= MIN_DIR_SETUP_NS, format!("{name}.min_dir_setup_ns {} < {MIN_DIR_SETUP_NS}", g["min_dir_setup_ns"]));
    }
    let (wd, gd) = (f(&want["max_slave_deviation_steps"]), f(&got["max_slave_deviation_steps"]));
    check(gd <= wd + 0.1 && gd <= 0.5, format!("max_slave_deviation_steps: {wd} -> {gd}"));
    for key in ["mean_cycles", "max_cycles"] {
        let (w, g) = (f(&want["step_isr"][key]), f(&got["step_isr"][key]));
        check((g - w).abs() <= ISR_TOLERANCE * w, format!("step_isr.{key}: {w} -> {g} (±{} %)", ISR_TOLERANCE * 100.0));
    }
    assert!(failures.is_empty(), "paper demo differs from {GOLDEN}:\n  {}\n(after an intended change: UPDATE_GOLDEN=1)", failures.join("\n  "));
}

#[test]
fn net_steps_follow_the_grbl_dir_convention() {
    let mut b = boot();
    for line in ["G91", "G1 X1 Y-0.5 F3000"] {
        b.send_line_wait_ok(line).unwrap();
    }
    assert!(b.run_until_quiet(HZ / 20, 2 * HZ).unwrap());
    let r = b.report();
    let net: Vec<i64> = r.axes.0.iter().map(|(_, a)| a.net_steps).collect();
    assert_eq!(net, [250, -125, 0, 0, 0, 0, 0], "dir low = positive (default 250 steps/mm)");
    assert!(r.cpu_load_peak < 1.0 && r.cpu_load_peak_with_boot >= r.cpu_load_peak, "{} / {}", r.cpu_load_peak, r.cpu_load_peak_with_boot);
    assert!(r.boot_cycles.is_some());
}
