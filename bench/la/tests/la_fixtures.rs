//! Logic-analyzer checker against committed sigrok captures with known answers
//! (bench/la/fixtures/, made by make_fixtures.py: 24 MHz, 24 samples = 1 µs).

use std::path::PathBuf;

use ddastep_la as la;
use ddastep_la::{map, synth, Analyzer, Config, Report};

// path of a fixture
fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

// check a fixture the way the CLI does
fn check(
    name: &str,
    map_arg: &str,
    dir_arg: &str,
    expect: Option<&str>,
    min_glitch_ns: u64,
    rate: Option<f64>,
) -> Report {
    let mut capture = la::open(&fixture(name), None, rate).expect("open fixture");
    let channels = capture.info().channels.clone();
    let axes = map::resolve(
        &channels,
        &map::parse_pairs(map_arg).unwrap(),
        &map::parse_pairs(dir_arg).unwrap(),
    )
    .expect("map channels");
    let config = Config {
        axes,
        min_glitch_ps: min_glitch_ns * 1000,
        expect: expect.map(|e| map::parse_ratio(e).unwrap()),
        ..Config::default()
    };
    let mut analyzer = Analyzer::new(config).unwrap();
    capture.stream(&mut analyzer).expect("read fixture");
    analyzer.finish()
}

// assert a measured time in ns within `tolerance`
fn near(got: Option<f64>, want: f64, tolerance: f64) {
    let got = got.unwrap_or_else(|| panic!("expected {want}, got None"));
    assert!((got - want).abs() <= tolerance, "got {got}, want {want}");
}

// the known answers of the 5:3:2 Bresenham move
fn assert_bresenham(report: &Report, tolerance_ns: f64) {
    let steps: Vec<_> = report
        .axes
        .iter()
        .map(|a| (a.name.as_str(), a.steps, a.net_steps))
        .collect();
    assert_eq!(steps, vec![("X", 50, 50), ("Y", 30, -30), ("Z", 20, 20)]);
    assert_eq!(report.ratio, vec![5, 3, 2]);
    assert_eq!(report.master, Some(0));
    for axis in &report.axes {
        near(axis.min_high_ns, 4_125.0, tolerance_ns);
        assert_eq!(axis.min_dir_hold_ns, None, "no dir change after a step");
    }
    near(report.axes[0].min_low_ns, 15_875.0, tolerance_ns);
    near(report.axes[1].min_low_ns, 15_875.0, tolerance_ns);
    near(report.axes[2].min_low_ns, 35_875.0, tolerance_ns);
    near(report.axes[0].min_dir_setup_ns, 6_000.0, tolerance_ns);
    near(report.axes[1].min_dir_setup_ns, 5_000.0, tolerance_ns);
    assert_eq!(report.axes[2].min_dir_setup_ns, None, "Z dir never changes");
    assert_eq!(report.axes[0].max_deviation_steps, None);
    near(report.axes[1].max_deviation_steps, 0.4, 1e-9);
    near(report.axes[2].max_deviation_steps, 0.4, 1e-9);
    let cruise = report.cruise.as_ref().expect("cruise");
    assert!((cruise.rate_hz - 50_000.0).abs() < 0.01, "{cruise:?}");
    near(report.axes[0].jitter_pp_ns, 0.0, tolerance_ns);
    near(report.axes[1].jitter_pp_ns, 20_000.0, tolerance_ns);
    assert!((report.axes[0].max_rate_hz - 50_000.0).abs() < 0.01);
    assert_eq!(report.glitches, 0);
}

#[test]
fn sigrok_vcd_bresenham_532() {
    let report = check("bresenham_532.vcd", "", "", Some("5:3:2"), 0, None);
    assert_bresenham(&report, 0.0);
    assert!(report.passed());
    let summary = report.summary();
    assert!(summary.starts_with("X:Y:Z = 50:30:20 = 5:3:2 exact, cruise 50.0 kHz, min pulse 4.125 µs, dir setup 5.000 µs"), "{summary}");
}

#[test]
fn sigrok_csv_with_d_names_needs_a_map() {
    let report = check(
        "bresenham_532_d.csv",
        "X=D0,Y=D1,Z=D2",
        "X=D3,Y=D4,Z=D5",
        Some("5:3:2"),
        0,
        None,
    );
    // libsigrok writes 41 ns per sample; the reader restores 41.67 ns from the sample rate.
    assert_bresenham(&report, 0.01);
    let mut capture = la::open(&fixture("bresenham_532_d.csv"), None, None).unwrap();
    assert_eq!(capture.info().sample_rate_hz, Some(24e6));
    assert!(
        map::resolve(&capture.info().channels, &[], &[]).is_err(),
        "D0.. names are not axes"
    );
    let mut recorded = la::capture::Recorded::default();
    capture.stream(&mut recorded).unwrap();
    assert!(recorded.levels.iter().all(|&(_, ch, _)| ch < 6));
}

