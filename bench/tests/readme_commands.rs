//! Every command README.md shows, run exactly as written (from a scratch directory inside the
//! workspace, with `bench` and `.ci` linked in and the files the commands name put there), or skipped
//! with the reason written here. A command added to the README fails this test until it is
//! listed below, so the README's commands cannot rot unnoticed.

use std::path::{Path, PathBuf};
use std::process::Command;

// the repository root
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").canonicalize().unwrap()
}

// shell commands README.md shows: lines of ```sh blocks (without `# comments`) and inline code
// spans that start with `cargo `, `bash ` or `socat `
fn readme_commands(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_sh = false;
    for line in text.lines() {
        let t = line.trim();
        if t.starts_with("```") {
            in_sh = !in_sh && t == "```sh";
            continue;
        }
        if in_sh {
            let cmd = t.split(" # ").next().unwrap().trim();
            if !cmd.is_empty() {
                out.push(cmd.to_string());
            }
            continue;
        }
        for (i, span) in line.split('`').enumerate() {
            let is_cmd = ["cargo ", "bash ", "socat "].iter().any(|p| span.starts_with(p));
            if i % 2 == 1 && is_cmd {
                out.push(span.to_string());
            }
        }
    }
    // a continued line (ending in `\`) joins the next
    let mut joined: Vec<String> = Vec::new();
    for c in out {
        match joined.last_mut() {
            Some(prev) if prev.ends_with('\\') => {
                prev.pop();
                prev.push_str(c.trim());
            }
            _ => joined.push(c),
        }
    }
    let mut seen = std::collections::HashSet::new();
    joined.retain(|c| seen.insert(c.clone()));
    joined
}

/// What the test does with a README command.
enum Plan {
    /// Run it; exit status 0 and these files must exist afterwards.
    Run(&'static [&'static str]),
    /// Not run, for this reason.
    Skip(&'static str),
}

// every README command and what to do with it
fn plan(cmd: &str) -> Option<Plan> {
    use Plan::*;
    Some(match cmd {
        "bash .ci/setup && cargo sim" => Run(&[]),
        "bash .ci/run --fresh" => Skip("removes Debian packages, then runs the whole suite: CI's job"),
        "cargo la" => Skip("the checker's name in prose; the forms with a capture run"),
        "cargo test-host" => Skip("the test suite this test belongs to (CI runs it in .ci/run)"),
        "cargo build --release" => Run(&[]),
        "cargo test -p ddastep --target host-tuple" => Skip("the library's tests: part of cargo test-host, which CI runs"),
        "cargo xtask cycles" => Run(&[]),
        "cargo run --release" => Skip("flashes a board: needs a debug probe and probe-rs"),
        "cargo sim -- --help" => Run(&[]),
        "cargo sim -- --serve" => Skip("serves until Ctrl-C; the --max-seconds form below runs"),
        "cargo la -- CAPTURE" => Skip("placeholder for a file; the concrete `cargo la` commands run"),
        "cargo bench-host" => Skip("benchmarks: minutes of both cores, numbers only"),
        "cargo sim" => Run(&[]),
        "cargo sim -- --gcode bench/demo/fast_532.gcode --vcd fast.vcd" => Run(&["fast.vcd"]),
        "cargo la -- fast.vcd --expect 5:3:2" => Run(&[]),
        "cargo sim -- --gcode bench/demo/fast_532.gcode" => Run(&[]),
        "cargo bench -p ddastep-bench --target host-tuple --bench plan_line" => {
            Skip("a benchmark: numbers only, a minute of the emulator")
        }
        "cargo build --release && arm-none-eabi-size target/thumbv7m-none-eabi/release/ddastep" => {
            Skip("run from the repository root by bench/tests/firmware_size.rs (the same size check)")
        }
        "cargo sim -- --point 7@200000" => Run(&[]),
        "cargo sim -- --floor" => Run(&[]),
        "cargo bench --target host-tuple -p ddastep-la --bench la_throughput" => {
            Skip("a benchmark: numbers only, half a minute")
        }
        "cargo sim -- --vcd paper.vcd --json paper.json" => Run(&["paper.vcd", "paper.json"]),
        "cargo sim -- --gcode my.gcode --max-seconds 5 --pin PA0@0.25=0" => Run(&[]),
        "cargo sim -- --machine bench/demo/gantry300.toml" => Run(&[]),
        "cargo sim -- --machine bench/demo/encoder_x.toml" => Run(&[]),
        "cargo sim -- --sweep" => Skip("the step-rate benchmark: about a minute of both cores"),
        "cargo sim -- --sweep --dual-edge" => Skip("the same benchmark in dual-edge mode: about a minute of both cores"),
        "cargo sim -- --sweep --dma" => Skip("the same benchmark in DMA burst mode: several minutes of both cores"),
        "cargo sim -- --serve --pty-link /tmp/ttyBLUEPILL --tcp 127.0.0.1:23000 --max-seconds 2" => Run(&[]),
        "socat pty,raw,echo=0,link=/tmp/ttyGRBL tcp:127.0.0.1:23000" => {
            Skip("bridges to a running --serve until stopped; socat is optional (TCP is tested in serve_senders)")
        }
        c if c.starts_with("sigrok-cli -d fx2lafw") => Skip("captures from a logic analyzer on USB"),
        "cargo la -- capture.vcd --expect 5:3:2 --plot capture.png --dir-invert" => Run(&["capture.png"]),
        "cargo la -- capture.vcd --map X=D0,Y=D1,Z=D2 --dir X=D3,Y=D4,Z=D5 --expect 5:3:2" => Run(&[]),
        "cargo la -- capture.vcd --json report.json" => Run(&["report.json"]),
        _ => return None,
    })
}

