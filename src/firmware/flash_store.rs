//! The persistent image (settings, offsets) in the last two 1 KiB flash pages, A/B
//! (`ddastep::grbl::store` says which page is newest); memory.x keeps the program out of them.

use ddastep::grbl::store::PAGE_OFFSETS as STORE_OFFSETS;
use ddastep::grbl::store::{Stored, IMAGE_LEN, PAGE_LEN};
use stm32f1xx_hal::flash;

const FLASH_SIZE: flash::FlashSize = flash::FlashSize::Sz64K;

/// Page `i` of the store, as mapped flash.
fn store_page(i: usize) -> &'static [u8] {
    // SAFETY: the store pages are mapped flash, read-only here; written only by `save`, which
    // runs in the same (idle) context.
    unsafe { core::slice::from_raw_parts((0x0800_0000 + STORE_OFFSETS[i]) as *const u8, PAGE_LEN) }
}

/// The newest valid image of the two pages (defaults when both are blank or torn, or when
/// `read` is false: a part without the pages, `ddastep::grbl::chip`).
pub fn load(read: bool) -> Stored {
    let page = |i| if read { store_page(i) } else { &[] };
    Stored::load([page(0), page(1)]).0
}

/// Writes the image into the page not holding the newest valid one, then reads it back (the
/// CPU stalls while flash is busy: only when idle). A power cut leaves the other page intact.
pub fn save(parts: &mut flash::Parts, image: &[u8; IMAGE_LEN]) {
    let target = Stored::newest([store_page(0), store_page(1)]).map_or(0, |i| 1 - i);
    let at = STORE_OFFSETS[target];
    let mut w = parts.writer(flash::SectorSize::Sz1K, FLASH_SIZE);
    // The read-back below compares the whole image: the HAL's own per-halfword and erase checks
    // would only repeat it (and cost flash).
    w.change_verification(false);
    let ok = w.erase(at, 1024).is_ok() && w.write(at, image).is_ok();
    // (A byte loop: the slice compare would link `memcmp` for this one call.)
    let same = store_page(target).iter().zip(image).all(|(a, b)| a == b);
    if !ok || !same {
        defmt::warn!("store: flash write failed; the previous image stays in force");
    }
}
