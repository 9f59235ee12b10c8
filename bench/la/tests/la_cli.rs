//! The `la` binary: report text, JSON, plot, and exit codes (0 pass, 1 failed check, 2 error).

use std::path::PathBuf;
use std::process::{Command, Output};

// path of a fixture
fn fixture(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
        .display()
        .to_string()
}

// a fresh path in the temp dir
fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("la-cli-{}-{name}", std::process::id()))
}

// run `la` with arguments
fn la(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_la"))
        .args(args)
        .output()
        .expect("run la")
}

// stdout and stderr as text
fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn passing_expect_exits_0_with_the_summary() {
    let out = la(&[&fixture("bresenham_532.vcd"), "--expect", "5:3:2"]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert!(
        stdout.contains("X:Y:Z = 50:30:20 = 5:3:2 exact, cruise 50.0 kHz"),
        "{stdout}"
    );
    assert!(
        stdout.contains("(VCD, 24 MHz): X=X_STEP/X_DIR Y=Y_STEP/Y_DIR Z=Z_STEP/Z_DIR"),
        "{stdout}"
    );
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("Y ") && l.contains("-30") && l.contains("0.40")),
        "{stdout}"
    );
}

#[test]
fn a_leading_double_dash_from_the_cargo_alias_is_ignored() {
    let out = la(&["--", &fixture("bresenham_532.vcd"), "--expect", "5:3:2"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out).1);
}

#[test]
fn ratio_wrong_by_one_step_exits_1() {
    let out = la(&[&fixture("wrong_ratio_51_30_20.vcd"), "--expect", "5:3:2"]);
    let (stdout, _) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("X:Y:Z = 51:30:20 = 51:30:20, expected 5:3:2: MISMATCH"),
        "{stdout}"
    );
    // Without --expect nothing is checked.
    assert_eq!(
        la(&[&fixture("wrong_ratio_51_30_20.vcd")]).status.code(),
        Some(0)
    );
}

#[test]
fn csv_with_map_and_dir_options() {
    let args = [
        &fixture("bresenham_532_d.csv"),
        "--map",
        "X=D0,Y=D1,Z=D2",
        "--dir",
        "X=D3,Y=D4,Z=D5",
        "--expect",
        "5:3:2",
    ];
    let out = la(&args);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert!(
        stdout.contains("(CSV, 24 MHz): X=D0/D3 Y=D1/D4 Z=D2/D5"),
        "{stdout}"
    );
    // --dir-invert flips the signs.
    let out = la(&[&args[..], &["--dir-invert"]].concat());
    assert!(
        text(&out)
            .0
            .lines()
            .any(|l| l.starts_with("X ") && l.contains("-50")),
        "{}",
        text(&out).0
    );
}

#[test]
fn min_glitch_option_decides_the_glitch_fixture() {
    assert_eq!(
        la(&[&fixture("glitch.vcd"), "--expect", "2:1"])
            .status
            .code(),
        Some(1)
    );
    let out = la(&[
        &fixture("glitch.vcd"),
        "--expect",
        "2:1",
        "--min-glitch-ns",
        "100",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out).0);
    assert!(
        text(&out).0.contains("4 glitches dropped"),
        "{}",
        text(&out).0
    );
}

#[test]
fn json_goes_to_stdout_or_a_file_and_the_plot_is_a_png() {
    let out = la(&[&fixture("ramp_500_300_200.vcd"), "--json"]);
    assert_eq!(out.status.code(), Some(0));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is JSON");
    assert_eq!(json["ratio"], serde_json::json!([5, 3, 2]));
    assert_eq!(json["axes"][1]["steps"], 300);
    assert_eq!(json["lines"][0]["step"], "X_STEP");
    assert_eq!(json["axes"][0]["min_dir_setup_ns"], serde_json::Value::Null);
    assert!(json["cruise"]["rate_hz"].as_f64().unwrap() > 49_000.0);

    let (json_path, png_path) = (temp("report.json"), temp("rate.png"));
    let out = la(&[
        &fixture("ramp_500_300_200.vcd"),
        "--json",
        json_path.to_str().unwrap(),
        "--plot",
        png_path.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out).1);
    assert!(text(&out).0.contains("5:3:2"), "human report still printed");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json_path).unwrap()).unwrap();
    assert_eq!(json["axes"][0]["steps"], 500);
    let png = std::fs::read(&png_path).unwrap();
    assert!(
        png.starts_with(b"\x89PNG\r\n\x1a\n") && png.len() > 10_000,
        "{} bytes",
        png.len()
    );
    let _ = std::fs::remove_file(json_path);
    let _ = std::fs::remove_file(png_path);
}

