//! Every `unsafe` block of the firmware shell says why it is sound: clippy's
//! `undocumented_unsafe_blocks`, denied for the firmware in `src/firmware/mod.rs`, finds none.
//! Only that lint is checked here (`-A clippy::all`: the library's other lints are not this
//! test's business); `.ci/setup` installs clippy.

use std::path::PathBuf;
use std::process::Command;

/// The lint attribute this test relies on (without it clippy would pass vacuously).
const DENY: &str = "#![deny(clippy::undocumented_unsafe_blocks)]";

#[test]
fn firmware_unsafe_blocks_have_safety_comments() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let shell = std::fs::read_to_string(root.join("src/firmware/mod.rs")).expect("src/firmware/mod.rs readable");
    assert!(shell.contains(DENY), "src/firmware/mod.rs lost `{DENY}`");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(&root)
        .args(["clippy", "--release", "--target", "thumbv7m-none-eabi", "--bin", "ddastep", "--", "-A", "clippy::all"])
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("RUSTFLAGS")
        .output()
        .expect("cargo clippy runs (clippy missing? bash .ci/setup installs it)");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "cargo clippy failed for the firmware:\n{stderr}");
    assert!(!stderr.contains("undocumented_unsafe_blocks"), "undocumented unsafe blocks:\n{stderr}");
}
