//! The sweep's Markdown: the results table, and bench/RESULTS.md (method, look-ahead and
//! move-change figures, the tables per mode, the step ISR's cost, profile and notes).

use std::path::Path;

use anyhow::Result;

use super::measure::run_point;
use super::point::{point_text, verdict_text, Verdict};
use super::search::{Bracket, Options, Sweep};
use super::setup::Mode;
use super::stamp::{flash_bytes, utc_date};
use crate::emu::board::Board;
use crate::emu::clock::HZ;

impl Sweep {
    // the results table (Markdown)
    pub fn table(&self) -> String {
        let mut s = String::new();
        s += "| axes | max kHz (CPU ≤ 95 %) | max kHz (step ISR ≤ 95 %) | CPU / ISR load @ 50 kHz | @ 200 kHz | @ 400 kHz | ISR cycles per step @ 50 kHz | ISR mean / max cycles per entry @ 50 kHz | BSRR offset min / max cycles |\n";
        s += "|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
        for r in &self.rows {
            let load = |hz: u32| match r.at(hz) {
                Some(p) if matches!(p.isr_verdict, Verdict::Ok | Verdict::Load(_)) => {
                    let mark = if p.ok() { "" } else if p.isr_ok() { " ¹" } else { " ²" };
                    format!("{:.0} / {:.0} %{mark}", p.load_max * 100.0, p.isr_load_max * 100.0)
                }
                Some(p) => short_verdict(&p.verdict),
                None => "-".into(),
            };
            let (cps, isr) = match r.at(50_000) {
                Some(p) if p.isr_entries > 0 => (format!("{:.0}", p.isr_cycles_per_step), format!("{:.0} / {}", p.isr_mean_cycles, p.isr_max_cycles)),
                _ => ("-".into(), "-".into()),
            };
            let bsrr_min = r.tried.iter().filter_map(|p| p.bsrr_min).min();
            let bsrr_max = r.tried.iter().filter(|p| p.isr_ok()).filter_map(|p| p.bsrr_max).max();
            let bsrr = format!("{} / {}", bsrr_min.map_or("-".into(), |v| v.to_string()), bsrr_max.map_or("-".into(), |v| v.to_string()));
            let again = r.cpu_passes_again_hz.map_or(String::new(), |hz| format!(" ³ {:.0}", hz as f64 / 1000.0));
            s += &format!(
                "| {} | {}{again} | {} | {} | {} | {} | {cps} | {isr} | {bsrr} |\n",
                r.axes,
                bracket_text(&r.cpu),
                bracket_text(&r.isr),
                load(50_000),
                load(200_000),
                load(400_000)
            );
        }
        s
    }
}

// the master rates the move-change benchmark runs at: 0.5 % under the cap for 1, 3 and 7 axes
// (the firmware's `Timing::max_rate_for`: `$I`'s one-axis cap, and for more axes the handler's
// cost per slave, 17 ticks, on the sweep's short pulse)
fn change_rates(s: &Sweep) -> Vec<(usize, f64)> {
    let base = (72_000_000.0 / s.cap_hz as f64).round();
    [1usize, 3, 7].iter().map(|&a| (a, (72_000_000.0 / (base + 17.0 * (a - 1) as f64)).floor() * 0.995)).collect()
}