#[test]
fn bad_inputs_exit_2_with_a_message() {
    let garbage = temp("garbage.vcd");
    std::fs::write(
        &garbage,
        "$timescale 1 ns $end\n$var wire 1 ! X_STEP $end\n$enddefinitions $end\n#10\n1?\n",
    )
    .unwrap();
    let truncated = temp("truncated.vcd");
    std::fs::write(&truncated, "$timescale 1 ns $end\n$var wire 1 ! X_STEP").unwrap();
    let backwards = temp("backwards.vcd");
    std::fs::write(
        &backwards,
        "$var wire 1 ! X_STEP $end\n$enddefinitions $end\n#10\n1!\n#5\n0!\n",
    )
    .unwrap();
    let binary = temp("binary.csv");
    std::fs::write(&binary, [0xffu8, 0xfe, 0x00, 0x12, b'\n']).unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["/nonexistent/capture.vcd".into()], "cannot open"),
        (vec![garbage.display().to_string()], "unknown identifier"),
        (vec![truncated.display().to_string()], "missing $end"),
        (vec![backwards.display().to_string()], "time goes backwards"),
        (vec![binary.display().to_string()], "cannot read"),
        (vec![fixture("bresenham_532_d.csv")], "--map"),
        (
            vec![
                fixture("bresenham_532_d.csv"),
                "--map".into(),
                "X=D9".into(),
            ],
            "no channel named \"D9\"",
        ),
        (
            vec![
                fixture("bresenham_532.vcd"),
                "--expect".into(),
                "5:3".into(),
            ],
            "--expect 5:3 has 2 terms but 3 of the 3 mapped axes stepped (X, Y, Z); give one term per stepping axis, or pick the axes in ratio order with --map, e.g. --map X=X_STEP,Y=Y_STEP",
        ),
        (
            vec![
                fixture("bresenham_532.vcd"),
                "--expect".into(),
                "5:3:2:1".into(),
            ],
            "4 terms but only 3 axes are mapped (X, Y, Z); name the step channel of each axis in ratio order with --map",
        ),
        (
            vec![
                fixture("bresenham_532.vcd"),
                "--expect".into(),
                "5:x:2".into(),
            ],
            "not a ratio",
        ),
        (
            vec![fixture("bresenham_532.vcd"), "--no-such-flag".into()],
            "unexpected argument",
        ),
    ];
    for (args, message) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = la(&args);
        let (stdout, stderr) = text(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stdout}{stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    for path in [garbage, truncated, backwards, binary] {
        let _ = std::fs::remove_file(path);
    }
}

// a bench-style VCD of a 50:30:20 move on X, Y, Z with A, B, C, U present and never stepping
fn seven_axis_vcd(name: &str) -> PathBuf {
    let names = ["X", "Y", "Z", "A", "B", "C", "U"];
    let axes = ddastep_la::synth::dda_move(&names, &[50, 30, 20, 0, 0, 0, 0], 10_000, 20_000, 2_000);
    let path = temp(name);
    let file = std::fs::File::create(&path).unwrap();
    ddastep_la::synth::write_vcd(&axes, 1_100_000, file).unwrap();
    path
}

#[test]
fn axes_that_never_step_do_not_count_against_expect() {
    let vcd = seven_axis_vcd("idle.vcd");
    let out = la(&[vcd.to_str().unwrap(), "--expect", "5:3:2"]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert!(
        stdout.contains("X:Y:Z = 50:30:20 = 5:3:2 exact") && stdout.contains("no steps on A, B, C, U"),
        "{stdout}"
    );
    // A wrong ratio over the stepping axes still fails the check.
    let out = la(&[vcd.to_str().unwrap(), "--expect", "5:3:1"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out).0);
    // All seven terms: the idle axes are compared too (as zeros).
    let out = la(&[vcd.to_str().unwrap(), "--expect", "5:3:2:0:0:0:0"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out).0);
    // Two terms for three stepping axes: a mapping problem, with the fix in the message.
    let out = la(&[vcd.to_str().unwrap(), "--expect", "5:3"]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(2), "{stdout}{stderr}");
    assert!(stderr.contains("3 of the 7 mapped axes stepped (X, Y, Z)") && stderr.contains("--map X=X_STEP,Y=Y_STEP"), "{stderr}");
    // --map picks the axes explicitly.
    let out = la(&[vcd.to_str().unwrap(), "--map", "X=X_STEP,Y=Y_STEP", "--expect", "5:3"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out).0);
    let _ = std::fs::remove_file(vcd);
}

#[test]
fn pulses_and_path_pictures_count_what_they_show() {
    let (pulses, path) = (temp("pulses.png"), temp("path.png"));
    // 50 kHz 5:3:2 Bresenham: five master periods hold 5, 3 and 2 rising edges
    let out = la(&[
        &fixture("bresenham_532.vcd"),
        "--pulses",
        pulses.to_str().unwrap(),
        "--pulses-us",
        "100",
        "--path",
        path.to_str().unwrap(),
        "--per-mm",
        "100",
    ]);
    let (stdout, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stdout.contains("pulses: X 5, Y 3, Z 2 rising edges in 100 us"), "{stdout}");
    // 50 and 30 kHz at 100 steps/mm: 583 mm/s = 34 986 mm/min, within a step (600 mm/min) over
    // the 1 ms capture
    let top: f64 = stdout.split("path: top XY speed ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!((top - 34_986.0).abs() < 600.0, "{stdout}");
    for png in [&pulses, &path] {
        let bytes = std::fs::read(png).unwrap();
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n") && bytes.len() > 5_000, "{} bytes", bytes.len());
        let _ = std::fs::remove_file(png);
    }
    // bad windows and scales exit 2
    for bad in [["--pulses-us", "0"], ["--pulses-at", "-1"], ["--per-mm", "0"]] {
        let out = la(&[&fixture("bresenham_532.vcd"), "--pulses", pulses.to_str().unwrap(), "--path", path.to_str().unwrap(), bad[0], bad[1]]);
        assert_eq!(out.status.code(), Some(2), "{bad:?}: {}", text(&out).1);
    }
}
