//! The USB link against USART1 on the virtual bench (modeled cycles): the same 400 short G1
//! lines streamed with character counting over each, on the firmware defaults (250 steps/mm,
//! F500: about 2 kHz steps, so the motion paces the stream). Prints the line rate, what each port's interrupts cost per line and per ms, USB
//! NAKs, and the step interrupt's latency (update event to its first BSRR store) while the
//! port's interrupts run: stm32-usbd masks every interrupt (PRIMASK) around its register and
//! packet-memory accesses, which the step interrupt sees as latency.
//!
//! Then the LaserGRBL-style raster of issue 27 (`emu::raster`; `M4`, one `X… S…` line per pixel at F6000,
//! rows alternating: 0.1 mm pixels are 1 000 lines/s of motion, 0.05 mm pixels 2 000), streamed
//! with character counting over each port on the bench settings (100 steps/mm; preloaded in
//! flash), against the same path sent as one line per row:
//! lines/s, the time ratio, the 1 ms windows without a step between the first and the last
//! step (step-less ms, for the raster and for one line per row), and the planner fill while
//! lines are still being sent. The fill comes from a third run that polls `?` every 10 ms
//! with `Bf:` on (`$10=3`), as senders poll; the other two do not poll, so the poll does not
//! touch their figures (its own line rate is printed beside the fill).
//!
//! `cargo bench -p ddastep-bench --target host-tuple --bench usb_link` (a few minutes).

use ddastep_bench::emu::nvic::IRQ0;
use ddastep_bench::emu::raster;
use ddastep_bench::emu::sender::{stream_char_count, Link};
use ddastep_bench::emu::{firmware_elf, Board, HZ, TIM2_IRQ, USART1_IRQ};

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

fn main() -> anyhow::Result<()> {
    if !std::env::args().any(|a| a == "--bench") {
        return Ok(());
    }
    run(Link::Usart)?;
    run(Link::Usb)?;
    let mut table = vec![raster::TABLE_HEAD.to_string()];
    for (pixels, pitch) in raster::PIXELS {
        for link in [Link::Usart, Link::Usb] {
            let f = raster::measure(link, pixels, pitch)?;
            table.push(f.table_row());
            let (mean, min) = f.polled.fill_mean_min();
            println!(
                "raster {} rows x {pixels} pixels of {pitch} mm at F6000 over {link:?}: {} lines at {:.0} lines/s; steps {:.3} s, one line per row {:.3} s (x{:.2}); step-less {} ms (1 ms windows without a step; one line per row: {} ms); planner fill while streaming mean {mean:.1}, min {min} of {} blocks ({} status reports, `?` every 10 ms with $10=3: that run {:.0} lines/s)",
                raster::ROWS,
                f.lines,
                f.raster.lines_per_s,
                f.raster.steps_s,
                f.rows.steps_s,
                f.raster.steps_s / f.rows.steps_s,
                f.raster.stepless_ms,
                f.rows.stepless_ms,
                f.polled.blocks,
                f.polled.fill.len(),
                f.polled.lines_per_s,
            );
        }
    }
    println!("As in bench/RESULTS.md (\"Streaming a LaserGRBL raster\"):\n{}", table.join("\n"));
    Ok(())
}
