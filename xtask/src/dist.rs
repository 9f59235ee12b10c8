//! `cargo xtask dist`: the release firmware as the files a board owner flashes.
//!
//! Builds the firmware (`cargo build --release` for thumbv7m-none-eabi, without the caller's
//! RUSTFLAGS, as the bench does) and writes `ddastep-VERSION.elf`, `.bin` and `.hex` to
//! `target/dist/` (VERSION from `git describe --always --dirty --tags`, else the crate version):
//!
//! - `.bin`: what `arm-none-eabi-objcopy -O binary` writes: every allocated section with file
//!   contents at its load address (LMA, from the PT_LOAD program header that holds it, so
//!   `.data`'s initial values sit right after `.rodata`), from the lowest LMA to the end of the
//!   highest, gaps filled with 0x00;
//! - `.hex`: what `arm-none-eabi-objcopy -O ihex` writes: the same sections in address order,
//!   16 data bytes a record (a section starts a new record; no record crosses 64 KiB), an
//!   extended linear address record (type 04) whenever the upper 16 bits change, the start
//!   linear address record (type 05) holding the entry point, the end record; CR LF lines.
//!
//! Each file is printed with its size and SHA-256.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use object::elf::{FileHeader32, PT_LOAD, SHF_ALLOC, SHT_NOBITS};
use object::read::elf::{FileHeader, ProgramHeader, SectionHeader};
use object::Endianness;
use sha2::{Digest, Sha256};

/// One piece of the flash image: a section's bytes at its load address.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Piece {
    pub lma: u32,
    pub data: Vec<u8>,
}

/// What the ELF puts in flash: its loadable pieces in address order and its entry point.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    pub pieces: Vec<Piece>,
    pub entry: u32,
}

/// The loadable sections of a 32-bit ELF at their load addresses, as objcopy selects them:
/// SHF_ALLOC, not SHT_NOBITS, size > 0; the LMA of a section is p_paddr + (sh_addr - p_vaddr)
/// of the PT_LOAD segment whose file bytes hold it (its own address when none does).
pub fn load_image(elf: &[u8]) -> Result<Image, String> {
    let header = FileHeader32::<Endianness>::parse(elf).map_err(|e| format!("not a 32-bit ELF: {e}"))?;
    let endian = header.endian().map_err(|e| format!("ELF endianness: {e}"))?;
    let segments = header.program_headers(endian, elf).map_err(|e| format!("ELF program headers: {e}"))?;
    let sections = header.sections(endian, elf).map_err(|e| format!("ELF section headers: {e}"))?;
    let mut pieces = Vec::new();
    for sh in sections.iter() {
        let flags = sh.sh_flags(endian);
        let size = sh.sh_size(endian);
        if flags & SHF_ALLOC == 0 || sh.sh_type(endian) == SHT_NOBITS || size == 0 {
            continue;
        }
        let (addr, offset) = (sh.sh_addr(endian), sh.sh_offset(endian));
        let data = sh.data(endian, elf).map_err(|e| format!("section at {addr:#x}: {e}"))?;
        let lma = segments
            .iter()
            .filter(|ph| ph.p_type(endian) == PT_LOAD)
            .find(|ph| {
                let (off, filesz) = (ph.p_offset(endian), ph.p_filesz(endian));
                offset >= off && offset + size <= off + filesz
            })
            .map(|ph| ph.p_paddr(endian).wrapping_add(addr.wrapping_sub(ph.p_vaddr(endian))))
            .unwrap_or(addr);
        pieces.push(Piece { lma, data: data.to_vec() });
    }
    pieces.sort_by_key(|p| p.lma);
    Ok(Image { pieces, entry: header.e_entry(endian) })
}

/// The flat image objcopy -O binary writes: (first address, bytes), gaps 0x00.
pub fn binary(image: &Image) -> (u32, Vec<u8>) {
    let Some(low) = image.pieces.iter().map(|p| p.lma).min() else { return (0, Vec::new()) };
    let high = image.pieces.iter().map(|p| p.lma as u64 + p.data.len() as u64).max().unwrap_or(low as u64);
    let mut out = vec![0u8; (high - low as u64) as usize];
    for p in &image.pieces {
        let at = (p.lma - low) as usize;
        out[at..at + p.data.len()].copy_from_slice(&p.data);
    }
    (low, out)
}

// one Intel HEX record, as BFD's ihex writer formats it (upper-case hex, CR LF)
fn record(out: &mut String, kind: u8, addr: u16, data: &[u8]) {
    let mut sum = data.len() as u8;
    sum = sum.wrapping_add((addr >> 8) as u8).wrapping_add(addr as u8).wrapping_add(kind);
    let _ = write!(out, ":{:02X}{addr:04X}{kind:02X}", data.len());
    for b in data {
        let _ = write!(out, "{b:02X}");
        sum = sum.wrapping_add(*b);
    }
    let _ = write!(out, "{:02X}\r\n", sum.wrapping_neg());
}

