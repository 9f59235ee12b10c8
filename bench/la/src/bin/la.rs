//! `cargo la -- CAPTURE [options]`: check a logic-analyzer capture of step/dir lines.
//! Exit code 0 when every requested check passes, 1 when `--expect` fails, 2 on usage or
//! read errors.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{anyhow, Context, Result};
use clap::Parser;
use ddastep_la as la;
use ddastep_la::{map, Analyzer, AxisChannels, Config, Format, Report};
use serde::Serialize;

/// Check step/dir pulse trains in a sigrok capture (VCD or CSV) or a bench VCD.
#[derive(Parser, Debug)]
#[command(name = "la", version)]
struct Args {
    /// Capture: sigrok-cli `-O vcd` or `-O csv` output, or a virtual-bench VCD.
    capture: PathBuf,
    /// File format (default: from the extension, else from the first byte).
    #[arg(long, value_enum)]
    format: Option<Format>,
    /// Step channels in ratio order, e.g. `X=D0,Y=D1,Z=D2` (default: channels named AXIS_STEP).
    #[arg(long, value_name = "AXIS=CH,..")]
    map: Option<String>,
    /// Dir channels, e.g. `X=D3,Y=D4` (default: channels named AXIS_DIR).
    #[arg(long, value_name = "AXIS=CH,..")]
    dir: Option<String>,
    /// Dir low means + (default: dir high means +).
    #[arg(long)]
    dir_invert: bool,
    /// Dual-edge stepping (TMC22xx `dedge`, ddastep `$580=1`): every edge of a step line is a
    /// step; high and low widths are then the spacing between two toggles.
    #[arg(long)]
    dual_edge: bool,
    /// Expected step ratio in axis order, e.g. `5:3:2` (compared after dividing by the gcd).
    #[arg(long, value_name = "A:B:C")]
    expect: Option<String>,
    /// Drop pulses narrower than this as glitches (0: only pulses within one timestamp).
    #[arg(long, value_name = "NS", default_value_t = 0.0)]
    min_glitch_ns: f64,
    /// Sample rate for CSV files without one, e.g. `24m`, `24MHz`, `1000000`.
    #[arg(long, value_name = "HZ")]
    samplerate: Option<String>,
    /// Write a PNG of step rate and slave deviation over time.
    #[arg(long, value_name = "PNG")]
    plot: Option<PathBuf>,
    /// Write a PNG of the step lines of the axes that step, as a logic analyzer shows them,
    /// over a short window (see --pulses-at, --pulses-us).
    #[arg(long, value_name = "PNG")]
    pulses: Option<PathBuf>,
    /// With --pulses: the window starts this long after the first rising step edge.
    #[arg(long, value_name = "MS", default_value_t = 0.0)]
    pulses_at: f64,
    /// With --pulses: the window's length.
    #[arg(long, value_name = "US", default_value_t = 100.0)]
    pulses_us: f64,
    /// Write a PNG of the XY path of the first two axes that step, coloured by path speed.
    #[arg(long, value_name = "PNG")]
    path: Option<PathBuf>,
    /// With --path: steps per mm (the same on both axes); positions and speed in mm, not steps.
    #[arg(long, value_name = "STEPS")]
    per_mm: Option<f64>,
    /// Print the report as JSON instead, or write it to FILE as well.
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    json: Option<PathBuf>,
}

/// One axis's channels by name, for the output.
#[derive(Serialize)]
struct AxisLines {
    axis: String,
    step: String,
    dir: Option<String>,
}

/// The JSON document: where the data came from, then the report.
#[derive(Serialize)]
struct Output<'a> {
    capture: String,
    format: Format,
    sample_rate_hz: Option<f64>,
    lines: Vec<AxisLines>,
    #[serde(flatten)]
    report: &'a Report,
}

// "24m", "24 MHz", "1k", "1000000"
fn parse_rate(text: &str) -> Result<f64> {
    let t = text.trim().to_ascii_lowercase().replace(' ', "");
    let t = t.strip_suffix("hz").unwrap_or(&t);
    let (digits, scale) = match t.chars().last() {
        Some('k') => (&t[..t.len() - 1], 1e3),
        Some('m') => (&t[..t.len() - 1], 1e6),
        Some('g') => (&t[..t.len() - 1], 1e9),
        _ => (t, 1.0),
    };
    let rate: f64 = digits
        .parse()
        .map_err(|_| anyhow!("{text:?} is not a sample rate like 24m or 24000000"))?;
    if rate.is_nan() || rate <= 0.0 {
        return Err(anyhow!("sample rate must be positive"));
    }
    Ok(rate * scale)
}

