//! Issue 27's raster: a LaserGRBL-style job (`M4`, one `G1 X… S…` line per pixel at F6000,
//! rows alternating) streamed with character counting over USART1 or the modeled USB, against
//! the same path sent as one line per row. For the `usb_link` benchmark and bench/RESULTS.md
//! (the sweep's results file), which print the same figures.

use anyhow::Result;

use super::sender::{stream_char_count_polled, Link};
use super::{firmware_elf, Board, HZ, STEP_PINS};
use ddastep::grbl::settings::Settings;
use ddastep::grbl::store::Stored;

/// Rows in each raster: 20 rows of 20 mm.
pub const ROWS: usize = 20;
/// The two pixel sizes: (pixels a row, mm a pixel). At F6000 (100 mm/s) 0.1 mm pixels are
/// 1 000 lines/s of motion, 0.05 mm pixels 2 000.
pub const PIXELS: [(usize, f64); 2] = [(200, 0.1), (400, 0.05)];
/// How often the fill run asks `?` (as senders poll the status while streaming).
pub const POLL: u64 = HZ / 100;

// the decimals a row's Y (and the row end's X) needs at `pitch` mm: 1 at 0.1 mm, 2 at 0.05
fn decimals(pitch: f64) -> usize {
    if (pitch * 10.0).fract().abs() < 1e-9 {
        1
    } else {
        2
    }
}

/// Rows of `pixels` pixels of `pitch` mm (rows `pitch` apart), alternating, one `G1 X… S…`
/// line each (LaserGRBL's raster).
pub fn raster(rows: usize, pixels: usize, pitch: f64) -> Vec<String> {
    let mut v = vec!["G90 G21".to_string(), "M4 S0".to_string(), "G0 X0 Y0".to_string(), "G1 F6000".to_string()];
    for r in 0..rows {
        v.push(format!("Y{:.*}", decimals(pitch), r as f64 * pitch));
        for p in 1..=pixels {
            let x = if r % 2 == 0 { p } else { pixels - p };
            // (Issue 27's line, `G1 X12.345 S123`: 720 lines/s at most at 115200 baud.)
            v.push(format!("G1 X{:.3} S{}", x as f64 * pitch, 100 + (x * 37 + r * 11) % 900));
        }
    }
    v.push("M5".to_string());
    v
}

/// The same path as one line per row.
pub fn rows_only(rows: usize, pixels: usize, pitch: f64) -> Vec<String> {
    let mut v = vec!["G90 G21".to_string(), "M4 S0".to_string(), "G0 X0 Y0".to_string(), "G1 F6000".to_string()];
    for r in 0..rows {
        v.push(format!("Y{:.*}", decimals(pitch), r as f64 * pitch));
        v.push(format!("X{:.*} S500", decimals(pitch), if r % 2 == 0 { pixels as f64 * pitch } else { 0.0 }));
    }
    v.push("M5".to_string());
    v
}

/// What one streamed job gave.
#[derive(Clone, Debug)]
pub struct Job {
    /// Lines from the first line written to the last reply, per modeled second.
    pub lines_per_s: f64,
    /// First to last step, modeled seconds.
    pub steps_s: f64,
    /// 1 ms windows without a step between the first and the last step.
    pub stepless_ms: usize,
    /// Planner blocks queued in each status report read while lines were still being sent
    /// (after the first step; empty unless polled), and the planner's size (blocks free at rest).
    pub fill: Vec<u32>,
    pub blocks: u32,
}

impl Job {
    // mean and least planner fill over the status reports
    pub fn fill_mean_min(&self) -> (f64, u32) {
        let mean = self.fill.iter().sum::<u32>() as f64 / self.fill.len().max(1) as f64;
        (mean, self.fill.iter().min().copied().unwrap_or(0))
    }
}

/// A fresh board with the bench settings, laser mode and `$10=status_mask`, on `link`.
fn board(link: Link, status_mask: u8) -> Result<Board> {
    let settings = Settings { laser_mode: true, status_mask, ..Settings::BENCH };
    let mut b = Board::load(firmware_elf()?)?;
    b.write_mem(0x0800_0000 + 62 * 1024, &Stored::from(settings).to_bytes())?;
    b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl"))?;
    if link == Link::Usb {
        b.usb_connect(2 * HZ)?;
        b.run_until(HZ / 10, |b| b.usb_output().contains("Grbl"))?;
    }
    Ok(b)
}

