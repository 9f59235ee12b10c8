//! Throughput of the logic-analyzer checker on a generated 10 s capture in sigrok-cli's VCD
//! format at 24 MHz: X:Y:Z = 5:3:2 with X at 50 kHz (1 M pulses, 2 M edges, ~30 MB).
//! `cargo bench-host --bench la_throughput` (or `cargo bench --target host-tuple -p
//! ddastep-la --bench la_throughput`). Prints numbers; nothing is asserted on time.

use std::io::Write;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ddastep_la::capture::Capture;
use ddastep_la::{Analyzer, AxisChannels, Config};

const RATE: u64 = 24_000_000;
const SECONDS: u64 = 10;

// a sigrok-style VCD (timescale 100 ps, several changes per line) of a 5:3:2 move
fn sigrok_vcd() -> Vec<u8> {
    let mut out = Vec::with_capacity(40 << 20);
    let header = "$date generated $end\n$version libsigrok 0.5.2 $end\n$comment\n  Acquisition with 3/8 channels at 24 MHz\n$end\n\
        $timescale 100 ps $end\n$scope module libsigrok $end\n$var wire 1 ! X_STEP $end\n$var wire 1 \" Y_STEP $end\n\
        $var wire 1 # Z_STEP $end\n$upscope $end\n$enddefinitions $end\n#0 0! 0\" 0#\n";
    out.extend_from_slice(header.as_bytes());
    let ticks = |sample: u64| (sample * 10_000_000_000 + RATE / 2) / RATE;
    let (period, width) = (480, 99); // 50 kHz, 4.125 µs
    let steps = SECONDS * RATE / period - 1;
    let mut accumulators = [steps / 2; 2];
    for k in 0..steps {
        let mut ids = String::from("!");
        for (acc, (count, id)) in accumulators.iter_mut().zip([(3, '"'), (2, '#')]) {
            *acc += count * steps / 5;
            if *acc >= steps {
                *acc -= steps;
                ids.push(id);
            }
        }
        let rise = 240 + k * period;
        let up: Vec<String> = ids.chars().map(|c| format!("1{c}")).collect();
        let down: Vec<String> = ids.chars().map(|c| format!("0{c}")).collect();
        writeln!(out, "#{} {}", ticks(rise), up.join(" ")).unwrap();
        writeln!(out, "#{} {}", ticks(rise + width), down.join(" ")).unwrap();
    }
    writeln!(out, "#{}", ticks(SECONDS * RATE)).unwrap();
    out
}

// the three axes of the generated capture
fn config() -> Config {
    Config::new(vec![
        AxisChannels::new("X", 0, None),
        AxisChannels::new("Y", 1, None),
        AxisChannels::new("Z", 2, None),
    ])
}

// read and check the capture from memory
fn check(vcd: &[u8]) -> u64 {
    let reader = Box::new(std::io::Cursor::new(vcd.to_vec()));
    let mut capture = Capture::from_reader(reader, None, None).unwrap();
    let mut analyzer = Analyzer::new(config()).unwrap();
    capture.stream(&mut analyzer).unwrap();
    analyzer.finish().axes[0].steps
}

// feed the analyzer directly, as the virtual bench does
fn analyze_only(steps: u64) -> u64 {
    let mut analyzer = Analyzer::new(config()).unwrap();
    for ch in 0..3 {
        analyzer.edge(0, ch, false);
    }
    for k in 0..steps {
        let t = 10_000_000 + k * 20_000_000;
        for ch in 0..3 {
            analyzer.edge(t, ch, true);
            analyzer.edge(t + 4_125_000, ch, false);
        }
    }
    analyzer.finish().axes[0].steps
}

// one timed run of the whole 10 s capture, then criterion samples
fn throughput(c: &mut Criterion) {
    let vcd = sigrok_vcd();
    let start = Instant::now();
    let steps = check(&vcd);
    let elapsed = start.elapsed().as_secs_f64();
    println!(
        "la: 10 s / 24 MHz capture, {:.1} MB, {steps} master steps: checked in {elapsed:.3} s ({:.0} MB/s)",
        vcd.len() as f64 / 1e6,
        vcd.len() as f64 / 1e6 / elapsed
    );

    let mut group = c.benchmark_group("la");
    group.sample_size(10);
    group.throughput(Throughput::Bytes(vcd.len() as u64));
    group.bench_function("sigrok_vcd_10s_24MHz", |b| b.iter(|| check(&vcd)));
    group.throughput(Throughput::Elements(6 * 500_000));
    group.bench_function("analyzer_3M_edges", |b| b.iter(|| analyze_only(500_000)));
    group.finish();
}

criterion_group!(benches, throughput);
criterion_main!(benches);
