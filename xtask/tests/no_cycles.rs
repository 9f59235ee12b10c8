//! The repository itself has no import cycle between files (`cargo xtask cycles`).

use std::process::Command;

#[test]
fn the_workspace_has_no_import_cycles() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let out = Command::new(env!("CARGO_BIN_EXE_xtask")).args(["cycles", "--root", root]).output().expect("xtask runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.starts_with("no import cycles"), "{text}");
}