#[test]
fn sigrok_csv_with_channel_labels_and_no_header_needs_the_rate() {
    let err = la::open(&fixture("bresenham_532_labels.csv"), None, None)
        .err()
        .expect("no unit, no rate");
    assert!(format!("{err:#}").contains("--samplerate"), "{err:#}");
    let report = check(
        "bresenham_532_labels.csv",
        "",
        "",
        Some("5:3:2"),
        0,
        Some(24e6),
    );
    assert_bresenham(&report, 0.01);
}

#[test]
fn ratio_off_by_one_step_fails_expect() {
    let report = check("wrong_ratio_51_30_20.vcd", "", "", Some("5:3:2"), 0, None);
    assert_eq!(report.ratio, vec![51, 30, 20]);
    assert!(!report.passed());
    assert!(
        report.summary().contains("expected 5:3:2: MISMATCH"),
        "{}",
        report.summary()
    );
}

#[test]
fn ramp_finds_cruise_at_50khz() {
    let report = check("ramp_500_300_200.vcd", "", "", Some("5:3:2"), 0, None);
    assert!(report.passed());
    let counts: Vec<_> = report.axes.iter().map(|a| a.steps).collect();
    assert_eq!(counts, vec![500, 300, 200]);
    let cruise = report.cruise.clone().expect("cruise");
    assert!((cruise.rate_hz - 50_000.0).abs() < 250.0, "{cruise:?}");
    assert!(cruise.end_ms - cruise.start_ms >= 5.0, "{cruise:?}");
    // Ramp: the rate curve starts far below cruise.
    let rates = &report.series.rate_hz[0];
    assert!(
        rates[0] < 10_000.0 && rates.iter().copied().fold(0.0, f64::max) > 49_000.0,
        "{rates:?}"
    );
    assert!(report.axes[1].max_deviation_steps.unwrap() <= 0.5 + 1e-9);
}

#[test]
fn capture_starting_mid_pulse_counts_no_partial_pulse() {
    for name in ["midpulse.vcd", "midpulse.csv"] {
        let report = check(name, "", "", Some("3:2"), 0, None);
        assert_eq!(
            (report.axes[0].steps, report.axes[1].steps),
            (3, 2),
            "{name}"
        );
        assert!(report.passed(), "{name}");
        near(report.axes[0].min_high_ns, 2_000.0, 0.05);
        near(report.axes[1].min_high_ns, 2_000.0, 0.05);
        // The end of the partial pulse is a real edge: the low after it counts.
        near(report.axes[0].min_low_ns, 4_500.0, 0.05);
        near(report.axes[1].min_low_ns, 1_666.67, 0.05);
    }
}

#[test]
fn zero_width_glitches_are_dropped_and_narrow_ones_on_request() {
    let report = check("glitch.vcd", "", "", None, 0, None);
    assert_eq!(
        (report.axes[0].steps, report.axes[1].steps),
        (12, 5),
        "two 1-sample spikes count"
    );
    assert_eq!(report.axes[0].glitches, 2, "two zero-width pulses dropped");
    near(report.axes[0].min_high_ns, 41.7, 0.05);

    let report = check("glitch.vcd", "", "", Some("2:1"), 100, None);
    assert_eq!((report.axes[0].steps, report.axes[1].steps), (10, 5));
    assert_eq!(report.axes[0].glitches, 4);
    near(report.axes[0].min_high_ns, 2_000.0, 0.01);
    assert!(report.passed());
}

#[test]
fn bench_vcd_with_four_axes_and_enable() {
    let report = check("bench_xyzu.vcd", "", "", Some("4:3:2:1"), 0, None);
    assert!(report.passed(), "{}", report.summary());
    let net: Vec<_> = report
        .axes
        .iter()
        .map(|a| (a.name.as_str(), a.net_steps))
        .collect();
    assert_eq!(net, vec![("X", 40), ("Y", 30), ("Z", -20), ("U", 10)]);
    near(report.axes[0].min_high_ns, 2_000.0, 0.0);
    near(report.axes[2].min_dir_setup_ns, 5_000.0, 0.0);
}

// the bench fixture's trace: 40:30:20:10 at 50 kHz, 2 µs pulses, Z reversed 5 µs before start
fn bench_trace() -> Vec<synth::AxisTrace> {
    let mut axes = synth::dda_move(
        &["X", "Y", "Z", "U"],
        &[40, 30, 20, 10],
        10_000,
        20_000,
        2_000,
    );
    axes[2].dir_toggles_ns = vec![5_000];
    axes
}

#[test]
fn bench_fixture_matches_its_generator() {
    let mut written = Vec::new();
    synth::write_vcd(&bench_trace(), 820_000, &mut written).unwrap();
    let committed = std::fs::read(fixture("bench_xyzu.vcd")).unwrap();
    assert_eq!(
        String::from_utf8(written).unwrap(),
        String::from_utf8(committed).unwrap()
    );
}

#[test]
#[ignore = "writes bench/la/fixtures/bench_xyzu.vcd"]
fn regenerate_bench_fixture() {
    let file = std::fs::File::create(fixture("bench_xyzu.vcd")).unwrap();
    synth::write_vcd(&bench_trace(), 820_000, file).unwrap();
}
