//! Builds tiny test programs from Thumb assembly with `arm-none-eabi-as` and `-ld`
//! (package binutils-arm-none-eabi). For the emulator's own tests. The program gets a vector
//! table at 0x0800_0000 built from `vectors` (symbol names; missing ones point at a `b .`).

use std::path::PathBuf;
use std::process::Command;

use anyhow::{bail, Context, Result};

// assemble `body` (Thumb, unified syntax) with a vector table of `vectors` into an ELF
pub fn build(name: &str, vectors: &[(u32, &str)], body: &str) -> Result<Vec<u8>> {
    static SEQ: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let seq = SEQ.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("ddastep-emu-asm-{}-{seq}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let n = vectors.iter().map(|v| v.0).max().unwrap_or(15).max(15) + 1;
    let mut src = String::from(".syntax unified\n.cpu cortex-m3\n.thumb\n.text\n.word 0x20005000\n");
    for i in 1..n {
        match vectors.iter().find(|v| v.0 == i) {
            Some((_, sym)) => src += &format!(".word {sym}\n"),
            None => src += ".word unhandled\n",
        }
    }
    src += ".thumb_func\nunhandled:\n  b unhandled\n";
    src += body;
    src += "\n";
    let s: PathBuf = dir.join("p.s");
    let o = dir.join("p.o");
    let elf = dir.join("p.elf");
    std::fs::write(&s, src)?;
    run(Command::new("arm-none-eabi-as").args(["-mcpu=cortex-m3", "-mthumb", "-o"]).arg(&o).arg(&s))?;
    run(Command::new("arm-none-eabi-ld")
        .args(["-Ttext=0x08000000", "-Tdata=0x20000000", "-e", "0x08000001", "-o"])
        .arg(&elf)
        .arg(&o))?;
    let bytes = std::fs::read(&elf)?;
    let _ = std::fs::remove_dir_all(&dir);
    Ok(bytes)
}

fn run(cmd: &mut Command) -> Result<()> {
    let out = cmd.output().with_context(|| format!("running {cmd:?} (install binutils-arm-none-eabi)"))?;
    if !out.status.success() {
        bail!("{cmd:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
    }
    Ok(())
}
