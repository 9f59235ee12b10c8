//! `cargo xtask dist` writes the firmware files a board owner flashes: the `.bin` is byte for
//! byte what `arm-none-eabi-objcopy -O binary` makes of the ELF (.ci/setup installs binutils),
//! the `.hex` holds exactly the same bytes at 0x08000000 and the entry point as its start
//! address (and is what `objcopy -O ihex` writes), and the sizes and SHA-256 sums it prints are
//! those of the files.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use sha2::{Digest, Sha256};

fn root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/..")).canonicalize().unwrap()
}

/// One printed line: path, size, hash.
struct Line {
    path: PathBuf,
    size: u64,
    sha256: String,
}

// run `xtask dist` once into a folder of its own; its stdout lines
fn dist() -> &'static (String, Vec<Line>) {
    static RUN: OnceLock<(String, Vec<Line>)> = OnceLock::new();
    RUN.get_or_init(|| {
        let target = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| root().join("target"));
        let out_dir = target.join("xtask-dist-test");
        let _ = std::fs::remove_dir_all(&out_dir);
        let out = Command::new(env!("CARGO_BIN_EXE_xtask"))
            .args(["dist", "--out"])
            .arg(&out_dir)
            .current_dir(root())
            .env_remove("RUSTFLAGS")
            .env_remove("CARGO_ENCODED_RUSTFLAGS")
            .output()
            .expect("xtask runs");
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(out.status.success(), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
        let lines = stdout
            .lines()
            .map(|l| {
                // "<path>  <size> bytes  sha256 <hex>"
                let f: Vec<&str> = l.split_whitespace().collect();
                assert!(f.len() == 5 && f[2] == "bytes" && f[3] == "sha256", "unexpected line: {l}");
                let path = PathBuf::from(f[0]);
                let path = if path.is_absolute() { path } else { root().join(path) };
                Line { path, size: f[1].parse().unwrap(), sha256: f[4].to_owned() }
            })
            .collect();
        (stdout, lines)
    })
}

// the printed file with this extension
fn file(ext: &str) -> &'static Line {
    let (stdout, lines) = dist();
    let found: Vec<_> = lines.iter().filter(|l| l.path.extension().is_some_and(|e| e == ext)).collect();
    assert_eq!(found.len(), 1, "{stdout}");
    found[0]
}

fn objcopy(format: &str, elf: &Path) -> Vec<u8> {
    let out = std::env::temp_dir().join(format!("ddastep-dist-test-{}.{format}", std::process::id()));
    let status = Command::new("arm-none-eabi-objcopy")
        .args(["-O", format])
        .arg(elf)
        .arg(&out)
        .status()
        .expect("arm-none-eabi-objcopy (binutils-arm-none-eabi; bash .ci/setup installs it)");
    assert!(status.success());
    let bytes = std::fs::read(&out).unwrap();
    let _ = std::fs::remove_file(&out);
    bytes
}

// Intel HEX -> bytes by address and start address (checksums, counts, records 00/01/04/05)
fn parse_hex(text: &str) -> (BTreeMap<u32, u8>, Option<u32>) {
    let mut bytes = BTreeMap::new();
    let (mut upper, mut start, mut end) = (0u32, None, false);
    for line in text.split("\r\n").filter(|l| !l.is_empty()) {
        assert!(!end, "a record after the end record: {line}");
        let raw: Vec<u8> = (1..line.len()).step_by(2).map(|i| u8::from_str_radix(&line[i..i + 2], 16).unwrap()).collect();
        assert!(line.starts_with(':') && line.len() % 2 == 1, "{line}");
        assert_eq!(raw.iter().fold(0u8, |s, b| s.wrapping_add(*b)), 0, "checksum of {line}");
        assert_eq!(raw[0] as usize, raw.len() - 5, "count of {line}");
        let addr = u16::from_be_bytes([raw[1], raw[2]]) as u32;
        let data = &raw[4..raw.len() - 1];
        match raw[3] {
            0 => {
                for (i, b) in data.iter().enumerate() {
                    assert!(bytes.insert(upper + addr + i as u32, *b).is_none(), "written twice: {line}");
                }
            }
            1 => end = true,
            4 => upper = (u16::from_be_bytes([data[0], data[1]]) as u32) << 16,
            5 => start = Some(u32::from_be_bytes([data[0], data[1], data[2], data[3]])),
            other => panic!("record type {other} in {line}"),
        }
    }
    assert!(end, "no end record");
    (bytes, start)
}

