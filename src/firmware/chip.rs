//! The chip check's registers, read once in `init` and handed to `ddastep::grbl::chip`, which
//! decodes them, decides and words the reports.

use ddastep::grbl::chip::{Chip, CPUID_ADDR, FLASH_SIZE_ADDR, UID_ADDR};

/// The flash size, unique ID and CPUID as the part gives them.
pub fn read() -> Chip {
    let word = |addr: u32| {
        // SAFETY: the unique ID (system memory, RM0008 §30.2) and CPUID (SCB) are read-only
        // words mapped on every F103 and its clones; an aligned volatile load has no effect.
        unsafe { core::ptr::read_volatile(addr as *const u32) }
    };
    Chip {
        // SAFETY: F_SIZE is a read-only half-word of system memory (RM0008 §30.1), aligned.
        flash_kib: unsafe { core::ptr::read_volatile(FLASH_SIZE_ADDR as *const u16) },
        uid: [word(UID_ADDR), word(UID_ADDR + 4), word(UID_ADDR + 8)],
        cpuid: word(CPUID_ADDR),
    }
}