// bench/RESULTS.md: command, date, model, table, ISR cost and profile, notes, every point
pub fn results_markdown(s: &Sweep, others: &[Sweep], command: &str, firmware: &str, elf: &Path) -> Result<String> {
    let dual = others.iter().find(|o| o.mode == Mode { dual_edge: true, dma: false });
    let dma = others.iter().find(|o| o.mode == Mode { dual_edge: false, dma: true });
    let dma_dual = others.iter().find(|o| o.mode == Mode { dual_edge: true, dma: true });
    use std::fmt::Write as _;
    let mut m = String::new();
    let (date, commit, flash) = (utc_date(), firmware, flash_bytes(elf));
    let cruise_ms = Options::default().cruise_ms;
    writeln!(m, "# Step-rate sweep on the virtual bench\n")?;
    writeln!(m, "Made by `{command}` on {date} (UTC), firmware {commit}, flash image {flash} bytes;")?;
    writeln!(m, "{} points (about a minute on two cores). Regenerate with the same command after a firmware", s.points)?;
    writeln!(m, "change: on the same firmware only the date changes.\n")?;
    writeln!(m, "## What the numbers are\n")?;
    writeln!(m, "Every cycle and load figure is **modeled**: the release ELF runs on unicorn and the bench charges")?;
    writeln!(m, "Cortex-M3 TRM cycle costs per instruction plus the STM32F103's memory timing: flash lines with")?;
    writeln!(m, "FLASH_ACR's 2 wait states and the prefetch buffer, refills after taken branches, AHB-to-APB")?;
    writeln!(m, "bridge stalls (TIM2 reads 5 cycles, GPIO 3), exception entry 14 / return 12 / tail-chain 8")?;
    writeln!(m, "(bench/README.md, \"Model\"). The memory model is checked against two published silicon")?;
    writeln!(m, "measurements within ±5 % (`bench/tests/emu_silicon.rs`); expect a handler within roughly ±10 %,")?;
    writeln!(m, "and before/after comparisons on the bench much tighter than that. On a board, `$I` reports the")?;
    writeln!(m, "firmware's own DWT measurement of the step interrupt.\n")?;
    writeln!(m, "Per point: reset, then `{}`, `G91` and one `G1` on N axes", s.settings.join("`, `"))?;
    writeln!(m, "(steps X:Y:Z:A:B:C:U = 10:6:4:8:2:7:5, all positive, F for the target master rate, trapezoid")?;
    writeln!(m, "ramp at 10⁸ steps/s²). The firmware's cap (`Timing::max_rate_for`) combines the pulse rule")?;
    writeln!(m, "(2·pulse + 72 ticks) with the step handler's measured cost. `$I` reports {} Hz with these", s.cap_hz)?;
    writeln!(m, "settings: the cap of the search.\n")?;
    writeln!(m, "Measured: {cruise_ms} whole 1 ms windows starting 2 ms after the ramp; each must have X within 1 % of")?;
    writeln!(m, "the target (first-to-last X edge of the window). A rate is **sustainable** when, for the move,")?;
    writeln!(m, "there is no timer overrun, every axis made exactly its steps (rising edges and net count),")?;
    writeln!(m, "cruise held, and no measured window is over 95 % busy. \"CPU\" is everything not asleep in")?;
    writeln!(m, "WFI (step ISR, other interrupts, `idle`); \"ISR\" is the step interrupt's share alone (entry to")?;
    let o = Options::default();
    writeln!(m, "end of return). Per axis count the search scans up from {0} kHz in {0} kHz steps until the step", o.grid_hz / 1000)?;
    writeln!(m, "ISR fails, then bisects each criterion between its last pass and first failure of the scan to")?;
    writeln!(m, "{} kHz: \"max\" is sustainable at every scanned rate up to it.\n", o.resolution_hz / 1000)?;
    writeln!(m, "## Continuous motion (look-ahead)\n")?;
    {
        let mut b = Board::load(elf)?;
        b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl"))?;
        let (r, why) = crate::emu::stream::stream_segments_profiled(&mut b, 300, 0x2545_F491_4F6C_DD1D, &[])?;
        writeln!(m, "300 G1 segments of 0.1–0.5 mm at F3000 (turning up to ±30° each, default settings), sent")?;
        writeln!(m, "like a sender (line, wait for `ok`) at 115200 baud; `cargo bench -p ddastep-bench --target")?;
        writeln!(m, "host-tuple --bench plan_line` prints the same.\n")?;
        writeln!(m, "| what | figure (modeled) |")?;
        writeln!(m, "|---|---|")?;
        writeln!(m, "| thread-mode cycles per streamed line (parse, plan, look-ahead, feeder, polls, replies) | {:.0} ({:.3} ms) |", r.thread_cycles_per_line, r.thread_cycles_per_line / 72_000.0)?;
        let p = &r.plan;
        writeln!(
            m,
            "| parse + plan per line with the look-ahead full (`Controller::gcode` + `Controller::push`, inclusive, interrupts excluded; {} lines): mean / longest parse / longest push | {:.0} ({:.3} ms) / {} / {} |",
            p.lines,
            p.mean,
            p.mean / 72_000.0,
            p.max_parse,
            p.max_push
        )?;
        writeln!(m, "| step ISR during the back-to-back moves: mean / max cycles | {:.1} / {} (max/mean {:.2}) |", r.isr.mean_cycles, r.isr.max_cycles, r.isr.max_cycles as f64 / r.isr.mean_cycles.max(1.0))?;
        writeln!(m, "| 10 ms windows without a step while streaming | {} |", r.starved_windows)?;
        writeln!(m, "| motion time | {:.3} s |\n", r.seconds)?;
        writeln!(m, "At this feed (5 kHz master) most step ticks are far apart; the max is a start from rest or")?;
        writeln!(m, "the end of a chain. Moves changing at the rate cap are measured below.\n")?;
        writeln!(m, "Parse + plan per line was 55 586 modeled cycles before issue 27's cuts (firmware `4499139`:")?;
        writeln!(m, "f32 compares on the bits, per-axis loops over the moving axes only, the look-ahead's forward")?;
        writeln!(m, "pass searching only where an exit can change, the cruise index over whole entries first, the")?;
        writeln!(m, "parsed block filled in place). Where it goes now (`-- --profile` on the same bench: exclusive")?;
        writeln!(m, "cycles inside `gcode` and `push`; `-- --time NAME` gives a function's inclusive cycles and callers):\n")?;
        writeln!(m, "| function | cycles per line | share |")?;
        writeln!(m, "|---|---:|---:|")?;
        for f in why.functions.iter().take(10) {
            writeln!(m, "| `{}` | {:.0} | {:.1} % |", f.function, f.cycles as f64 / p.lines.max(1) as f64, f.share * 100.0)?;
        }
        writeln!(m)?;
    }
    writeln!(m, "### Ramp half: trapezoid and S-curve\n")?;
    {
        writeln!(m, "The engine's ramp half (the TIM4 vector the step interrupt pends at each ramp millisecond,")?;
        writeln!(m, "trigger and move start) on a ramp-heavy job: {}; `cargo bench -p ddastep-bench --target", crate::emu::ramp_half::JOB)?;
        writeln!(m, "host-tuple --bench ramp_half` prints the same. S-curve mode maps every ramp leg through the")?;
        writeln!(m, "logistic there (and finds each move's peak once), the step interrupt is the same.\n")?;
        writeln!(m, "| `$41` | motion | ramp half, modeled cycles per ms of motion (share of the CPU) |")?;
        writeln!(m, "|---|---:|---:|")?;
        for shape in [0, 1] {
            let mut b = Board::load(elf)?;
            let r = crate::emu::ramp_half::measure(&mut b, shape)?;
            let name = if shape == 0 { "0 (trapezoid)" } else { "1 (S-curve)" };
            writeln!(m, "| {name} | {:.0} ms | {:.0} ({:.2} %) |", r.ms, r.per_ms(), r.per_ms() / (HZ / 1000) as f64 * 100.0)?;
        }
        writeln!(m)?;
    }
    writeln!(m, "### Moves changing at the rate cap\n")?;
    writeln!(m, "`ddastep_bench::emu::changes::back_to_back`, as `bench/tests/firmware_lookahead.rs` runs it: the")?;
    writeln!(m, "sweep's settings, one long move, then {} short ones (200 master steps each) queued behind it,", crate::emu::changes::MOVES)?;
    writeln!(m, "at 0.5 % under `Timing::max_rate_for` for the axis count (steps in the sweep's ratio; on 3 and")?;
    writeln!(m, "7 axes Y reverses at every junction: a direction change at speed). The step ISR's runs at")?;
    writeln!(m, "speed (update within {} cycles of the one before) up to the chain's last step; a move", crate::emu::changes::AT_SPEED_CYCLES)?;
    writeln!(m, "change is the tick of a move's last step (it finds the primed successor) and the next one's")?;
    writeln!(m, "first (it enters it); the ramp work runs in its own interrupt.\n")?;
    writeln!(m, "| axes | master rate | mean / max cycles (max/mean) | move change: last step / first step | not at speed (start from rest) / the chain's end |")?;
    writeln!(m, "|---:|---:|---:|---:|---:|")?;
    for (axes, hz) in change_rates(s) {
        let mut b = Board::load(elf)?;
        b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl"))?;
        let r = crate::emu::changes::back_to_back(&mut b, axes, hz)?;
        writeln!(m, "| {axes} | {:.1} kHz | {:.1} / {} ({:.2}) | {} / {} | {} / {} |", hz / 1000.0, r.mean, r.max, r.ratio(), r.max_last, r.max_first, r.max_start, r.max_end)?;
    }
    writeln!(m)?;
    raster_section(&mut m)?;
    writeln!(m, "## Results\n")?;
    m += &s.table();
    writeln!(m, "\nLoad cells: busiest measured window, CPU / step ISR; ¹ sustained except the CPU load (over 95 %),")?;
    writeln!(m, "² the step ISR alone is over 95 % too. A failure is named when the rate was not sustained at all")?;
    writeln!(m, "(\"steps lost\": fewer rising edges on the pins than the move's steps).")?;
    if s.rows.iter().any(|r| r.cpu_passes_again_hz.is_some()) {
        writeln!(m, "³ a scanned rate above the failure where the CPU criterion passes again: the CPU load is not")?;
        writeln!(m, "monotone in the rate (how often `idle` completes its loop and reaches WFI between steps).")?;
    }
    writeln!(m, "BSRR offset: update event to the handler's first GPIOB store, over the points the ISR sustained.\n")?;
    if let Some(d) = dual {
        writeln!(m, "## Dual-edge mode (`$580=1`)\n")?;
        writeln!(m, "The same sweep with `$580=1` first (applied in place): every step toggles its pin, one update")?;
        writeln!(m, "event per step and no compare event. Steps are counted on both edges; the X high time column")?;
        writeln!(m, "is then the shortest time between two toggles of X. `$I` reports {} Hz with these settings", d.cap_hz)?;
        writeln!(m, "(`Timing::min_period_for`, dual-edge rule: the handler's measured cost per step, two toggles a")?;
        writeln!(m, "long tick brings closer still a pulse apart, the pulse plus the store jitter). A \"fails\" just above a row's cap is the")?;
        writeln!(m, "planner's clamp (the move cruises at the cap, not at the target: \"no cruise\" in the point list).\n")?;
        m += &d.table();
        writeln!(m, "\nSide by side (CPU ≤ 95 %; `$I`, one axis: {:.1} kHz single-edge, {:.1} kHz dual-edge):\n", s.cap_hz as f64 / 1000.0, d.cap_hz as f64 / 1000.0)?;
        writeln!(m, "| axes | max kHz, single-edge | max kHz, dual-edge | dual / single |\n|---:|---:|---:|---:|")?;
        for (a, b) in s.rows.iter().zip(&d.rows) {
            let gain = if a.cpu.max_hz > 0 { format!("{:.2}", b.cpu.max_hz as f64 / a.cpu.max_hz as f64) } else { "-".into() };
            writeln!(m, "| {} | {} | {} | {gain} |", a.axes, bracket_text(&a.cpu), bracket_text(&b.cpu))?;
        }
    }
    if let Some(d) = dma {
        writeln!(m, "## DMA burst mode (`$581=1`)\n")?;
        writeln!(m, "The same sweep with `$581=1` first (applied in place): TIM2 paces every edge, DMA1 stores the")?;
        writeln!(m, "words the engine buffered (update event: the step word into GPIOB's BSRR; compare 3: the next")?;
        writeln!(m, "period into ARR; compare 1: the falling-edge word), and the step path is the buffer fill in")?;
        writeln!(m, "DMA1 channel 1's half/complete interrupt (`src/firmware/burst.rs`, `ddastep::motion::burst`). The")?;
        writeln!(m, "\"ISR\" columns are that interrupt; DMA's own bus cycles are charged to the CPU while it runs")?;
        writeln!(m, "(the bench's DMA model, bench/src/emu/dma.rs: 7 cycles per store to GPIO, 9 to TIM2, the")?;
        writeln!(m, "bus-matrix share stolen from a running core). `$I` reports {} Hz with these settings", d.cap_hz)?;
        writeln!(m, "(`Timing::min_period_for`, DMA rule: the fill's measured cost per step, above the pulse and low")?;
        writeln!(m, "time plus the stores' latency margin). A \"fails\" just above a row's cap is the planner's clamp.\n")?;
        m += &d.table();
        writeln!(m)?;
    }
    if let Some(d) = dma_dual {
        writeln!(m, "### DMA burst mode, dual-edge (`$581=1`, `$580=1`)\n")?;
        writeln!(m, "The same with every step toggling its pin: no compare event, no falling-edge store (two DMA")?;
        writeln!(m, "stores per entry). Steps are counted on both edges; the X high time column is the shortest time")?;
        writeln!(m, "between two toggles of X. `$I` reports {} Hz with these settings.\n", d.cap_hz)?;
        m += &d.table();
        writeln!(m)?;
    }
    if !others.is_empty() {
        writeln!(m, "## The modes side by side\n")?;
        writeln!(m, "Highest sustainable master rate per axis count (CPU ≤ 95 %, kHz):\n")?;
        let all: Vec<&Sweep> = std::iter::once(s).chain(others.iter()).collect();
        let head: Vec<String> = all.iter().map(|w| format!("{} (`$I` {:.1})", w.mode.label(), w.cap_hz as f64 / 1000.0)).collect();
        writeln!(m, "| axes | {} |\n|---:|{}", head.join(" | "), "---:|".repeat(all.len()))?;
        for (i, r) in s.rows.iter().enumerate() {
            let cells: Vec<String> = all.iter().map(|w| w.rows.get(i).map_or("-".into(), |r| bracket_text(&r.cpu))).collect();
            writeln!(m, "| {} | {} |", r.axes, cells.join(" | "))?;
        }
        writeln!(m, "| reference: Klipper on an STM32F103 (silicon, 1 stepper, full pulses) | 590 |{}", " |".repeat(all.len() - 1))?;
        writeln!(m, "| reference: grbl32 (silicon, 1 axis) | 222 |{}", " |".repeat(all.len() - 1))?;
        writeln!(m, "\nReference lines from issue 15: Klipper 1.18 M toggles/s (590 kHz with full pulses, one")?;
        writeln!(m, "stepper), grbl32 222 kHz (one axis), both measured on silicon; ours are modeled.\n")?;
    }
    if let Some((a, b)) = isr_cost_fit(s) {
        writeln!(m, "## Step ISR cost\n")?;
        writeln!(m, "Modeled step-ISR cycles per master step at 50 kHz cruise: ≈ {a:.0} + {b:.1} × slaves")?;
        let entries: Vec<f64> = s.rows.iter().filter_map(|r| r.at(50_000).map(|p| p.isr_entries as f64 / (p.target_hz as f64 * cruise_ms as f64 / 1000.0))).collect();
        writeln!(m, "(least squares over the axis counts; entry, body and return included; {:.2}–{:.2} handler entries", entries.iter().copied().fold(f64::INFINITY, f64::min), entries.iter().copied().fold(0.0, f64::max))?;
        writeln!(m, "per step: with a short pulse the compare event is already pending when the update handler")?;
        writeln!(m, "checks it, so the falling edge costs no entry of its own). The step ISR alone saturates the core")?;
        writeln!(m, "at 72 MHz / cycles: ≈ {:.0} kHz for 1 axis, ≈ {:.0} kHz for 7. 500 kHz needs", 72e3 / a, 72e3 / (a + 6.0 * b))?;
        writeln!(m, "≤ 144 cycles per step including entry and return (26). The step interrupt's code (the TIM2")?;
        writeln!(m, "handler, `Stepper::tick`, the plain step of `Stepper::tick_quick`) runs from SRAM, where the")?;
        writeln!(m, "bench charges its fetches sharing the System bus with data (bench/README.md, \"Model\").\n")?;
        let floor = crate::emu::floor::measure()?;
        writeln!(m, "### The step handler's floor\n")?;
        writeln!(m, "A hand-scheduled Thumb handler that does only what interrupt mode's plain step must (the")?;
        writeln!(m, "checks of `Stepper::tick_quick`, the step's state, the rising store first, the compare")?;
        writeln!(m, "event's falling edge, the DWT self-timing `$I` reports), one axis, TIM2 at 250 kHz")?;
        writeln!(m, "(`cargo sim -- --floor`, bench/src/emu/floor.rs; entry and return included):\n")?;
        m += &crate::emu::floor::markdown(&floor);
        writeln!(m, "\nNo compiled handler of the same work goes below the first row ({:.0} cycles; ours: {a:.0}).", floor[0].1)?;
        writeln!(m, "500 kHz in interrupt mode needs ≤ 137 cycles per step at 95 % CPU, so it is out of reach")?;
        writeln!(m, "while every step times itself; without the self-timing the floor would allow it, with")?;
        writeln!(m, "nothing left for the long ticks (a move change, a ramp millisecond) that must also fit.\n")?;
    }
    let mut thread_per_entry = 0.0f64;
    for (axes, hz) in [(7usize, 50_000u32), (1, 50_000)] {
        let p = run_point(elf, axes, hz, cruise_ms, 0.95, true, Mode::default());
        let e = p.isr_entries.max(1) as f64;
        writeln!(m, "### Where the cycles go: {axes} {} at {} kHz ({:.0} cycles per step)\n", if axes == 1 { "axis" } else { "axes" }, hz / 1000, p.isr_cycles_per_step)?;
        writeln!(m, "| step ISR, by function | cycles per entry | share |\n|---|---:|---:|")?;
        for f in &p.profile {
            writeln!(m, "| `{}` | {:.1} | {:.1} % |", f.function, f.cycles as f64 / e, f.share * 100.0)?;
        }
        writeln!(m, "\n| hottest blocks (start, function+offset) | cycles per entry | cycles per run |\n|---|---:|---:|")?;
        for (name, runs, cycles) in p.profile_blocks.iter().take(10) {
            writeln!(m, "| `{name}` | {:.1} | {:.1} |", *cycles as f64 / e, *cycles as f64 / (*runs).max(1) as f64)?;
        }
        let thread: u64 = p.profile_thread.iter().map(|f| f.cycles).sum();
        thread_per_entry = thread_per_entry.max(thread as f64 / e);
        writeln!(m, "\nThread mode in the same windows: {:.0} cycles per step-ISR entry ({}).\n", thread as f64 / e, p.profile_thread.iter().take(4).map(|f| format!("`{}` {:.0}", f.function, f.cycles as f64 / e)).collect::<Vec<_>>().join(", "))?;
    }
    writeln!(m, "## Notes\n")?;
    if thread_per_entry > 50.0 {
        m += IDLE_NOTE;
    }
    m += NOTES;
    writeln!(m, "\n<details><summary>Every point tried</summary>\n\n```")?;
    for r in &s.rows {
        for p in &r.tried {
            writeln!(m, "{}", point_text(p))?;
        }
    }
    for o in others {
        for r in &o.rows {
            for p in &r.tried {
                writeln!(m, "{} {}", o.mode.label(), point_text(p))?;
            }
        }
    }
    writeln!(m, "```\n</details>")?;
    Ok(m)
}

