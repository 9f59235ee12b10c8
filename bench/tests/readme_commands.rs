//! Every command README.md and `docs/*.md` show, run exactly as written (from a scratch directory
//! inside the workspace, with `bench` and `.ci` linked in and the files the commands name put
//! there), or skipped with the reason written here. A command that flashes a board is checked as
//! far as this machine allows: after `cargo xtask dist` the files it names exist (VERSION
//! substituted), and its subcommand and flags are in the tool's own help text when the tool is
//! installed. A command added to the README or the docs fails this test until it is listed below,
//! so the commands cannot rot unnoticed.

use std::path::{Path, PathBuf};
use std::process::Command;

// the repository root
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").canonicalize().unwrap()
}

// shell commands a page shows: lines of ```sh blocks (without `# comments`) and inline code
// spans that start with `cargo `, `bash `, `socat `, `python3 ` or `UPDATE_DOCS=1 `
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
            let is_cmd = ["cargo ", "bash ", "socat ", "python3 ", "UPDATE_DOCS=1 "].iter().any(|p| span.starts_with(p));
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
    /// Flashes a board, so not run: its files and its syntax are checked (`check_flash_command`).
    Board,
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
        "cargo xtask dist" => Run(&[]),
        "cargo doc" => Skip("the API docs of every workspace crate, named in prose (internals.md); minutes of rustdoc"),
        "cargo run --example step_move --target host-tuple" => Run(&[]),
        "bash .ci/setup" => Run(&[]),
        "cargo install probe-rs-tools --locked" => {
            Skip("installs probe-rs from crates.io (minutes of compiling); its download command is checked")
        }
        "probe-rs download --chip STM32F103C8 target/dist/ddastep-VERSION.elf" => Board,
        "st-flash write target/dist/ddastep-VERSION.bin 0x8000000" => Board,
        "stm32flash -w target/dist/ddastep-VERSION.bin -v -g 0x0 /dev/ttyUSB0" => Board,
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
        "cargo bench -p ddastep-bench --target host-tuple --bench ramp_half" => {
            Skip("a benchmark: numbers only, the emulator on two moves in both ramp shapes")
        }
        "cargo build --release && arm-none-eabi-size target/thumbv7m-none-eabi/release/ddastep" => {
            Skip("run from the repository root by bench/tests/firmware_size.rs (the same size check)")
        }
        "cargo sim -- --point 7@200000" => Run(&[]),
        "cargo sim -- --floor" => Run(&[]),
        "cargo sim -- --flash-kib 32" => Run(&[]),
        "cargo bench --target host-tuple -p ddastep-la --bench la_throughput" => {
            Skip("a benchmark: numbers only, half a minute")
        }
        "cargo sim -- --vcd paper.vcd --json paper.json" => Run(&["paper.vcd", "paper.json"]),
        "cargo la -- paper.vcd --plot paper_rates.png --pulses paper_pulses.png --pulses-at 75 --dir-invert" => {
            Run(&["paper_rates.png", "paper_pulses.png"])
        }
        "cargo sim -- --gcode bench/demo/scurve_532.gcode --vcd scurve.vcd" => Run(&["scurve.vcd"]),
        "cargo la -- scurve.vcd --plot scurve_rates.png --dir-invert" => Run(&["scurve_rates.png"]),
        "cargo sim -- --gcode bench/demo/cam_job.gcode --vcd cam.vcd" => Run(&["cam.vcd"]),
        "cargo la -- cam.vcd --path cam_path.png --per-mm 100 --dir-invert" => Run(&["cam_path.png"]),
        "cargo sim -- --gcode my.gcode --max-seconds 5 --pin PA0@0.25=0" => Run(&[]),
        "cargo sim -- --machine bench/demo/gantry300.toml" => Run(&[]),
        "cargo sim -- --usb --char-count --gcode bench/demo/usb_job.gcode --json usb.json" => Run(&["usb.json"]),
        "cargo sim -- --serve --usb --pty-link /tmp/ttyBLUEPILL --max-seconds 2" => Run(&[]),
        "cargo build --release --no-default-features" => {
            Skip("would replace the release ELF the other tests load; bench/tests/firmware_size.rs builds the USART1-only image in its own target dir")
        }
        "cargo bench -p ddastep-bench --target host-tuple --bench usb_link" => Skip("a benchmark: about a minute of both cores"),
        "cargo sim -- --machine bench/demo/encoder_x.toml" => Run(&[]),
        "cargo sim -- --sweep" => Skip("the step-rate benchmark: about a minute of both cores"),
        "cargo sim -- --sweep --dual-edge" => Skip("the same benchmark in dual-edge mode: about a minute of both cores"),
        "cargo sim -- --sweep --dma" => Skip("the same benchmark in DMA burst mode: several minutes of both cores"),
        "cargo sim -- --serve --pty-link /tmp/ttyBLUEPILL --tcp 127.0.0.1:23000 --max-seconds 2" => Run(&[]),
        "socat pty,raw,echo=0,link=/tmp/ttyGRBL tcp:127.0.0.1:23000" => {
            Skip("bridges to a running --serve until stopped; socat is optional (TCP is tested in serve_senders)")
        }
        c if c.starts_with("sigrok-cli -d fx2lafw") => Skip("captures from a logic analyzer on USB"),
        c if c.starts_with("python3 stream.py job.gcode ") => {
            Skip("gnea/grbl's stream.py against a board or a running --serve; serve_senders.rs streams the same way")
        }
        "UPDATE_DOCS=1 cargo test -p ddastep --target host-tuple --test settings_docs"
        | "UPDATE_DOCS=1 cargo test -p ddastep --target host-tuple --test wiring_svg" => {
            Skip("rewrites a committed docs file; the same test without UPDATE_DOCS (cargo test-host) fails when it differs")
        }
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

