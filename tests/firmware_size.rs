//! The release firmware fits its budget: flash ≤ 32 KiB, static RAM ≤ 8 KiB.

use object::{Object, ObjectSection, SectionFlags};

/// (flash, static RAM) bytes of the release ELF: allocated sections by address; `.data` counts
/// in both (its image lives in flash and is copied to RAM).
fn footprint() -> (u64, u64) {
    let elf = ddastep_bench::emu::firmware_elf().expect("firmware builds");
    let bytes = std::fs::read(&elf).expect("ELF readable");
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

#[test]
fn release_firmware_fits_32k_flash_and_8k_static_ram() {
    let (flash, ram) = footprint();
    println!("release firmware: flash {flash} B of 32768, static RAM {ram} B of 8192");
    assert!(flash > 4096 && ram > 1024, "implausibly small: {flash} / {ram}");
    assert!(flash <= 32 * 1024, "flash {flash} B > 32 KiB");
    assert!(ram <= 8 * 1024, "static RAM {ram} B > 8 KiB");
}
