//! The step word: the slaves' step bits for one master step, and dual-edge mode's toggle.
//!
//! Who uses it: the step path (a tick's step) and the DMA fill's lanes.

use crate::motion::prepared::Slave;

/// The step bits of the slaves of a move with `n` slaves and `total` master steps, for one
/// master step: unrolled over the slots (N is a constant), stopping after the move's last
/// slave: no loop counter, no bounds checks, no branch inside a slot.
#[inline(always)]
pub(super) fn slave_bits<const N: usize>(slaves: &mut [Slave; N], n: usize, total: u32) -> u32 {
    let mut bits = 0;
    macro_rules! slaves {
        ($out:lifetime; $($i:literal)*) => {$(
            if $i + 1 >= N || $i >= n {
                break $out;
            }
            let s = &mut slaves[$i];
            bits |= s.on & s.dda.step_mask(total);
        )*};
    }
    'slaves: {
        slaves!('slaves; 0 1 2 3 4 5);
    }
    bits
}

/// Dual-edge mode: the BSRR word that toggles the pins of `word`, given their `level` (set
/// those that are low, reset those that are high); `level` follows.
#[inline(always)]
pub(super) fn toggle(word: u32, level: &mut u32) -> u32 {
    let old = *level;
    *level = old ^ word;
    (word & !old) | (word & old) << 16
}
