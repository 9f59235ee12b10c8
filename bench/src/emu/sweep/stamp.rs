//! What a RESULTS.md regeneration is stamped with: the date, the firmware's last commit (git)
//! and its flash bytes.

use std::path::Path;

use crate::emu::firmware::repo_root;

// today's date (UTC) as YYYY-MM-DD
pub(super) fn utc_date() -> String {
    let days = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs() / 86_400) as i64;
    // Civil from days (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let mo = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + (mo <= 2) as i64;
    format!("{y:04}-{mo:02}-{d:02}")
}

// the last commit of the firmware sources, marked when they have uncommitted changes
pub fn firmware_commit() -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git").current_dir(repo_root()).args(args).output().ok().map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    // The last commit that touched the firmware, not HEAD (bench-only commits change nothing).
    let head = git(&["log", "-1", "--format=%h", "--", "src", "Cargo.toml", "Cargo.lock", "memory.x", "build.rs"]).unwrap_or_else(|| "?".into());
    let dirty = git(&["status", "--porcelain", "--", "src", "Cargo.toml", "Cargo.lock", "memory.x", "build.rs"]).is_some_and(|s| !s.is_empty());
    if dirty {
        format!("`{head}` + uncommitted changes in src/")
    } else {
        format!("`{head}`")
    }
}

// bytes the ELF puts in flash, counted as everywhere else (`image_sizes`: text + data)
pub(super) fn flash_bytes(elf: &Path) -> u64 {
    image_sizes(elf).0
}

/// (flash, static RAM) bytes of the ELF, as `arm-none-eabi-size` counts them (text + data,
/// data + bss): the one count RESULTS.md and docs/performance.md print.
pub fn image_sizes(elf: &Path) -> (u64, u64) {
    use object::{Object, ObjectSection, SectionFlags};
    let Ok(bytes) = std::fs::read(elf) else { return (0, 0) };
    let Ok(file) = object::File::parse(&*bytes) else { return (0, 0) };
    let (mut flash, mut ram) = (0, 0);
    for sec in file.sections() {
        let SectionFlags::Elf { sh_flags } = sec.flags() else { continue };
        if sh_flags & u64::from(object::elf::SHF_ALLOC) == 0 {
            continue;
        }
        let in_ram = (0x2000_0000..0x2000_5000).contains(&sec.address());
        let nobits = sec.kind() == object::SectionKind::UninitializedData;
        if !in_ram || !nobits {
            flash += if nobits { 0 } else { sec.size() };
        }
        if in_ram {
            ram += sec.size();
        }
    }
    (flash, ram)
}