/// Intel HEX of the image, record for record what `objcopy -O ihex` writes (BFD ihex.c):
/// 16 bytes a record, a section starts a new record, extended segment address records (02)
/// below 1 MiB and extended linear address records (04) above, start address (03 or 05) when
/// the entry point is not 0, then the end-of-file record.
pub fn intel_hex(image: &Image) -> String {
    let mut out = String::new();
    let (mut segbase, mut extbase) = (0u64, 0u64);
    for p in &image.pieces {
        let mut at = p.lma as u64;
        let mut rest = &p.data[..];
        while !rest.is_empty() {
            let mut now = rest.len().min(16);
            if at < segbase + extbase || at > segbase + extbase + 0xffff {
                if extbase == 0 && at <= 0xfffff {
                    segbase = at & 0xf0000;
                    record(&mut out, 2, 0, &[(segbase >> 12) as u8, (segbase >> 4) as u8]);
                } else {
                    if segbase != 0 {
                        record(&mut out, 2, 0, &[0, 0]);
                        segbase = 0;
                    }
                    extbase = at & 0xffff_0000;
                    record(&mut out, 4, 0, &[(extbase >> 24) as u8, (extbase >> 16) as u8]);
                }
            }
            let rec_addr = at - (extbase + segbase);
            if rec_addr + now as u64 > 0xffff {
                now = (0x10000 - rec_addr) as usize;
            }
            record(&mut out, 0, rec_addr as u16, &rest[..now]);
            at += now as u64;
            rest = &rest[now..];
        }
    }
    let e = image.entry;
    if e != 0 {
        if e <= 0xfffff {
            record(&mut out, 3, 0, &[((e & 0xf0000) >> 12) as u8, 0, (e >> 8) as u8, e as u8]);
        } else {
            record(&mut out, 5, 0, &e.to_be_bytes());
        }
    }
    record(&mut out, 1, 0, &[]);
    out
}

/// The bytes an Intel HEX text holds, by address (records 00, 02, 04; checksums checked), and
/// its start address (record 03 or 05) if any. For the tests and as a self-check after writing.
pub fn parse_intel_hex(text: &str) -> Result<(std::collections::BTreeMap<u32, u8>, Option<u32>), String> {
    let mut bytes = std::collections::BTreeMap::new();
    let (mut base, mut start, mut ended) = (0u32, None, false);
    for (n, line) in text.lines().enumerate() {
        let line = line.trim_end_matches('\r');
        let err = |what: &str| format!("hex line {}: {what}: {line}", n + 1);
        if ended {
            return Err(err("after the end record"));
        }
        let hex = line.strip_prefix(':').ok_or_else(|| err("no ':'"))?;
        if hex.len() % 2 != 0 || hex.len() < 10 {
            return Err(err("bad length"));
        }
        let raw: Vec<u8> = (0..hex.len() / 2)
            .map(|i| u8::from_str_radix(&hex[2 * i..2 * i + 2], 16))
            .collect::<Result<_, _>>()
            .map_err(|_| err("not hex"))?;
        if raw.iter().fold(0u8, |s, b| s.wrapping_add(*b)) != 0 {
            return Err(err("checksum"));
        }
        let (len, addr, kind, data) = (raw[0] as usize, u16::from_be_bytes([raw[1], raw[2]]), raw[3], &raw[4..raw.len() - 1]);
        if data.len() != len {
            return Err(err("count"));
        }
        match (kind, len) {
            (0, _) => {
                for (i, b) in data.iter().enumerate() {
                    if bytes.insert(base.wrapping_add(addr as u32 + i as u32), *b).is_some() {
                        return Err(err("address written twice"));
                    }
                }
            }
            (1, 0) => ended = true,
            (2, 2) => base = (u16::from_be_bytes([data[0], data[1]]) as u32) << 4,
            (4, 2) => base = (u16::from_be_bytes([data[0], data[1]]) as u32) << 16,
            (3, 4) => start = Some(((u16::from_be_bytes([data[0], data[1]]) as u32) << 4) + u16::from_be_bytes([data[2], data[3]]) as u32),
            (5, 4) => start = Some(u32::from_be_bytes([data[0], data[1], data[2], data[3]])),
            _ => return Err(err("unknown record")),
        }
    }
    if !ended {
        return Err("hex: no end record".into());
    }
    Ok((bytes, start))
}

/// SHA-256 of bytes as lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

/// VERSION: `git describe --always --dirty --tags` in the repository, else the root crate's
/// version from its Cargo.toml.
pub fn version(root: &Path) -> String {
    let described = Command::new("git")
        .current_dir(root)
        .args(["describe", "--always", "--dirty", "--tags"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
        .filter(|v| !v.is_empty() && v.chars().all(|c| c.is_ascii_alphanumeric() || "-._+".contains(c)));
    described.unwrap_or_else(|| crate_version(root).unwrap_or_else(|| env!("CARGO_PKG_VERSION").to_owned()))
}

// the `version = "..."` of the root Cargo.toml's [package]
fn crate_version(root: &Path) -> Option<String> {
    let text = std::fs::read_to_string(root.join("Cargo.toml")).ok()?;
    let mut in_package = false;
    for line in text.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            in_package = t == "[package]";
        } else if in_package {
            if let Some(v) = t.strip_prefix("version").map(str::trim_start).and_then(|r| r.strip_prefix('=')) {
                return Some(v.trim().trim_matches('"').to_owned());
            }
        }
    }
    None
}