// the files a command reads, put in the scratch directory
fn prepare(dir: &Path, cmd: &str) {
    let fixtures = root().join("bench/la/fixtures");
    let capture = std::fs::read_to_string(fixtures.join("bresenham_532.vcd")).unwrap();
    if cmd.contains("capture.vcd --map") {
        // a capture without --channels names: sigrok's D0..D5
        let mut unnamed = capture.clone();
        for (name, d) in [("X_STEP", "D0"), ("Y_STEP", "D1"), ("Z_STEP", "D2"), ("X_DIR", "D3"), ("Y_DIR", "D4"), ("Z_DIR", "D5")] {
            unnamed = unnamed.replace(&format!(" {name} $end"), &format!(" {d} $end"));
        }
        std::fs::write(dir.join("capture.vcd"), unnamed).unwrap();
    } else if cmd.contains("capture.vcd") {
        std::fs::write(dir.join("capture.vcd"), capture).unwrap();
    }
    if cmd.contains("my.gcode") {
        std::fs::copy(root().join("bench/demo/paper_532.gcode"), dir.join("my.gcode")).unwrap();
    }
}

#[test]
fn every_readme_command_runs_as_written() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let commands = readme_commands(&readme);
    assert!(commands.len() >= 15, "{commands:?}");
    let unknown: Vec<_> = commands.iter().filter(|c| plan(c).is_none()).collect();
    assert!(unknown.is_empty(), "README commands this test does not know (add them to `plan`): {unknown:?}");

    // A scratch directory inside the workspace: cargo finds the workspace from there, and the
    // relative paths the README uses (bench/demo/..., .ci/setup) resolve through links.
    let dir = root().join("target/readme-commands");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for linked in ["bench", ".ci"] {
        std::os::unix::fs::symlink(root().join(linked), dir.join(linked)).unwrap();
    }
    let mut report = Vec::new();
    for cmd in &commands {
        match plan(cmd).unwrap() {
            Plan::Skip(why) => report.push(format!("skipped  {cmd}  ({why})")),
            Plan::Run(files) => {
                prepare(&dir, cmd);
                let out = Command::new("bash")
                    .arg("-c")
                    .arg(cmd)
                    .current_dir(&dir)
                    .env_remove("CARGO_ENCODED_RUSTFLAGS")
                    .env_remove("RUSTFLAGS")
                    .env_remove("CARGO_TARGET_DIR")
                    .env("CARGO_TARGET_DIR", std::env::var_os("CARGO_TARGET_DIR").unwrap_or_else(|| root().join("target").into()))
                    .output()
                    .unwrap();
                let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
                assert!(out.status.success(), "`{cmd}` failed ({}):\n{text}", out.status);
                for f in files {
                    assert!(dir.join(f).exists(), "`{cmd}` did not write {f}");
                }
                report.push(format!("ran      {cmd}"));
            }
        }
    }
    println!("{}", report.join("\n"));
    // The issue's pair: a 7-axis bench VCD of a 3-axis move (there and back) checks against a
    // 3-term ratio.
    let out = Command::new("bash")
        .arg("-c")
        .arg("cargo la -- fast.vcd --expect 5:3:2")
        .current_dir(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("X:Y:Z = 10000:6000:4000 = 5:3:2 exact") && stdout.contains("no steps on A, B, C, U"), "{stdout}");
}