// the ELF's entry point (e_entry, 32-bit little-endian ELF)
fn entry(elf: &[u8]) -> u32 {
    assert_eq!(&elf[..6], b"\x7fELF\x01\x01", "a 32-bit little-endian ELF");
    u32::from_le_bytes(elf[24..28].try_into().unwrap())
}

#[test]
fn it_writes_three_files_named_by_version_and_prints_their_sizes_and_hashes() {
    let (stdout, lines) = dist();
    assert_eq!(lines.len(), 3, "{stdout}");
    let described = Command::new("git").current_dir(root()).args(["describe", "--always", "--dirty", "--tags"]).output().unwrap();
    let version = String::from_utf8_lossy(&described.stdout).trim().to_owned();
    assert!(!version.is_empty());
    for (line, ext) in lines.iter().zip(["elf", "bin", "hex"]) {
        assert_eq!(line.path.file_name().unwrap().to_string_lossy(), format!("ddastep-{version}.{ext}"), "{stdout}");
        let bytes = std::fs::read(&line.path).unwrap();
        assert_eq!(line.size, bytes.len() as u64, "{}", line.path.display());
        let sha: String = Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(line.sha256, sha, "{}", line.path.display());
    }
    // the ELF is the release build's
    let built = std::fs::read(
        std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| root().join("target")).join("thumbv7m-none-eabi/release/ddastep"),
    )
    .unwrap();
    assert!(std::fs::read(&file("elf").path).unwrap() == built, "the .elf is not the release build");
}

#[test]
fn the_bin_is_what_objcopy_writes() {
    let bin = std::fs::read(&file("bin").path).unwrap();
    let expected = objcopy("binary", &file("elf").path);
    assert!(bin.len() > 30_000 && bin.len() <= 62 * 1024, "{} bytes", bin.len());
    assert_eq!(bin.len(), expected.len(), "size differs from objcopy -O binary");
    assert!(bin == expected, "bytes differ from objcopy -O binary");
}

#[test]
fn the_hex_holds_the_bin_at_flash_start_with_the_entry_point() {
    let bin = std::fs::read(&file("bin").path).unwrap();
    let text = std::fs::read_to_string(&file("hex").path).unwrap();
    let (bytes, start) = parse_hex(&text);
    // Every byte the hex holds is the bin's at its address; the bin's other bytes are the
    // zero fill objcopy writes between sections (alignment gaps), and the hex ends where it does.
    let held: std::collections::BTreeMap<u32, u8> = bytes.into_iter().collect();
    for (&a, &b) in &held {
        let i = a.checked_sub(0x0800_0000).expect("below flash start") as usize;
        assert_eq!(bin.get(i), Some(&b), "the hex's byte at {a:#x} differs from the bin's");
    }
    for (i, &b) in bin.iter().enumerate() {
        assert!(held.contains_key(&(0x0800_0000 + i as u32)) || b == 0, "bin byte {i:#x} is in no section but not fill");
    }
    assert_eq!(held.keys().next_back().copied(), Some(0x0800_0000 + bin.len() as u32 - 1), "the hex ends where the bin does");
    assert!(bin.len() - held.len() < 64, "gaps of alignment only: {} bytes", bin.len() - held.len());
    let elf = std::fs::read(&file("elf").path).unwrap();
    assert_eq!(start, Some(entry(&elf)), "start address record");
    assert!(text.lines().any(|l| l == ":020000040800F2\r" || l == ":020000040800F2"), "extended linear address 0x0800");
}

#[test]
fn the_hex_is_what_objcopy_writes() {
    let hex = std::fs::read(&file("hex").path).unwrap();
    let expected = objcopy("ihex", &file("elf").path);
    assert!(hex == expected, "the .hex differs from objcopy -O ihex");
}
