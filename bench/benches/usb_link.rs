//! The USB link against USART1 on the virtual bench (modeled cycles): the same 400 short G1
//! lines streamed with character counting over each, on the firmware defaults (250 steps/mm,
//! F500: about 2 kHz steps, so the motion paces the stream). Prints the line rate, what each port's interrupts cost per line and per ms, USB
//! NAKs, and the step interrupt's latency (update event to its first BSRR store) while the
//! port's interrupts run: stm32-usbd masks every interrupt (PRIMASK) around its register and
//! packet-memory accesses, which the step interrupt sees as latency.
//!
//! Then the LaserGRBL-style raster of issue 27 (`M4`, one `X… S…` line per 0.1 mm pixel at
//! F6000, rows alternating: 1 000 lines/s of motion), streamed with character counting over
//! each port on the bench settings (100 steps/mm; preloaded in flash), against the same path sent as one line per row: lines/s, the time ratio, and the
//! 1 ms windows without a step while the raster runs.
//!
//! `cargo bench -p ddastep-bench --target host-tuple --bench usb_link` (a few minutes).

use ddastep_bench::emu::nvic::IRQ0;
use ddastep_bench::emu::sender::{stream_char_count, Link};
use ddastep::grbl::settings::Settings;
use ddastep::grbl::store::Stored;
use ddastep_bench::emu::{firmware_elf, Board, HZ, STEP_PINS, TIM2_IRQ, USART1_IRQ};

/// USB_LP_CAN1_RX0.
const USB_IRQ: u32 = 20;

fn lines() -> Vec<String> {
    let mut v = vec!["G91".to_string()];
    v.extend((0..400).map(|i| format!("G1 X{:.3} Y{:.3} F500", 0.02 + 0.004 * (i % 5) as f64, if i % 2 == 0 { 0.008 } else { -0.008 })));
    v
}

fn run(link: Link) -> anyhow::Result<()> {
    let mut b = Board::load(firmware_elf()?)?;
    let irq = match link {
        Link::Usart => USART1_IRQ,
        Link::Usb => USB_IRQ,
    };
    b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl"))?;
    if link == Link::Usb {
        b.usb_connect(2 * HZ)?;
        b.run_until(HZ / 10, |b| b.usb_output().contains("Grbl"))?;
    }
    b.set_profile(true);
    b.reset_step_isr_stats();
    let lines = lines();
    let t0 = b.cycles();
    let replies = stream_char_count(&mut b, link, &lines, 2 * HZ)?;
    let t1 = b.cycles();
    let ms = (t1 - t0) as f64 / (HZ as f64 / 1000.0);
    let port: u64 = b.profile(IRQ0 + irq).iter().map(|f| f.cycles).sum();
    let r = b.report();
    println!(
        "{link:?}: {} lines ({} ok) in {:.3} s modeled = {:.0} lines/s; port interrupt {:.0} modeled cycles/line, {:.0} cycles/ms ({:.2} % of the CPU)",
        lines.len(),
        replies.iter().filter(|r| *r == "ok").count(),
        ms / 1000.0,
        lines.len() as f64 / (ms / 1000.0),
        port as f64 / lines.len() as f64,
        port as f64 / ms,
        port as f64 / ms / 720.0
    );
    println!(
        "  step ISR during the stream: {} entries, max {} modeled cycles; update event -> first BSRR {:?}..{:?} modeled cycles",
        r.step_isr.entries, r.step_isr.max_cycles, r.step_isr.bsrr_offset_min_cycles, r.step_isr.bsrr_offset_max_cycles
    );
    if let Some(u) = &r.usb {
        println!("  USB: {} bytes out, {} bytes in, {} NAKed OUT packets, {} enumeration(s), errors {:?}", u.bytes_out, u.bytes_in, u.naked_out_packets, u.enumerations, u.errors);
    }
    let _ = TIM2_IRQ;
    Ok(())
}

