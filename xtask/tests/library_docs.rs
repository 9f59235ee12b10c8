//! The library's documentation builds without a warning (broken or private intra-doc links,
//! bad HTML, ...): `cargo doc -p ddastep --no-deps --target host-tuple` with
//! RUSTDOCFLAGS="-D warnings", for people who embed the library.

use std::process::Command;

#[test]
fn cargo_doc_of_the_library_has_no_warnings() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(root)
        .args(["doc", "-p", "ddastep", "--no-deps", "--target", "host-tuple"])
        .env_remove("RUSTFLAGS")
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("CARGO_ENCODED_RUSTDOCFLAGS")
        .env("RUSTDOCFLAGS", "-D warnings")
        .output()
        .expect("cargo doc runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "cargo doc failed (a warning is an error here):\n{stderr}");
}
