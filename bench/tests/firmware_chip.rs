//! The chip check at boot on the release firmware: the emulated part's flash size register,
//! unique ID and CPUID (`Board::set_chip`) as `$I` reports them; a 64 KiB and a 128 KiB part
//! and one that does not give its size run; a 32 KiB part boots into `ALARM:16` with its
//! reason, refuses motion with the reason each time, keeps its drivers off and its step pins
//! silent, and does not read or write the settings pages.

mod firmware_rig;

use ddastep::board::{ENABLE_PIN, STEP_PINS};
use ddastep::grbl::chip::Chip;
use ddastep::grbl::settings::Settings;
use ddastep::grbl::store::Stored;
use ddastep_bench::emu::{Board, Port, BLUE_PILL};
use firmware_rig::*;

const REFUSED: &str = "[MSG:chip flash 32 KiB, needs 64 KiB: motion refused]\r\n";

/// `$I`'s chip line for the emulator's ID and CPUID with flash `size`.
fn chip_line(size: &str) -> String {
    let [a, b, c] = BLUE_PILL.uid;
    format!("[MSG:chip flash {size} uid {a:08X}-{b:08X}-{c:08X} cpuid 411FC231]\r\n")
}

/// Step edges on the step pins so far.
fn step_edges(b: &Board) -> usize {
    b.edges().iter().filter(|e| e.port == 1 && STEP_PINS.contains(&e.pin)).count()
}

/// A part that runs: `$I` names it, the bench settings came from flash, and a move steps.
fn runs(chip: Chip, size: &str) {
    let mut b = boot_part(Some(Stored::from(Settings::BENCH)), &chip);
    assert!(!b.serial_output().contains("ALARM"), "{}", b.serial_output());
    let info = b.send_line_wait_ok("$I").unwrap();
    assert!(info.contains(&chip_line(size)), "{info}");
    assert!(reply(&mut b, "$$").contains("$100=100.000\r\n"), "settings read from flash");
    ok(&mut b, "G91 G1 X1 F600");
    wait_idle(&mut b, 1.0);
    assert_eq!(steps(&b).len(), 100, "1 mm at 100 steps/mm");
}

#[test]
fn a_64_kib_part_runs() {
    assert_eq!(BLUE_PILL.flash_kib, 64, "the emulator's default part");
    runs(BLUE_PILL, "64 KiB");
}

#[test]
fn a_128_kib_part_runs_with_the_settings_where_they_are() {
    runs(Chip { flash_kib: 128, ..BLUE_PILL }, "128 KiB");
}

#[test]
fn a_part_that_does_not_give_its_size_runs_and_says_unknown() {
    runs(Chip { flash_kib: 0xFFFF, ..BLUE_PILL }, "unknown");
}

#[test]
fn a_32_kib_part_refuses_motion_with_its_reason() {
    let bench = Stored::from(Settings::BENCH);
    let mut b = boot_part(Some(bench), &Chip { flash_kib: 32, ..BLUE_PILL });
    b.run_seconds(0.05).unwrap();
    let boot = b.serial_output().to_string();
    assert!(boot.ends_with(&format!("Grbl 1.1h ['$' for help]\r\nALARM:16\r\n{REFUSED}")), "{boot:?}");
    assert!(status(&mut b).starts_with("<Alarm|"));
    assert_eq!(answer(&mut b, "G91 G1 X10 F600"), format!("{REFUSED}error:9\r\n"));
    for line in ["$X", "$H", "$J=G91 X10 F600", "$100=50"] {
        assert_eq!(answer(&mut b, line), format!("{REFUSED}error:49\r\n"), "{line}");
    }
    let info = b.send_line_wait_ok("$I").unwrap();
    assert!(info.contains(&chip_line("32 KiB")), "{info}");
    // The pages were not read (defaults in force, not the bench's 100 steps/mm) nor written.
    assert!(!reply(&mut b, "$$").contains("$100=100.000\r\n"));
    b.run_seconds(0.3).unwrap();
    assert_eq!(step_edges(&b), 0, "step pins silent");
    assert!(b.output(Port::B, ENABLE_PIN), "drivers off (EN high)");
    assert_eq!(stored(&mut b), Some(bench), "pages untouched");
    // Ctrl-X: the reason again, still refused.
    let mark = b.serial_output().len();
    b.serial_send(&[0x18]);
    b.run_seconds(0.05).unwrap();
    assert!(b.serial_output()[mark..].ends_with(&format!("ALARM:16\r\n{REFUSED}")), "{:?}", &b.serial_output()[mark..]);
    assert_eq!(answer(&mut b, "$X"), format!("{REFUSED}error:49\r\n"));
}

/// Sends a line and returns everything the firmware wrote up to its `ok` or `error`.
fn answer(b: &mut Board, line: &str) -> String {
    let mark = b.serial_output().len();
    let _ = b.send_line_wait_ok(line);
    b.serial_output()[mark..].to_string()
}