// the `Bf:` blocks-free figure of a status report
fn blocks_free(status: &str) -> Option<u32> {
    status.split("|Bf:").nth(1)?.split(',').next()?.parse().ok()
}

/// Streams `lines` over `link` with character counting on a fresh board (bench settings,
/// laser mode); with `poll`, also asks `?` every `poll` modeled cycles with `Bf:` on
/// (`$10=3`) for the planner fill.
pub fn stream_job(link: Link, lines: &[String], poll: Option<u64>) -> Result<Job> {
    let mut b = board(link, if poll.is_some() { 3 } else { 1 })?;
    let mut blocks = 0;
    if poll.is_some() {
        let mark = link.output(&b).len();
        link.send(&mut b, b"?");
        b.run_until(HZ / 10, |b| link.output(b)[mark..].ends_with(b">\r\n"))?;
        blocks = blocks_free(&String::from_utf8_lossy(&link.output(&b)[mark..])).unwrap_or(0);
    }
    let t0 = b.cycles();
    // (The closing M5 waits for the motion to finish before its `ok`.)
    let got = stream_char_count_polled(&mut b, link, lines, 30 * HZ, poll)?;
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
    let fill = got
        .statuses
        .iter()
        .filter(|(t, _)| (first..=got.last_sent).contains(t))
        .filter_map(|(_, s)| blocks_free(s))
        .map(|free| blocks.saturating_sub(free))
        .collect();
    Ok(Job {
        lines_per_s: lines.len() as f64 / ((t1 - t0) as f64 / HZ as f64),
        steps_s: (last - first) as f64 / HZ as f64,
        stepless_ms: idle,
        fill,
        blocks,
    })
}

/// One port at one pixel size: the raster, the same path as one line per row, and the
/// raster again polled for the planner fill (the first two do not poll, so the poll touches
/// none of their figures).
#[derive(Clone, Debug)]
pub struct Figures {
    pub link: Link,
    pub pixels: usize,
    pub pitch: f64,
    pub lines: usize,
    pub raster: Job,
    pub rows: Job,
    pub polled: Job,
}

/// Measures `link` at `pixels` pixels of `pitch` mm.
pub fn measure(link: Link, pixels: usize, pitch: f64) -> Result<Figures> {
    let r = raster(ROWS, pixels, pitch);
    Ok(Figures {
        link,
        pixels,
        pitch,
        lines: r.len(),
        raster: stream_job(link, &r, None)?,
        rows: stream_job(link, &rows_only(ROWS, pixels, pitch), None)?,
        polled: stream_job(link, &r, Some(POLL))?,
    })
}

impl Figures {
    // the port's name as the docs write it
    pub fn port(&self) -> &'static str {
        match self.link {
            Link::Usart => "USART1 (115 200 baud)",
            Link::Usb => "USB",
        }
    }

    // one markdown table row: port, pixel, lines/s, time against one line per row, step-less
    // ms (raster; one line per row), planner fill mean / min of the planner
    pub fn table_row(&self) -> String {
        let (mean, min) = self.polled.fill_mean_min();
        format!(
            "| {} | {} mm ({} lines/s of motion) | {:.0} | {:.3} s / {:.3} s = {:.2}× | {} ({}) | {mean:.1} / {min} of {} ({:.0} lines/s polled) |",
            self.port(),
            self.pitch,
            grouped((100.0 / self.pitch).round() as u64),
            self.raster.lines_per_s,
            self.raster.steps_s,
            self.rows.steps_s,
            self.raster.steps_s / self.rows.steps_s,
            self.raster.stepless_ms,
            self.rows.stepless_ms,
            self.polled.blocks,
            self.polled.lines_per_s,
        )
    }
}

// 2000 -> "2 000", as the docs write numbers
fn grouped(n: u64) -> String {
    if n >= 1000 {
        format!("{} {:03}", n / 1000, n % 1000)
    } else {
        n.to_string()
    }
}

/// The table head for [`Figures::table_row`].
pub const TABLE_HEAD: &str = "| port | pixel | lines/s sustained | steps: raster / one line per row | step-less ms: raster (one line per row) | planner fill while streaming: mean / min of the blocks |\n|---|---|---:|---:|---:|---:|";