// the target directory the commands build into
fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| root().join("target"))
}

/// Runs (or skips, or checks) every command in a scratch directory `target/<scratch>`; returns
/// the report lines and each run command's output (stdout then stderr).
fn run_all(commands: &[String], scratch: &str) -> (Vec<String>, std::collections::HashMap<String, String>) {
    let unknown: Vec<_> = commands.iter().filter(|c| plan(c).is_none()).collect();
    assert!(unknown.is_empty(), "commands this test does not know (add them to `plan`): {unknown:?}");

    // A scratch directory inside the workspace: cargo finds the workspace from there, and the
    // relative paths the README uses (bench/demo/..., .ci/setup) resolve through links.
    let dir = root().join("target").join(scratch);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for linked in ["bench", ".ci"] {
        std::os::unix::fs::symlink(root().join(linked), dir.join(linked)).unwrap();
    }
    let mut report = Vec::new();
    let mut outputs = std::collections::HashMap::new();
    let mut boards = Vec::new();
    for cmd in commands {
        match plan(cmd).unwrap() {
            Plan::Skip(why) => report.push(format!("skipped  {cmd}  ({why})")),
            Plan::Board => boards.push(cmd.clone()),
            Plan::Run(files) => {
                prepare(&dir, cmd);
                let out = Command::new("bash")
                    .arg("-c")
                    .arg(cmd)
                    .current_dir(&dir)
                    .env_remove("CARGO_ENCODED_RUSTFLAGS")
                    .env_remove("RUSTFLAGS")
                    .env_remove("CARGO_TARGET_DIR")
                    .env("CARGO_TARGET_DIR", target_dir())
                    .output()
                    .unwrap();
                let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
                assert!(out.status.success(), "`{cmd}` failed ({}):\n{text}", out.status);
                for f in files {
                    assert!(dir.join(f).exists(), "`{cmd}` did not write {f}");
                }
                report.push(format!("ran      {cmd}"));
                outputs.insert(cmd.clone(), text);
            }
        }
    }
    // The flashing commands, after `cargo xtask dist` wrote the files they name.
    if !boards.is_empty() {
        let dist = outputs.get("cargo xtask dist").expect("a page that flashes shows `cargo xtask dist` first");
        let version = dist_version(dist);
        for cmd in &boards {
            let note = check_flash_command(cmd, &version);
            report.push(format!("checked  {cmd}  (needs a board; {note})"));
        }
    }
    (report, outputs)
}

