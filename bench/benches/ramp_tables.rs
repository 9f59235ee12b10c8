//! Prints ramp-table build time and size for a few accelerations (host; a regression signal).

use std::time::Instant;

use ddastep::motion::ramp::{RampConfig, RampTable, Shape};

fn main() {
    println!("ramp table: {} bytes of RAM ({} entries max)", RampTable::<1024>::size_bytes(), 1024);
    println!("{:>10} {:>10} {:>10} {:>8} {:>10} {:>12}", "shape", "v0", "vmax", "accel", "entries", "build µs");
    let mut table: RampTable = RampTable::new();
    for shape in [Shape::Trapezoid, Shape::SCurve] {
        for (v0, vmax, accel) in
            [(500, 50_000, 200_000), (1000, 200_000, 800_000), (1000, 500_000, 2_000_000), (100, 20_000, 50_000)]
        {
            let cfg = RampConfig { v0, vmax, accel, shape };
            let runs = 200;
            let start = Instant::now();
            let mut ok = true;
            for _ in 0..runs {
                ok &= table.build(std::hint::black_box(cfg)).is_ok();
            }
            let us = start.elapsed().as_secs_f64() * 1e6 / runs as f64;
            let entries = if ok { table.len().to_string() } else { "too long".into() };
            println!("{:>10} {v0:>10} {vmax:>10} {accel:>8} {entries:>10} {us:>12.1}", format!("{shape:?}"));
        }
    }
}