// issue 27's raster over USART1 and the modeled USB (the `usb` build), as the usb_link
// benchmark prints it
fn raster_section(m: &mut String) -> Result<()> {
    use crate::emu::raster;
    use std::fmt::Write as _;
    writeln!(m, "### Streaming a LaserGRBL raster: USART1 against USB\n")?;
    writeln!(m, "`ddastep_bench::emu::raster`: {} rows of 20 mm at F6000 (`M4`, one `G1 X… S…` line per pixel, rows", raster::ROWS)?;
    writeln!(m, "alternating), bench settings with laser mode, streamed with character counting over USART1 at")?;
    writeln!(m, "115 200 baud and over the modeled USB (the release image, USB on by default; the host of")?;
    writeln!(m, "`emu/usb_host.rs`), against the same path sent as one line per row. Lines/s: first line")?;
    writeln!(m, "written to the last reply. Steps: first to last step. Step-less ms: 1 ms windows without a")?;
    writeln!(m, "step between the first and the last step. Planner fill: blocks queued in `Bf:` while lines")?;
    writeln!(m, "are still being sent, from a third run that asks `?` every 10 ms with `$10=3` (the other two")?;
    writeln!(m, "do not poll; the polled run's own line rate is in brackets). `cargo bench -p ddastep-bench")?;
    writeln!(m, "--target host-tuple --bench usb_link` prints the same.\n")?;
    writeln!(m, "{}", raster::TABLE_HEAD)?;
    for (pixels, pitch) in raster::PIXELS {
        for link in [crate::emu::sender::Link::Usart, crate::emu::sender::Link::Usb] {
            writeln!(m, "{}", raster::measure(link, pixels, pitch)?.table_row())?;
        }
    }
    writeln!(m)?;
    Ok(())
}