// VERSION from `cargo xtask dist`'s output (its `.../ddastep-VERSION.elf  N bytes  sha256 ...` line)
fn dist_version(out: &str) -> String {
    let elf = out
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .find(|p| p.ends_with(".elf"))
        .unwrap_or_else(|| panic!("no .elf line in `cargo xtask dist` output:\n{out}"));
    let name = Path::new(elf).file_name().unwrap().to_string_lossy().into_owned();
    name.strip_prefix("ddastep-").and_then(|n| n.strip_suffix(".elf")).expect("ddastep-VERSION.elf").to_owned()
}

// the tool's help text, or None when the tool is not installed
fn help_text(tool: &str, args: &[&str]) -> Option<String> {
    match Command::new(tool).args(args).output() {
        Ok(out) => Some(format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        Err(e) => panic!("running {tool}: {e}"),
    }
}

// whether `word` (a flag or subcommand) appears in `help` on its own (not inside a longer word)
fn in_help(help: &str, word: &str) -> bool {
    let part = |c: Option<char>| c.is_some_and(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    help.match_indices(word).any(|(i, _)| !part(help[..i].chars().next_back()) && !part(help[i + word.len()..].chars().next()))
}

/// Checks a flashing command without a board: every `target/dist/ddastep-VERSION.*` it names
/// exists (VERSION as `cargo xtask dist` printed it), and where the tool is installed, its
/// subcommand and flags appear in the tool's help and the arguments are where the usage puts
/// them. Returns what was checked.
fn check_flash_command(cmd: &str, version: &str) -> String {
    let words: Vec<&str> = cmd.split_whitespace().collect();
    let mut files = 0;
    for w in &words {
        if let Some(rest) = w.strip_prefix("target/") {
            assert!(w.contains("ddastep-VERSION."), "`{cmd}`: a target/ path that is not a dist file: {w}");
            let path = target_dir().join(rest.replace("VERSION", version));
            assert!(path.is_file(), "`{cmd}`: {} does not exist after cargo xtask dist", path.display());
            files += 1;
        }
    }
    assert_eq!(files, 1, "`{cmd}` names one firmware file");
    let flags: Vec<&str> = words.iter().filter(|w| w.starts_with('-')).map(|w| w.split('=').next().unwrap()).collect();
    let (tool, help) = match words[0] {
        "st-flash" => {
            // st-flash [options] {read|write} [path] [addr] [size]: write, the .bin, the flash start
            let sub = words.iter().position(|w| !w.starts_with('-') && *w != "st-flash").unwrap();
            assert_eq!(words[sub], "write", "`{cmd}`");
            assert!(words[sub + 1].ends_with(".bin"), "`{cmd}`: st-flash writes the .bin");
            assert_eq!(u32::from_str_radix(words[sub + 2].trim_start_matches("0x"), 16), Ok(0x0800_0000), "`{cmd}`: flash start");
            ("st-flash", help_text("st-flash", &["--help"]).map(|h| (h, vec!["write"])))
        }
        "stm32flash" => {
            // stm32flash [-bvngfhc] [-[rw] filename] [tty_device]: -w FILE, -g ADDRESS, the port last
            let at = |f: &str| words.iter().position(|w| *w == f).unwrap_or_else(|| panic!("`{cmd}` has no {f}"));
            assert!(words[at("-w") + 1].ends_with(".bin"), "`{cmd}`: stm32flash writes the .bin");
            assert_eq!(words[at("-g") + 1], "0x0", "`{cmd}`: start at the beginning of flash");
            assert!(words.last().unwrap().starts_with("/dev/tty"), "`{cmd}`: the serial port comes last");
            ("stm32flash", help_text("stm32flash", &["-h"]).map(|h| (h, vec![])))
        }
        "probe-rs" => {
            // probe-rs download --chip CHIP FILE
            assert_eq!(words[1], "download", "`{cmd}`");
            assert_eq!(words[words.iter().position(|w| *w == "--chip").unwrap() + 1], "STM32F103C8", "`{cmd}`: the runner's chip");
            assert!(words.last().unwrap().ends_with(".elf"), "`{cmd}`: probe-rs takes the ELF");
            ("probe-rs", help_text("probe-rs", &["download", "--help"]).map(|h| (h, vec![])))
        }
        other => panic!("`{cmd}`: no check for {other}"),
    };
    let Some((help, subcommands)) = help else {
        return format!("file exists; {tool} not installed, flags not checked");
    };
    for word in subcommands.iter().chain(&flags) {
        assert!(in_help(&help, word), "`{cmd}`: {tool}'s help does not mention {word}:\n{help}");
    }
    format!("file exists; {} in {tool}'s help", subcommands.iter().chain(&flags).copied().collect::<Vec<_>>().join(" "))
}

#[test]
fn every_readme_command_runs_as_written() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let commands = readme_commands(&readme);
    // the landing page's two commands for the virtual bench, as .ci/run runs them
    for two in ["bash .ci/setup && cargo sim", "cargo test-host"] {
        assert!(commands.iter().any(|c| c == two), "README lost `{two}`: {commands:?}");
    }
    let (report, _) = run_all(&commands, "readme-commands");
    println!("{}", report.join("\n"));
}

// what a page's commands printed that the page promises
fn check_page_outputs(name: &str, outputs: &std::collections::HashMap<String, String>) {
    if name == "commands" {
        // A part too small: every line refused with the reason, no step made.
        let small = &outputs["cargo sim -- --flash-kib 32"];
        assert!(small.contains("\"G91\" -> [MSG:chip flash 32 KiB, needs 64 KiB: motion refused]\r\nerror:9"), "{small}");
        assert!(small.contains("firmware self-report: [MSG:chip flash 32 KiB uid "), "{small}");
        assert!(small.contains("(each move against its own line, 0 moves)"), "{small}");
    }
    if name != "bench" {
        return;
    }
    // The library driven from code: the 5:3:2 move ends on its exact counts.
    let example = &outputs["cargo run --example step_move --target host-tuple"];
    assert!(example.contains("5:3:2: counts X 5000 Y 3000 Z 2000 "), "{example}");
    assert!(example.contains("BSRR 0x00000600  step X+, Y+"), "{example}");
    // The issue's pair: a 7-axis bench VCD of a 3-axis move (there and back) checks against a
    // 3-term ratio.
    let stdout = &outputs["cargo la -- fast.vcd --expect 5:3:2"];
    assert!(stdout.contains("X:Y:Z = 10000:6000:4000 = 5:3:2 exact") && stdout.contains("no steps on A, B, C, U"), "{stdout}");
    // The pictures show what the page says: the 5:3:2 pattern at cruise, the CAM job at its
    // rapid rate (6000 mm/min on X, a step per 5 ms either way).
    let pulses = &outputs["cargo la -- paper.vcd --plot paper_rates.png --pulses paper_pulses.png --pulses-at 75 --dir-invert"];
    assert!(pulses.contains("pulses: X 5, Y 3, Z 2 rising edges in 100 us"), "{pulses}");
    let path = &outputs["cargo la -- cam.vcd --path cam_path.png --per-mm 100 --dir-invert"];
    let top: f64 = path.split("path: top XY speed ").nth(1).and_then(|s| s.split(' ').next()).and_then(|s| s.parse().ok()).unwrap_or(0.0);
    assert!((5_900.0..=6_200.0).contains(&top), "{path}");
}

#[test]
fn every_docs_command_runs_or_is_checked() {
    let mut pages: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    // every page the README's table links to
    for page in ["install", "wiring", "settings", "commands", "senders", "safety", "bench", "performance", "internals"] {
        assert!(pages.iter().any(|p| p.ends_with(format!("{page}.md"))), "docs/{page}.md missing: {pages:?}");
    }
    for page in pages {
        let commands = readme_commands(&std::fs::read_to_string(&page).unwrap());
        let name = page.file_stem().unwrap().to_string_lossy().into_owned();
        let (report, outputs) = run_all(&commands, &format!("docs-commands-{name}"));
        println!("docs/{name}.md:\n{}", report.join("\n"));
        check_page_outputs(&name, &outputs);
        if name == "install" {
            // the three ways to flash are all there and checked
            for tool in ["probe-rs download", "st-flash write", "stm32flash -w"] {
                assert!(report.iter().any(|r| r.starts_with(&format!("checked  {tool}"))), "{report:?}");
            }
        }
    }
}
