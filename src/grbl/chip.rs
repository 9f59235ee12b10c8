//! The chip check at boot: what the part's device registers say (flash size, unique ID,
//! CPUID), whether ddastep may run motion on it, and the lines `$I` and the alarm print.
//!
//! Who uses it: the firmware shell reads the registers (`src/firmware/chip.rs`) and hands a
//! [`Chip`] to the controller (`Controller::chip_check`), which refuses motion on a part that
//! fails [`Chip::fits`].
//!
//! The rule: the settings pages sit at a fixed address the linker keeps free (memory.x ends
//! the program at 62 KiB; [`crate::grbl::store::PAGE_OFFSETS`]), so a part needs flash up to
//! their end, [`NEEDED_KIB`] = 64 KiB. A 128 KiB part keeps them there too, its upper half
//! unused: one image runs on both, and where the settings live never hangs on a register that
//! clones get wrong. A flash size the part does not give (0xFFFF, an erased word, or 0) is
//! reported as unknown and does not refuse motion: the image already runs from this flash up
//! to its end, and every store write is read back.
//!
//! Registers: RM0008 §30.1 (flash size, 16 bits, KiB) and §30.2 (unique ID, 96 bits), the
//! Cortex-M3 TRM §4.3.1 (CPUID).

use crate::grbl::reply::{put_hex, put_u32, Out};
use crate::grbl::store::{PAGE_LEN, PAGE_OFFSETS};

/// Flash size register (F_SIZE, 16 bits: KiB), RM0008 §30.1.
pub const FLASH_SIZE_ADDR: u32 = 0x1FFF_F7E0;
/// Unique device ID (96 bits, three words), RM0008 §30.2.
pub const UID_ADDR: u32 = 0x1FFF_F7E8;
/// SCB CPUID (a Cortex-M3 r1p1 reads 0x411FC231), Cortex-M3 TRM §4.3.1.
pub const CPUID_ADDR: u32 = 0xE000_ED00;

/// Flash a part needs: up to the end of the second settings page (64 KiB).
pub const NEEDED_KIB: u16 = ((PAGE_OFFSETS[1] as usize + PAGE_LEN) / 1024) as u16;

/// Longest line [`report`] writes.
pub const REPORT_LEN: usize = b"[MSG:chip flash 65534 KiB uid 01234567-01234567-01234567 cpuid 01234567]\r\n".len();

/// The device registers as read (raw: decoding is [`Chip`]'s methods).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Chip {
    /// F_SIZE as read.
    pub flash_kib: u16,
    /// The unique ID's three words in address order.
    pub uid: [u32; 3],
    /// CPUID as read.
    pub cpuid: u32,
}

impl Chip {
    /// The flash size in KiB; `None` when the part does not give it (0xFFFF or 0).
    pub const fn flash_kib(&self) -> Option<u16> {
        match self.flash_kib {
            0 | 0xFFFF => None,
            k => Some(k),
        }
    }

    /// The unique ID; `None` when every bit reads 1 (erased) or 0.
    pub fn uid(&self) -> Option<[u32; 3]> {
        (!blank(&self.uid)).then_some(self.uid)
    }

    /// CPUID; `None` for 0 or all ones (no core reads so).
    pub fn cpuid(&self) -> Option<u32> {
        (!blank(&[self.cpuid])).then_some(self.cpuid)
    }

    /// Motion may run: the part has the flash the settings pages need, or does not say.
    pub const fn fits(&self) -> bool {
        match self.flash_kib() {
            Some(k) => k >= NEEDED_KIB,
            None => true,
        }
    }
}

/// Every bit of `words` reads 0, or every bit 1 (an erased or absent register).
fn blank(words: &[u32]) -> bool {
    let (mut and, mut or) = (u32::MAX, 0);
    for &w in words {
        and &= w;
        or |= w;
    }
    and == u32::MAX || or == 0
}

/// `words` in hex joined by `-`, or `unknown` when [`blank`].
fn put_words(out: &mut impl Out, words: &[u32]) {
    if blank(words) {
        out.put(b"unknown");
        return;
    }
    for (i, &w) in words.iter().enumerate() {
        if i > 0 {
            out.put(b"-");
        }
        put_hex(out, w);
    }
}

/// `[MSG:chip flash 64 KiB` (or `unknown`): the start of both lines.
fn put_flash(out: &mut impl Out, c: &Chip) {
    out.put(b"[MSG:chip flash ");
    match c.flash_kib() {
        Some(k) => {
            put_u32(out, k as u32);
            out.put(b" KiB");
        }
        None => out.put(b"unknown"),
    }
}

