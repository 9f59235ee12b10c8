//! The safety door on the release firmware: the virtual machine opens the door (PC15 low)
//! during a move and closes it again; the move stops (`Door:2` → `Door:1`, `Pn:D`), `~` with
//! the door open does nothing, and after it closes `~` finishes the move with every step.

mod firmware_rig;

use ddastep::grbl::settings::Settings;
use ddastep_bench::emu::{Board, HZ};
use ddastep_bench::machine::MachineSpec;
use firmware_rig::*;

/// X, Y, Z at 100 steps/mm; the door opens at `open_s` and closes at `close_s`.
fn boot_door(open_s: f64, close_s: f64) -> Board {
    let axes: String = ["X", "Y", "Z"].iter().map(|n| format!("[[axis]]\nname='{n}'\nsteps_per_mm=100\n")).collect();
    let doors = format!("[[door]]\nat_s={open_s}\nopen=true\n[[door]]\nat_s={close_s}\nopen=false\n");
    let spec = MachineSpec::parse(&format!("{axes}{doors}")).unwrap();
    boot_machine(&spec, Settings::BENCH)
}

fn x_steps(b: &Board) -> usize {
    steps(b).iter().filter(|s| s.axis == 0).count()
}

#[test]
fn the_door_stops_a_move_and_cycle_start_finishes_it_once_closed() {
    let mut b = boot_door(1.0, 2.0);
    assert!(b.seconds() < 0.9, "booted at {} s", b.seconds());
    // 20 mm at 300 mm/min: 4 s, so the door opens mid-move.
    ok(&mut b, "G1 X20 F300");
    b.run_until_cycle(HZ as u64 * 11 / 10).unwrap();
    let s = status(&mut b);
    assert!(s.starts_with("<Door:2|") || s.starts_with("<Door:1|"), "{s}");
    b.run_until_cycle(HZ as u64 * 15 / 10).unwrap();
    let s = status(&mut b);
    assert!(s.starts_with("<Door:1|") && s.contains("|Pn:D"), "{s}");
    let stopped = x_steps(&b);
    assert!(stopped > 0 && stopped < 2000, "{stopped} steps before the stop");
    // The last step came soon after the door opened: the hold's deceleration, not the move's end.
    let last = steps(&b).iter().filter(|s| s.axis == 0).map(|s| s.cycle).max().unwrap();
    let after_ms = (last as f64 - HZ as f64) * 1e3 / HZ as f64;
    println!("door opened at 1.000 s; last X step {after_ms:.1} ms later; {stopped} of 2000 steps made");
    assert!(after_ms < 200.0, "last step {after_ms} ms after the door opened");

    // `~` with the door open does nothing.
    b.serial_send(b"~");
    b.run_seconds(0.2).unwrap();
    assert_eq!(x_steps(&b), stopped);
    assert!(status(&mut b).starts_with("<Door:1|"));

    b.run_until_cycle(HZ as u64 * 21 / 10).unwrap();
    let s = status(&mut b);
    assert!(s.starts_with("<Door:0|") && !s.contains("Pn:"), "{s}");
    assert_eq!(x_steps(&b), stopped);
    b.serial_send(b"~");
    wait_idle(&mut b, 10.0);
    assert_eq!(net(&steps(&b))[0], 2000, "every step of the move");
    assert!(b.watchdog_resets().is_empty());
}
