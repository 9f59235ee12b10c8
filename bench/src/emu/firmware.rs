//! Locating and building the release firmware ELF once per process, and streaming G-code
//! to a board the way a sender does (one line, then wait for `ok`/`error`). For tests in
//! the repo root's `tests/` and the `sim` CLI.

use std::path::PathBuf;
use std::process::Command;
use std::sync::OnceLock;

use anyhow::{bail, Context, Result};

use super::board::Board;

// the repository root (the bench crate's parent)
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

// build the release firmware once (cargo serializes parallel builds) and return its ELF path
pub fn firmware_elf() -> Result<PathBuf> {
    static ELF: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    ELF.get_or_init(|| build().map_err(|e| format!("{e:#}"))).clone().map_err(anyhow::Error::msg)
}

fn build() -> Result<PathBuf> {
    let root = repo_root();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .current_dir(&root)
        .args(["build", "--release", "--target", "thumbv7m-none-eabi", "--bin", "ddastep"])
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("RUSTFLAGS")
        .status()
        .context("running cargo build for the firmware")?;
    if !status.success() {
        bail!("firmware build failed ({status})");
    }
    let target = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| root.join("target"));
    let elf = target.join("thumbv7m-none-eabi/release/ddastep");
    if !elf.exists() {
        bail!("firmware ELF not found at {}", elf.display());
    }
    Ok(elf)
}

// the G-code lines of a file that a sender would send (comments and blank lines dropped)
pub fn gcode_lines(text: &str) -> Vec<String> {
    text.lines()
        .map(|l| l.split(';').next().unwrap_or("").trim().to_string())
        .filter(|l| !l.is_empty())
        .collect()
}

// send every line and wait for its reply; returns the replies
pub fn stream_gcode(board: &mut Board, text: &str) -> Result<Vec<String>> {
    gcode_lines(text).iter().map(|l| board.send_line_wait_ok(l)).collect()
}