// check the capture; Ok(false) when a check failed
fn run(args: &Args) -> Result<bool> {
    let expect = args.expect.as_deref().map(map::parse_ratio).transpose()?;
    let pairs = |o: &Option<String>| {
        o.as_deref()
            .map(map::parse_pairs)
            .transpose()
            .map(Option::unwrap_or_default)
    };
    let (map_pairs, dir_pairs) = (pairs(&args.map)?, pairs(&args.dir)?);
    if args.min_glitch_ns.is_nan() || args.min_glitch_ns < 0.0 {
        return Err(anyhow!("--min-glitch-ns must be 0 or more"));
    }
    let rate = args.samplerate.as_deref().map(parse_rate).transpose()?;

    let mut capture = la::open(&args.capture, args.format, rate)?;
    let info = capture.info().clone();
    let axes = map::resolve(&info.channels, &map_pairs, &dir_pairs)?;
    let config = Config {
        axes: axes.clone(),
        dir_invert: args.dir_invert,
        dual_edge: args.dual_edge,
        min_glitch_ps: (args.min_glitch_ns * 1e3).round() as u64,
        expect,
    };
    let mut analyzer = Analyzer::new(config)?;
    capture
        .stream(&mut analyzer)
        .with_context(|| format!("cannot read {}", args.capture.display()))?;
    let report = analyzer.finish();
    if let Some(problem) = report.expect.as_ref().and_then(|e| e.mapping_error.as_ref()) {
        print!("{report}");
        return Err(anyhow!("{problem}"));
    }

    let lines = axes.iter().map(|a| lines_of(a, &info.channels)).collect();
    let output = Output {
        capture: args.capture.display().to_string(),
        format: info.format,
        sample_rate_hz: info.sample_rate_hz,
        lines,
        report: &report,
    };
    let json = serde_json::to_string_pretty(&output)?;
    match args.json.as_deref() {
        Some(p) if p == Path::new("-") => println!("{json}"),
        other => {
            if let Some(path) = other {
                std::fs::write(path, json + "\n")
                    .with_context(|| format!("cannot write {}", path.display()))?;
            }
            print_human(&output);
        }
    }
    if let Some(path) = &args.plot {
        let summary = report.summary();
        let ratio_and_cruise = summary.split(", min pulse").next().unwrap_or(&summary);
        let title = format!(
            "{}: {}",
            args.capture
                .file_name()
                .map_or("capture".into(), |n| n.to_string_lossy()),
            ratio_and_cruise
        );
        la::plot::write_png(&report, &title, path)?;
    }
    if args.pulses.is_some() || args.path.is_some() {
        pictures(args, &axes, &file_name(&args.capture))?;
    }
    Ok(report.passed())
}

// the capture's file name, for titles
fn file_name(path: &Path) -> String {
    path.file_name().map_or("capture".into(), |n| n.to_string_lossy().into_owned())
}

// --pulses and --path: a second pass keeps the mapped lines in memory and draws them
fn pictures(args: &Args, axes: &[AxisChannels], name: &str) -> Result<()> {
    let ok = |v: f64| v.is_finite() && v >= 0.0;
    if !ok(args.pulses_at) || !ok(args.pulses_us) || args.pulses_us == 0.0 {
        return Err(anyhow!("--pulses-at must be 0 or more and --pulses-us more than 0"));
    }
    if args.per_mm.is_some_and(|p| !(p.is_finite() && p > 0.0)) {
        return Err(anyhow!("--per-mm must be more than 0"));
    }
    let rate = args.samplerate.as_deref().map(parse_rate).transpose()?;
    let mut capture = la::open(&args.capture, args.format, rate)?;
    let mut trace = la::trace::Trace::new(axes, args.dir_invert);
    capture
        .stream(&mut trace)
        .with_context(|| format!("cannot read {}", args.capture.display()))?;
    if let Some(path) = &args.pulses {
        let first = trace.first_step_ps().ok_or_else(|| anyhow!("--pulses: no step edges"))?;
        let from = first + (args.pulses_at * 1e9).round() as u64;
        let title = format!("{name} at {} ms, {} us", args.pulses_at, args.pulses_us);
        let len = (args.pulses_us * 1e6).round() as u64;
        la::pulses::write_png(&trace, from, len, &title, path)?;
        let counts: Vec<String> = (0..trace.axes.len())
            .filter(|&i| !trace.axes[i].steps.is_empty())
            .map(|i| format!("{} {}", trace.axes[i].name, la::pulses::rising_in(&trace, i, from, from + len)))
            .collect();
        println!("pulses: {} rising edges in {} us from {} ms after the first ({})", counts.join(", "), args.pulses_us, args.pulses_at, path.display());
    }
    if let Some(path) = &args.path {
        let (per, unit) = args.per_mm.map_or((1.0, "steps"), |p| (p, "mm"));
        let top = la::path::write_png(&trace, per, unit, name, path)?;
        println!("path: top XY speed {top:.0} {unit}/min over 5 ms ({})", path.display());
    }
    Ok(())
}

// channel names of one axis
fn lines_of(axis: &AxisChannels, channels: &[String]) -> AxisLines {
    AxisLines {
        axis: axis.name.clone(),
        step: channels[axis.step].clone(),
        dir: axis.dir.map(|d| channels[d].clone()),
    }
}

// the report for people: source line, summary, table
fn print_human(output: &Output) {
    let rate = output
        .sample_rate_hz
        .map_or(String::new(), |r| format!(", {} MHz", r / 1e6));
    let lines: Vec<String> = output
        .lines
        .iter()
        .map(|l| {
            format!(
                "{}={}{}",
                l.axis,
                l.step,
                l.dir.as_ref().map_or(String::new(), |d| format!("/{d}"))
            )
        })
        .collect();
    let format = match output.format {
        Format::Vcd => "VCD",
        Format::Csv => "CSV",
    };
    println!("{} ({format}{rate}): {}", output.capture, lines.join(" "));
    print!("{}", output.report);
}

// run and map the outcome to the exit code
fn main() -> ExitCode {
    // `cargo la` already ends in `--`, so `cargo la -- CAPTURE --expect ..` passes a second
    // one: drop a leading `--` so options after the capture still count.
    let argv = std::env::args_os()
        .enumerate()
        .filter(|(i, a)| !(*i == 1 && a == "--"))
        .map(|(_, a)| a);
    let args = Args::parse_from(argv);
    match run(&args) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("la: error: {e:#}");
            ExitCode::from(2)
        }
    }
}