/// Step-ISR cycles per master step at 50 kHz against the slave count, least squares: (base,
/// per slave), `None` with fewer than two axis counts.
pub fn isr_cost_fit(s: &Sweep) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = s.rows.iter().filter_map(|r| r.at(50_000).filter(|p| p.isr_entries > 0).map(|p| ((r.axes - 1) as f64, p.isr_cycles_per_step))).collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (sx, sy) = (pts.iter().map(|p| p.0).sum::<f64>(), pts.iter().map(|p| p.1).sum::<f64>());
    let sxx = pts.iter().map(|p| p.0 * p.0).sum::<f64>();
    let sxy = pts.iter().map(|p| p.0 * p.1).sum::<f64>();
    let b = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    Some(((sy - b * sx) / n, b))
}

/// Printed when thread mode runs more than 50 cycles per step interrupt.
const IDLE_NOTE: &str = "\
- Thread mode runs about as often as the step interrupt (the \"Thread mode\" figures above): `idle`
  goes round its loop after every wake-up from WFI. Its cycles are preemptible (they never delay
  a step), but they are CPU load: that is why the CPU column stops below the ISR column.
";

/// Notes that hold for the method (findings specific to a firmware version go in the report
/// that accompanies a regeneration).
const NOTES: &str = "\
- Above the ISR limit the firmware does not slow down: the timer keeps its period, handlers run
  back to back, updates are missed (overruns) and a rising edge can merge with the previous pulse
  (a step lost on the pins while the position counter counts it).
