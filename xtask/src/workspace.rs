//! The crate roots of the workspace: for each member folder of the root Cargo.toml, its
//! `src/lib.rs`, `src/main.rs`, `src/bin/*.rs`, `tests/*.rs` and `benches/*.rs`. Used by
//! `cycles.rs`.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

/// Member folders listed in `[workspace] members = [...]` of `root/Cargo.toml`.
pub fn members(root: &Path) -> io::Result<Vec<PathBuf>> {
    let manifest = fs::read_to_string(root.join("Cargo.toml"))?;
    let Some(start) = manifest.find("members") else {
        return Ok(vec![root.to_path_buf()]);
    };
    let rest = &manifest[start..];
    let (open, close) = match (rest.find('['), rest.find(']')) {
        (Some(open), Some(close)) if open < close => (open, close),
        _ => return Err(io::Error::other("Cargo.toml: `members` is not a list")),
    };
    Ok(rest[open + 1..close]
        .split(',')
        .map(|item| item.trim().trim_matches('"'))
        .filter(|item| !item.is_empty())
        .map(|item| root.join(item))
        .collect())
}

/// Every crate root file of one member folder, sorted.
pub fn crate_roots(member: &Path) -> Vec<PathBuf> {
    let mut roots: Vec<PathBuf> = ["src/lib.rs", "src/main.rs"]
        .iter()
        .map(|file| member.join(file))
        .filter(|file| file.is_file())
        .collect();
    for dir in ["src/bin", "tests", "benches"] {
        roots.extend(rust_files(&member.join(dir)));
    }
    roots
}

/// The `.rs` files directly in `dir` (none if it does not exist), sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|entry| entry.path())
        .filter(|path| path.is_file() && path.extension().is_some_and(|ext| ext == "rs"))
        .collect();
    files.sort();
    files
}
