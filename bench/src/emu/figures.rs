//! Figures from a sweep: the rows of docs/performance.md's "Figures" table that the sweep
//! measures are rewritten in place (matched by their first cell), so one command
//! (`bench/figures`) brings docs/performance.md, bench/RESULTS.md and the golden trace up to
//! date. For the `sim` CLI (`--sweep --readme docs/performance.md`).

use std::path::Path;

use anyhow::{bail, Context, Result};

use super::sweep::{image_sizes, isr_cost_fit, Bracket, Sweep, Verdict};

// "327 kHz", or "≥ 327 kHz (the `$I` cap)" when the cap itself passed
fn rate(b: &Bracket) -> String {
    match b.fail_hz {
        None => format!("≥ {} kHz (the `$I` cap)", b.max_hz / 1000),
        Some(_) => format!("{} kHz", b.max_hz / 1000),
    }
}

/// First cell of the size row: only its leading figures are rewritten (see [`rewrite_rows`]).
const SIZE_ROW: &str = "release flash / static RAM";

// 63280 -> "63 280", as the docs write numbers
fn grouped(n: u64) -> String {
    ddastep::grbl::settings::docs::grouped(&n.to_string())
}

// the figures rows (first cell, whole row) this sweep measures
pub fn readme_rows(s: &Sweep, flash_bytes: u64, ram_bytes: u64) -> Vec<(String, String)> {
    let mut rows = Vec::new();
    let mut push = |key: &str, value: String, how: &str| rows.push((key.to_string(), format!("| {key} | {value} | {how} |")));
    push(
        SIZE_ROW,
        format!("{} B of 63 488 / {} B of 16 384", grouped(flash_bytes), grouped(ram_bytes)),
        "`cargo build --release && arm-none-eabi-size target/thumbv7m-none-eabi/release/ddastep`; checked in CI by `bench/tests/firmware_size.rs`",
    );
    let row = |axes: usize| s.rows.iter().find(|r| r.axes == axes);
    let rates: Vec<String> = [1, 3, 7].iter().filter_map(|&a| row(a).map(|r| format!("{} with {a} {}", rate(&r.cpu), if a == 1 { "axis" } else { "axes" }))).collect();
    if !rates.is_empty() {
        push("highest sustainable master rate (no overrun, exact steps, CPU ≤ 95 %)", rates.join(", "), "`cargo sim -- --sweep` → `bench/RESULTS.md`");
    }
    if let Some(r7) = row(7) {
        let load = |hz: u32| match r7.at(hz) {
            Some(p) if matches!(p.isr_verdict, Verdict::Ok | Verdict::Load(_)) => format!("{:.0} %", p.load_max * 100.0),
            Some(p) if p.windows > 0 => format!("{:.0} % (not sustained: {})", p.load_max * 100.0, super::sweep::verdict_text(&p.verdict)),
            _ => "not sustained".into(),
        };
        push("modeled CPU load at 50 / 200 kHz, 7 axes", format!("{} / {}", load(50_000), load(200_000)), "same");
    }
    if let Some((a, b)) = isr_cost_fit(s) {
        let seven = row(7).and_then(|r| r.at(50_000)).map_or(String::new(), |p| format!(" ({:.0} for 7 axes)", p.isr_cycles_per_step));
        push(
            "step interrupt per master step",
            format!("≈ {a:.0} + {b:.1} × slaves modeled cycles{seven}"),
            "same; `cargo sim -- --point 7@200000` shows where they go",
        );
    }
    let sustained = || s.rows.iter().flat_map(|r| r.tried.iter()).filter(|p| p.isr_ok());
    if let (Some(lo), Some(hi)) = (sustained().filter_map(|p| p.bsrr_min).min(), sustained().filter_map(|p| p.bsrr_max).max()) {
        push("update event → BSRR store", format!("{lo}–{hi} modeled cycles"), "same");
    }
    rows
}

// replace the rows of `readme` whose first cell matches; every row must be found. The size
// row keeps what its figure cell says after the two sizes (what takes the RAM, the stack
// figure, which the sweep does not measure) and its last cell.
pub fn rewrite_rows(readme: &str, rows: &[(String, String)]) -> Result<String> {
    let mut out: Vec<String> = readme.lines().map(str::to_string).collect();
    for (key, row) in rows {
        let prefix = format!("| {key} |");
        match out.iter_mut().find(|l| l.starts_with(&prefix)) {
            Some(l) if key == SIZE_ROW => *l = keep_size_details(l, row),
            Some(l) => *l = row.clone(),
            None => bail!("the figures page has no row starting with {prefix:?}"),
        }
    }
    Ok(out.join("\n") + "\n")
}

// the new size row's two sizes in the old row: the old figure cell from its first ` (` or `;`
// on, and the old last cell, are kept
fn keep_size_details(old: &str, new: &str) -> String {
    let cells = |r: &str| r.trim().trim_matches('|').split(" | ").map(|c| c.trim().to_string()).collect::<Vec<_>>();
    let (o, n) = (cells(old), cells(new));
    if o.len() != 3 || n.len() != 3 {
        return new.to_string();
    }
    let tail = o[1].find([';', '(']).map_or("", |i| &o[1][i..]);
    let sep = if tail.starts_with('(') { " " } else { "" };
    format!("| {} | {}{sep}{tail} | {} |", n[0], n[1].trim_end(), o[2].trim())
}

// rewrite the figures rows of the page at `path` (docs/performance.md)
pub fn update_readme(path: &Path, s: &Sweep, elf: &Path) -> Result<()> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let (flash, ram) = image_sizes(elf);
    std::fs::write(path, rewrite_rows(&text, &readme_rows(s, flash, ram))?)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_replaced_by_their_first_cell() {
        let readme = "# x\n| what | figure | how |\n|---|---|---|\n| a | 1 | m |\n| b | 2 | n |\n";
        let out = rewrite_rows(readme, &[("b".into(), "| b | 3 | n |".into())]).unwrap();
        assert_eq!(out, "# x\n| what | figure | how |\n|---|---|---|\n| a | 1 | m |\n| b | 3 | n |\n");
        assert!(rewrite_rows(readme, &[("c".into(), "| c | 0 | - |".into())]).is_err());
    }

    #[test]
    fn the_size_row_keeps_its_details() {
        let readme = "| release flash / static RAM | 61 784 B of 63 488 / 12 440 B of 16 384 (ramp table 4 KiB); deepest stack 6 296 B | `size`; CI |\n";
        let new = format!("| {SIZE_ROW} | {} B of 63 488 / {} B of 16 384 | how |", grouped(63280), grouped(12496));
        let out = rewrite_rows(readme, &[(SIZE_ROW.into(), new)]).unwrap();
        assert_eq!(out, "| release flash / static RAM | 63 280 B of 63 488 / 12 496 B of 16 384 (ramp table 4 KiB); deepest stack 6 296 B | `size`; CI |\n");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(1000), "1 000");
    }
}
