//! Repository checks run as `cargo xtask <task>` (alias in .cargo/config.toml; host build).
//!
//! - `cycles`: import cycles between files in every crate of the workspace (`cycles.rs`);
//!   exits 1 and prints each cycle as a chain of files if there is one. CI runs it.
//! - `dist`: builds the release firmware and writes `target/dist/ddastep-VERSION.elf`, `.bin`
//!   and `.hex` (`dist.rs`), printing each file's size and SHA-256.

mod cycles;
mod dist;
mod graph;
mod modtree;
mod paths;
mod workspace;

use std::path::PathBuf;
use std::process::ExitCode;

const USAGE: &str = "usage: cargo xtask cycles [--root DIR]
       cargo xtask dist [--root DIR] [--out DIR]

  cycles   list import cycles between files in every crate of the workspace
           (the library, its firmware binary, the bench, the checker, xtask; their tests and
           benches); exit 1 if there is one
  dist     build the release firmware and write ddastep-VERSION.elf, .bin (as objcopy -O binary)
           and .hex (Intel HEX, as objcopy -O ihex) to target/dist/; VERSION from
           `git describe --always --dirty --tags`; prints each file's size and SHA-256
  --root   workspace root (default: the folder above xtask/)
  --out    folder for the dist files (default: target/dist, in $CARGO_TARGET_DIR if set)";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."));
    let mut task = None;
    let mut out: Option<PathBuf> = None;
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--root" => match it.next() {
                Some(dir) => root = PathBuf::from(dir),
                None => return usage_error("--root needs a folder"),
            },
            "--out" => match it.next() {
                Some(dir) => out = Some(PathBuf::from(dir)),
                None => return usage_error("--out needs a folder"),
            },
            "-h" | "--help" | "help" => {
                println!("{USAGE}");
                return ExitCode::SUCCESS;
            }
            name if task.is_none() => task = Some(name.to_owned()),
            other => return usage_error(&format!("unexpected argument `{other}`")),
        }
    }
    match task.as_deref() {
        Some("cycles") => match cycles::check_workspace(&root) {
            Ok(report) => {
                print!("{report}");
                if report.cycles.is_empty() {
                    ExitCode::SUCCESS
                } else {
                    ExitCode::FAILURE
                }
            }
            Err(e) => {
                eprintln!("xtask cycles: {e}");
                ExitCode::from(2)
            }
        },
        Some("dist") => match dist::run(&root, out.as_deref()) {
            Ok(files) => {
                let here = std::env::current_dir().ok().and_then(|d| d.canonicalize().ok());
                for f in files {
                    let shown = here.as_deref().and_then(|h| f.path.strip_prefix(h).ok()).unwrap_or(&f.path);
                    println!("{}  {} bytes  sha256 {}", shown.display(), f.size, f.sha256);
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("xtask dist: {e}");
                ExitCode::from(2)
            }
        },
        Some(other) => usage_error(&format!("unknown task `{other}`")),
        None => usage_error("no task given"),
    }
}

fn usage_error(msg: &str) -> ExitCode {
    eprintln!("xtask: {msg}\n\n{USAGE}");
    ExitCode::from(2)
}
