//! The chip check (`ddastep::grbl::chip`) in the controller: a part with too little flash
//! boots into `ALARM:16` with its reason, refuses every line that would move, unlock or write
//! flash (the reason again, then the error) and keeps the drivers off; a part that fits, or
//! one that does not give its flash size, runs as before; `$I` names the part.

mod protocol_rig;

use ddastep::grbl::chip::Chip;
use ddastep::grbl::settings::Settings;
use protocol_rig::Bench;

const BANNER: &str = "\r\nGrbl 1.1h ['$' for help]\r\n";
const REFUSED: &str = "[MSG:chip flash 32 KiB, needs 64 KiB: motion refused]\r\n";
const UID: [u32; 3] = [0x0034_002B, 0x3136_510E, 0x3736_3833];

fn part(flash_kib: u16) -> Chip {
    Chip { flash_kib, uid: UID, cpuid: 0x411F_C231 }
}

/// A rig booted as the firmware boots: the chip check, then the banner.
fn boot(settings: Settings, chip: Chip) -> (Bench<3>, String) {
    let mut b = Bench::<3>::new(settings);
    b.take();
    b.ctl.chip_check(chip);
    b.ctl.welcome(&mut b.tx);
    let banner = b.take();
    (b, banner)
}

#[test]
fn a_part_too_small_refuses_motion_and_says_why() {
    // `$1=255` would keep the drivers on at rest: the check turns them off anyway.
    let (mut b, banner) = boot(Settings { idle_delay_ms: 255, ..Settings::BENCH }, part(32));
    assert_eq!(banner, format!("{BANNER}ALARM:16\r\n{REFUSED}"));
    assert!(b.status().starts_with("<Alarm|MPos:0.000,0.000,0.000|"));
    // G-code: Grbl's alarm lock, after the reason.
    for line in ["G0 X10", "G1 X1 F100", "G21", "M3 S1000"] {
        assert_eq!(b.line(line), format!("{REFUSED}error:9\r\n"), "{line}");
    }
    // What would unlock, move or write flash: grblHAL's self-test error.
    for line in ["$X", "$H", "$HX", "$J=G91 X1 F100", "$100=50", "$RST=*", "$N0=G0 X1", "$I=mine", "$C", "$SLP"] {
        assert_eq!(b.line(line), format!("{REFUSED}error:49\r\n"), "{line}");
    }
    // Reports still answer.
    for line in ["$", "$$", "$#", "$G", "$N"] {
        let r = b.line(line);
        assert!(r.ends_with("ok\r\n") && !r.contains("error"), "{line}: {r}");
    }
    assert!(b.line("$I").contains("[MSG:chip flash 32 KiB uid 0034002B-3136510E-37363833 cpuid 411FC231]\r\n"));
    b.run_ms(50);
    assert_eq!(b.shared.positions(), [0, 0, 0]);
    assert_eq!(b.ctl.pending_moves(), 0);
    assert!(b.actions.iter().all(|a| !a.enable && !a.save), "drivers stay off, flash untouched");
    // Ctrl-X says it again; nothing unlocks.
    b.byte(0x18);
    b.run_ms(2);
    assert_eq!(b.take(), format!("{BANNER}ALARM:16\r\n{REFUSED}"));
    assert_eq!(b.line("$X"), format!("{REFUSED}error:49\r\n"));
    assert!(b.status().starts_with("<Alarm|"));
}

#[test]
fn parts_that_fit_or_do_not_say_run_and_dollar_i_names_them() {
    for (kib, line) in [
        (64, "[MSG:chip flash 64 KiB uid 0034002B-3136510E-37363833 cpuid 411FC231]"),
        (128, "[MSG:chip flash 128 KiB uid 0034002B-3136510E-37363833 cpuid 411FC231]"),
        (0xFFFF, "[MSG:chip flash unknown uid 0034002B-3136510E-37363833 cpuid 411FC231]"),
    ] {
        let (mut b, banner) = boot(Settings::BENCH, part(kib));
        assert_eq!(banner, BANNER, "{kib} KiB");
        let info = b.line("$I");
        assert!(info.starts_with("[VER:1.1h.ddastep:]\r\n[OPT:"), "{info}");
        assert!(info.contains(&format!("{line}\r\n")) && info.ends_with("ok\r\n"), "{info}");
        assert_eq!(b.line("G0 X1"), "ok\r\n");
        b.run_to_idle(2000);
        assert_eq!(b.shared.positions()[0], 100, "{kib} KiB: moved 1 mm at 100 steps/mm");
    }
    // An ID and a CPUID that read blank are not guessed.
    let (mut b, _) = boot(Settings::BENCH, Chip { flash_kib: 0, uid: [u32::MAX; 3], cpuid: 0 });
    assert!(b.line("$I").contains("[MSG:chip flash unknown uid unknown cpuid unknown]\r\n"));
}

#[test]
fn without_a_chip_check_dollar_i_has_no_chip_line() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    let info = b.line("$I");
    assert!(!info.contains("chip") && info.ends_with("ok\r\n"), "{info}");
}

/// Whatever the flash size register reads, the part boots into `ALARM:16` and refuses a move
/// exactly when it gives a size below the settings pages' end (64 KiB).
fn check_refused_exactly_below_the_settings_pages(kib: u16) -> Result<(), proptest::test_runner::TestCaseError> {
    let (mut b, banner) = boot(Settings::BENCH, part(kib));
    let refused = kib != 0 && kib != 0xFFFF && kib < 64;
    proptest::prop_assert_eq!(banner.contains("ALARM:16\r\n"), refused, "{} KiB: {}", kib, banner);
    let reply = b.line("G91 G0 X0.01");
    let refusal = format!("[MSG:chip flash {kib} KiB, needs 64 KiB: motion refused]\r\nerror:9\r\n");
    proptest::prop_assert_eq!(reply == refusal, refused, "{} KiB: {}", kib, reply);
    proptest::prop_assert_eq!(reply == "ok\r\n", !refused, "{} KiB: {}", kib, reply);
    b.run_ms(5);
    proptest::prop_assert_eq!(b.shared.positions()[0] != 0 || b.ctl.pending_moves() > 0, !refused, "{} KiB", kib);
    Ok(())
}

#[test]
fn refused_exactly_below_the_settings_pages_at_the_edges() {
    for kib in [0, 1, 16, 32, 63, 64, 65, 128, 256, 0xFFFE, 0xFFFF] {
        check_refused_exactly_below_the_settings_pages(kib).unwrap();
    }
}

proptest::proptest! {
    #[test]
    fn refused_exactly_below_the_settings_pages(
        kib in proptest::prop_oneof![0u16..=130, proptest::strategy::Just(0xFFFF), proptest::prelude::any::<u16>()]
    ) {
        check_refused_exactly_below_the_settings_pages(kib)?;
    }
}
