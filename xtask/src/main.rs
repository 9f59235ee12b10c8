//! Repository checks run as `cargo xtask <task>` (alias in .cargo/config.toml; host build).
//!
//! - `cycles`: import cycles between files in every crate of the workspace (`cycles.rs`);
//!   exits 1 and prints each cycle as a chain of files if there is one. CI runs it.

mod cycles;
mod graph;
mod modtree;
mod paths;
mod workspace;

use std::path::PathBuf;
use std::process::ExitCode;

const USAGE: &str = "usage: cargo xtask cycles [--root DIR]

  cycles   list import cycles between files in every crate of the workspace
           (the library, its firmware binary, the bench, the checker, xtask; their tests and
           benches); exit 1 if there is one
  --root   workspace root (default: the folder above xtask/)";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."));
    let mut task = None;
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--root" => match it.next() {
                Some(dir) => root = PathBuf::from(dir),
                None => return usage_error("--root needs a folder"),
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
        Some(other) => usage_error(&format!("unknown task `{other}`")),
        None => usage_error("no task given"),
    }
}

fn usage_error(msg: &str) -> ExitCode {
    eprintln!("xtask: {msg}\n\n{USAGE}");
    ExitCode::from(2)
}
