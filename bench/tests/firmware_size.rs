//! The release firmware, USB port included (feature `usb`, on by default), fits its budget:
//! flash ≤ 62 KiB (the chip's 64 KiB less the two last 1 KiB pages, which hold settings and
//! coordinates), static RAM ≤ 16 KiB of the 20 KiB. A USART1-only image still builds.

mod firmware_rig;

use object::{Object, ObjectSection, ObjectSymbol, SectionFlags};

/// (flash, static RAM) bytes of the release ELF: allocated sections by address; `.data` counts
/// in both (its image lives in flash and is copied to RAM).
fn footprint() -> (u64, u64) {
    footprint_of(&ddastep_bench::emu::firmware_elf().expect("firmware builds"))
}

fn footprint_of(elf: &std::path::Path) -> (u64, u64) {
    let bytes = std::fs::read(elf).expect("ELF readable");
    let file = object::File::parse(&*bytes).expect("ELF parses");
    let (mut flash, mut ram) = (0, 0);
    for s in file.sections() {
        let SectionFlags::Elf { sh_flags } = s.flags() else { continue };
        if sh_flags & u64::from(object::elf::SHF_ALLOC) == 0 || s.size() == 0 {
            continue;
        }
        let name = s.name().unwrap_or("");
        let in_ram = (0x2000_0000..0x2000_5000).contains(&s.address());
        if in_ram {
            ram += s.size();
            if name == ".data" {
                flash += s.size();
            }
        } else {
            flash += s.size();
        }
    }
    (flash, ram)
}

/// Hard budgets (bytes). The aim is flash ≤ 52 KiB; docs/performance.md states the measured figure.
const FLASH_BUDGET: u64 = 62 * 1024;
const RAM_BUDGET: u64 = 16 * 1024;

/// The ELF holds the USB driver (stm32-usbd's functions: the `usb` feature; the vector name
/// alone is also the default handler's alias).
fn has_usb(elf: &std::path::Path) -> bool {
    let bytes = std::fs::read(elf).expect("ELF readable");
    let file = object::File::parse(&*bytes).expect("ELF parses");
    file.symbols().any(|s| s.name().is_ok_and(|n| n.contains("stm32_usbd")))
}

#[test]
fn release_firmware_fits_62k_flash_and_16k_static_ram() {
    let elf = ddastep_bench::emu::firmware_elf().expect("firmware builds");
    assert!(has_usb(&elf), "the release firmware has no USB driver (feature `usb` off?)");
    let (flash, ram) = footprint();
    println!("release firmware: flash {flash} B of {FLASH_BUDGET}, static RAM {ram} B of {RAM_BUDGET}");
    assert!(flash > 4096 && ram > 1024, "implausibly small: {flash} / {ram}");
    assert!(flash <= FLASH_BUDGET, "flash {flash} B > {FLASH_BUDGET} B");
    assert!(ram <= RAM_BUDGET, "static RAM {ram} B > {RAM_BUDGET} B");
}

/// The stack fits beside the statics through a session that reaches the deepest paths:
/// boot, the connect queries, settings and coordinate writes (flash), a CAM job with arcs
/// through the look-ahead, a jog and its cancel, a soft reset. Prints the figure for docs/performance.md.
#[test]
fn stack_stays_clear_of_the_statics_through_a_session() {
    let mut b = firmware_rig::boot();
    for q in ["$I", "$$", "$G", "$#", "$N"] {
        firmware_rig::ok(&mut b, q);
    }
    firmware_rig::ok(&mut b, "$110=30000");
    firmware_rig::ok(&mut b, "G10 L20 P1 X0 Y0 Z0");
    for line in ["G21 G90 G17 F3000", "G1 X10 Y5", "G2 X20 Y5 I5 J0", "G3 X10 Y5 R5", "G18 G2 X20 Z0 I5 K0", "G0 X0 Y0 Z0"] {
        firmware_rig::ok(&mut b, line);
    }
    firmware_rig::wait_idle(&mut b, 10.0);
    firmware_rig::ok(&mut b, "$J=G91 X5 F600");
    b.serial_send(&[0x85]);
    firmware_rig::wait_idle(&mut b, 5.0);
    b.serial_send(&[0x18]);
    b.run_seconds(0.05).expect("runs");
    let (used, room) = b.stack_peak().expect("ELF has _stack_end");
    println!("stack: {used} B used of {room} B between the statics and the top of RAM");
    firmware_rig::assert_stack_fits(&b);
}

/// `--no-default-features` still builds: the USART1-only image (own target dir, so the release
/// ELF the other tests load is not replaced), without the USB handler, within the budget.
#[test]
fn usart_only_build_still_builds_and_fits() {
    let root = ddastep_bench::emu::repo_root();
    let target = std::env::var_os("CARGO_TARGET_DIR").map(std::path::PathBuf::from).unwrap_or_else(|| root.join("target")).join("usart-only");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = std::process::Command::new(cargo)
        .current_dir(&root)
        .args(["build", "--release", "--target", "thumbv7m-none-eabi", "--bin", "ddastep", "--no-default-features", "--target-dir"])
        .arg(&target)
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("RUSTFLAGS")
        .status()
        .expect("cargo runs");
    assert!(status.success(), "cargo build --release --no-default-features failed");
    let elf = target.join("thumbv7m-none-eabi/release/ddastep");
    assert!(!has_usb(&elf), "the USART1-only image has the USB driver");
    let (flash, ram) = footprint_of(&elf);
    println!("USART1-only firmware: flash {flash} B, static RAM {ram} B");
    assert!(flash <= FLASH_BUDGET && ram <= RAM_BUDGET, "{flash} / {ram}");
}