// the target directory cargo builds into
fn target_dir(root: &Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| root.join("target"))
}

/// Builds the release firmware and returns its ELF path.
pub fn build_firmware(root: &Path) -> Result<PathBuf, String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .current_dir(root)
        .args(["build", "--release", "--target", "thumbv7m-none-eabi", "--bin", "ddastep"])
        // the firmware's flags come from .cargo/config.toml's target table, which RUSTFLAGS
        // would replace
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("RUSTFLAGS")
        .status()
        .map_err(|e| format!("running cargo build: {e}"))?;
    if !status.success() {
        return Err(format!("firmware build failed ({status})"));
    }
    let elf = target_dir(root).join("thumbv7m-none-eabi/release/ddastep");
    if !elf.exists() {
        return Err(format!("firmware ELF not found at {}", elf.display()));
    }
    Ok(elf)
}

/// One written file: its path, size and SHA-256.
pub struct Written {
    pub path: PathBuf,
    pub size: usize,
    pub sha256: String,
}

/// Builds the firmware and writes the three files to `out` (default `<target>/dist`).
pub fn run(root: &Path, out: Option<&Path>) -> Result<Vec<Written>, String> {
    let root = &root.canonicalize().map_err(|e| format!("{}: {e}", root.display()))?;
    let elf_path = build_firmware(root)?;
    let elf = std::fs::read(&elf_path).map_err(|e| format!("{}: {e}", elf_path.display()))?;
    let image = load_image(&elf)?;
    let (base, bin) = binary(&image);
    let hex = intel_hex(&image);
    // self-check: the hex holds exactly the bin's bytes where the bin starts
    let (held, start) = parse_intel_hex(&hex)?;
    let expected: std::collections::BTreeMap<u32, u8> = image
        .pieces
        .iter()
        .flat_map(|p| p.data.iter().enumerate().map(move |(i, b)| (p.lma + i as u32, *b)))
        .collect();
    if held != expected || start != Some(image.entry).filter(|e| *e != 0) {
        return Err("internal error: the Intel HEX does not hold the image".into());
    }
    if held.iter().any(|(a, b)| bin[(a - base) as usize] != *b) {
        return Err("internal error: the .bin does not hold the image".into());
    }
    let out = out.map(Path::to_path_buf).unwrap_or_else(|| target_dir(root).join("dist"));
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let out = out.canonicalize().map_err(|e| format!("{}: {e}", out.display()))?;
    let stem = format!("ddastep-{}", version(root));
    let mut written = Vec::new();
    for (ext, bytes) in [("elf", &elf[..]), ("bin", &bin[..]), ("hex", hex.as_bytes())] {
        let path = out.join(format!("{stem}.{ext}"));
        std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        written.push(Written { path, size: bytes.len(), sha256: sha256_hex(bytes) });
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_splits_at_64k_and_sections_and_round_trips() {
        let image = Image {
            pieces: vec![
                Piece { lma: 0x0800_fff8, data: (0..20).collect() },
                Piece { lma: 0x0801_000c, data: vec![0xAA; 3] },
                Piece { lma: 0x2000_0000, data: vec![1, 2] },
            ],
            entry: 0x0800_0131,
        };
        let hex = intel_hex(&image);
        let lines: Vec<&str> = hex.split("\r\n").filter(|l| !l.is_empty()).collect();
        assert_eq!(
            lines,
            [
                ":020000040800F2",
                ":08FFF8000001020304050607E5",
                ":020000040801F1",
                ":0C00000008090A0B0C0D0E0F1011121352",
                ":03000C00AAAAAAF3",
                ":020000042000DA",
                ":020000000102FB",
                ":0400000508000131BD",
                ":00000001FF",
            ]
        );
        let (bytes, start) = parse_intel_hex(&hex).unwrap();
        assert_eq!(start, Some(0x0800_0131));
        assert_eq!(bytes.len(), 25);
        assert_eq!(bytes[&0x0801_0000], 8);
        let (base, bin) = binary(&Image { pieces: image.pieces[..2].to_vec(), entry: 0 });
        assert_eq!(base, 0x0800_fff8);
        assert_eq!(bin.len(), 0x17);
        assert_eq!(&bin[0x14..], &[0xAA; 3]);
    }

    #[test]
    fn a_bad_checksum_is_refused() {
        assert!(parse_intel_hex(":020000000102FA\r\n:00000001FF\r\n").is_err());
        assert!(parse_intel_hex(":020000000102FB\r\n").is_err());
    }
}