/// `$I`'s chip line: `[MSG:chip flash 64 KiB uid 0034002B-3136510E-37363833 cpuid 411FC231]`
/// (the ID's words in address order; `unknown` for what the part does not give).
pub fn report(out: &mut impl Out, c: &Chip) {
    put_flash(out, c);
    out.put(b" uid ");
    put_words(out, &c.uid);
    out.put(b" cpuid ");
    put_words(out, &[c.cpuid]);
    out.put(b"]\r\n");
}

/// Why motion is refused (after `ALARM:16` at boot, and before the error of every line that
/// would move, unlock or write flash): `[MSG:chip flash 32 KiB, needs 64 KiB: motion refused]`.
pub fn refusal(out: &mut impl Out, c: &Chip) {
    put_flash(out, c);
    out.put(b", needs 64 KiB: motion refused]\r\n");
}
// (The text above names the rule's figure.)
const _: () = assert!(NEEDED_KIB == 64);

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;
    use std::string::String;

    const GENUINE: Chip = Chip { flash_kib: 64, uid: [0x0034_002B, 0x3136_510E, 0x3736_3833], cpuid: 0x411F_C231 };

    fn text(f: impl FnOnce(&mut heapless::Vec<u8, 256>)) -> String {
        let mut b = heapless::Vec::new();
        f(&mut b);
        String::from_utf8(b.to_vec()).unwrap()
    }

    #[test]
    fn lines_say_what_the_part_gives() {
        assert_eq!(
            text(|o| report(o, &GENUINE)),
            "[MSG:chip flash 64 KiB uid 0034002B-3136510E-37363833 cpuid 411FC231]\r\n"
        );
        let clone = Chip { flash_kib: 0xFFFF, uid: [u32::MAX; 3], cpuid: 0 };
        assert_eq!(text(|o| report(o, &clone)), "[MSG:chip flash unknown uid unknown cpuid unknown]\r\n");
        let small = Chip { flash_kib: 32, ..GENUINE };
        assert_eq!(text(|o| refusal(o, &small)), "[MSG:chip flash 32 KiB, needs 64 KiB: motion refused]\r\n");
    }

    #[test]
    fn the_rule_is_the_settings_pages_end() {
        assert_eq!(NEEDED_KIB, 64);
        assert!(GENUINE.fits());
        assert!(Chip { flash_kib: 128, ..GENUINE }.fits());
        assert!(!Chip { flash_kib: 63, ..GENUINE }.fits());
        assert!(!Chip { flash_kib: 32, ..GENUINE }.fits());
        // Unknown: reported, not guessed, and not refused.
        assert!(Chip { flash_kib: 0xFFFF, ..GENUINE }.fits());
        assert!(Chip { flash_kib: 0, ..GENUINE }.fits());
    }

    /// memory.x ends the program where the first settings page starts.
    #[test]
    fn linker_leaves_the_settings_pages() {
        let x = include_str!("../../memory.x");
        let flash = x.lines().find(|l| l.trim_start().starts_with("FLASH")).unwrap();
        let len = flash.split("LENGTH =").nth(1).unwrap().trim_start();
        let kib: u32 = len[..len.find('K').unwrap()].parse().unwrap();
        assert_eq!(kib * 1024, PAGE_OFFSETS[0]);
        assert_eq!(PAGE_OFFSETS[1], PAGE_OFFSETS[0] + PAGE_LEN as u32);
    }

    proptest! {
        #[test]
        fn report_decodes_back(flash in any::<u16>(), uid in any::<[u32; 3]>(), cpuid in any::<u32>()) {
            let c = Chip { flash_kib: flash, uid, cpuid };
            let line = text(|o| report(o, &c));
            prop_assert!(line.len() <= REPORT_LEN);
            let body = line.strip_prefix("[MSG:chip flash ").unwrap().strip_suffix("]\r\n").unwrap();
            prop_assert!(!body.contains(']'));
            let w: std::vec::Vec<&str> = body.split(' ').collect();
            match c.flash_kib() {
                Some(k) => prop_assert_eq!((w[0].parse::<u16>().ok(), w[1]), (Some(k), "KiB")),
                None => prop_assert_eq!(w[0], "unknown"),
            }
            let rest = &w[w.len() - 4..];
            prop_assert_eq!((rest[0], rest[2]), ("uid", "cpuid"));
            let uid_back: Option<std::vec::Vec<u32>> = rest[1].split('-').map(|h| u32::from_str_radix(h, 16).ok()).collect();
            prop_assert_eq!(uid_back, c.uid().map(|u| u.to_vec()));
            prop_assert!(rest[1] == "unknown" || rest[1].len() == 26, "{}", rest[1]);
            prop_assert_eq!(u32::from_str_radix(rest[3], 16).ok(), c.cpuid());
            // Refused exactly when a size is given and below the settings pages' end.
            prop_assert_eq!(c.fits(), flash == 0 || flash == 0xFFFF || flash >= NEEDED_KIB);
        }
    }
}
