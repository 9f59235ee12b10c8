//! The virtual machine (`bench/demo/gantry300.toml`) around the release firmware: carriages
//! follow the step pins exactly, limit switches drive PA0-PA2 with bounce, and the firmware
//! shows them in `Pn:` (with `$5` inverting).

mod firmware_rig;

use ddastep::grbl::settings::Settings;
use ddastep_bench::emu::Board;
use ddastep_bench::machine::VirtualMachine;
use firmware_rig::*;

/// The firmware with gantry300's steps/mm, fast rates, wired to the virtual gantry.
fn gantry() -> Board {
    boot_gantry(Settings::BENCH)
}

fn vm(b: &Board) -> &VirtualMachine {
    VirtualMachine::of(b).expect("machine attached")
}

#[test]
fn carriages_follow_the_steps_and_switches_show_in_pn() {
    let mut b = gantry();
    let s = status(&mut b);
    assert!(!s.contains("Pn:"), "carriages in the middle: {s}");
    ok(&mut b, "G91 G1 X150 Y-20 Z-10 F20000");
    wait_idle(&mut b, 5.0);
    let p = vm(&b).positions_mm();
    assert_eq!(vm(&b).steps(), [12_000, -1600, -4000]);
    assert!((p[0] - 300.0).abs() < 1e-9 && (p[1] - 130.0).abs() < 1e-9 && (p[2] - 30.0).abs() < 1e-9, "{p:?}");
    let s = status(&mut b);
    assert!(s.contains("|Pn:X") && !s.contains("Pn:XY"), "X on its max switch: {s}");
    assert!(s.contains("MPos:150.000,-20.000,-10.000"), "{s}");
    // The switch closed once, at the step that reached 300 mm (bounce is inside the bench).
    let ev = vm(&b).events().to_vec();
    assert_eq!(ev.len(), 1);
    assert_eq!((ev[0].axis, ev[0].level), (0, false));
    // Off the switch: released.
    ok(&mut b, "G1 X-0.1 Z50");
    wait_idle(&mut b, 5.0);
    let s = status(&mut b);
    assert!(s.contains("|Pn:Z") && !s.contains("X"), "Z on its top switch, X released: {s}");
    assert_eq!(vm(&b).events().len(), 3);
    // `$5=1` (NC wiring) inverts: the released X and Y read as active, the pressed Z not.
    ok(&mut b, "$5=1");
    let s = status(&mut b);
    assert!(s.contains("|Pn:XY|") || s.ends_with("|Pn:XY>"), "{s}");
}