- The BSRR offset grows when an update arrives while the previous handler is still running. The
  falling edge comes at the compare event (`$0` + 72 ticks, `STORE_LATENCY_TICKS`, after the
  update) or at the end of the update handler, whichever is later: with the sweep's short pulse
  it is the handler's end (the X high times in the point list); with a pulse longer
  than the handler the high time is `$0` + 48 ticks + the falling store's latency − the rising
  store's, at least `$0` while the BSRR offsets spread by less than 48 ticks.
- Peripheral bridge stalls are modeled (TIM2 reads on APB1 5 cycles, GPIO on APB2 3, writes
  buffered); the APB2 figure is fitted to a silicon measurement, the APB1 one extrapolated.
- The step interrupt includes its own DWT self-measurement (about 25 cycles per entry; `$I`).
- The sweep measures one straight move per point. Back-to-back moves at the `$I` cap (moves
  changing at speed, a direction reversing at every junction) are the \"Moves changing at the
  rate cap\" table above, also checked by `bench/tests/firmware_lookahead.rs`
  (`back_to_back_moves_at_the_rate_cap_keep_every_step`: every step, no overrun); the cap's
  long-tick and low-time terms come from there.
- \"CPU\" includes the ramp interrupt (the engine's ramp half, pended by the step interrupt at
  each ramp millisecond, trigger and move start): a few hundred cycles per millisecond.
";


// a verdict for a table cell
fn short_verdict(v: &Verdict) -> String {
    match v {
        Verdict::Counts(s) => match s.split_once(" (") {
            Some((_, over)) => format!("steps lost ({}", over),
            None => "steps lost".into(),
        },
        Verdict::NoCruise(_) => "no cruise".into(),
        Verdict::Error(_) => "error".into(),
        v => verdict_text(v),
    }
}

fn bracket_text(b: &Bracket) -> String {
    match (b.max_hz, b.fail_hz) {
        (0, Some(f)) => format!("< {:.0}", f as f64 / 1000.0),
        (m, None) => format!("≥ {:.0} (cap)", m as f64 / 1000.0),
        (m, Some(f)) => format!("{:.0} (fails {:.0})", m as f64 / 1000.0, f as f64 / 1000.0),
    }
}