/// Rows of `pixels` 0.1 mm pixels, alternating, one `G1 X… S…` line each (LaserGRBL's raster).
fn raster(rows: usize, pixels: usize) -> Vec<String> {
    let mut v = vec!["G90 G21".to_string(), "M4 S0".to_string(), "G0 X0 Y0".to_string(), "G1 F6000".to_string()];
    for r in 0..rows {
        v.push(format!("Y{:.1}", r as f64 * 0.1));
        for p in 1..=pixels {
            let x = if r % 2 == 0 { p } else { pixels - p };
            // (Issue 27's line, `G1 X12.345 S123`: 720 lines/s at most at 115200 baud.)
            v.push(format!("G1 X{:.3} S{}", x as f64 * 0.1, 100 + (x * 37 + r * 11) % 900));
        }
    }
    v.push("M5".to_string());
    v
}

/// The same path as one line per row.
fn rows_only(rows: usize, pixels: usize) -> Vec<String> {
    let mut v = vec!["G90 G21".to_string(), "M4 S0".to_string(), "G0 X0 Y0".to_string(), "G1 F6000".to_string()];
    for r in 0..rows {
        v.push(format!("Y{:.1}", r as f64 * 0.1));
        v.push(format!("X{:.1} S500", if r % 2 == 0 { pixels as f64 * 0.1 } else { 0.0 }));
    }
    v.push("M5".to_string());
    v
}

/// Streams `lines` over `link` on a fresh board with the bench settings and laser mode;
/// returns (lines/s from the first line to the last reply, first to last step in s, 1 ms
/// windows without a step between them).
fn stream_job(link: Link, lines: &[String]) -> anyhow::Result<(f64, f64, usize)> {
    let settings = Settings { laser_mode: true, ..Settings::BENCH };
    let mut b = Board::load(firmware_elf()?)?;
    b.write_mem(0x0800_0000 + 62 * 1024, &Stored::from(settings).to_bytes())?;
    b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl"))?;
    if link == Link::Usb {
        b.usb_connect(2 * HZ)?;
        b.run_until(HZ / 10, |b| b.usb_output().contains("Grbl"))?;
    }
    let t0 = b.cycles();
    // (The closing M5 waits for the motion to finish before its `ok`.)
    stream_char_count(&mut b, link, lines, 30 * HZ)?;
    let t1 = b.cycles();
    b.run_seconds(0.5)?;
    let steps: Vec<u64> = b
        .edges()
        .iter()
        .filter(|e| e.port == 1 && e.level && STEP_PINS[..2].contains(&e.pin))
        .map(|e| e.cycle)
        .collect();
    let (first, last) = (steps[0], *steps.last().unwrap());
    let ms = HZ / 1000;
    let mut idle = 0;
    let mut i = 0;
    for w in (first / ms)..(last / ms) {
        while i < steps.len() && steps[i] < w * ms {
            i += 1;
        }
        if i >= steps.len() || steps[i] >= (w + 1) * ms {
            idle += 1;
        }
    }
    Ok((lines.len() as f64 / ((t1 - t0) as f64 / HZ as f64), (last - first) as f64 / HZ as f64, idle))
}

fn main() -> anyhow::Result<()> {
    if !std::env::args().any(|a| a == "--bench") {
        return Ok(());
    }
    run(Link::Usart)?;
    run(Link::Usb)?;
    let (rows, pixels) = (20, 200);
    let r = raster(rows, pixels);
    let whole = rows_only(rows, pixels);
    for link in [Link::Usart, Link::Usb] {
        let (rate, t, idle) = stream_job(link, &r)?;
        let (_, t_rows, _) = stream_job(link, &whole)?;
        println!(
            "raster {rows} rows x {pixels} pixels of 0.1 mm at F6000 over {link:?}: {} lines at {rate:.0} lines/s; steps {t:.3} s, one line per row {t_rows:.3} s (x{:.2}); {idle} ms without a step",
            r.len(),
            t / t_rows
        );
    }
    Ok(())
}
