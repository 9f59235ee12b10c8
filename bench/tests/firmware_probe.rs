//! Probing on the release firmware (issue 12): the virtual machine's touch probe on Z drives
//! PC14, the firmware's EXTI14 handler stops the engine at its next tick, and `[PRB:]` is the
//! position the pulses made.

mod firmware_rig;

use ddastep::grbl::settings::Settings;
use ddastep::grbl::store::Stored;
use ddastep_bench::emu::{firmware_elf, Board, HZ};
use ddastep_bench::machine::{MachineSpec, VirtualMachine};
use firmware_rig::*;

/// X, Y, Z at 100 steps/mm, a probe on Z at `at_mm`; `Settings::BENCH` in flash; banner seen.
fn boot_probe(at_mm: f64) -> Board {
    let axes: String = ["X", "Y", "Z"].iter().map(|n| format!("[[axis]]\nname='{n}'\nsteps_per_mm=100\n")).collect();
    let spec = MachineSpec::parse(&format!("{axes}[probe]\naxis='Z'\nat_mm={at_mm}\n")).unwrap();
    let mut b = Board::load(firmware_elf().unwrap()).unwrap();
    b.attach_plant(Box::new(VirtualMachine::new(&spec)));
    b.write_mem(STORE_ADDR, &Stored::from(Settings::BENCH).to_bytes()).unwrap();
    assert!(b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl")).unwrap());
    b
}

fn vm(b: &Board) -> &VirtualMachine {
    VirtualMachine::of(b).expect("machine attached")
}

#[test]
fn g38_2_stops_within_one_step_period_of_the_probe_edge() {
    let mut b = boot_probe(-5.0);
    let r = reply(&mut b, "G38.2 Z-10 F100");
    let ev = vm(&b).probe_events().to_vec();
    assert_eq!(ev.len(), 1, "one contact: {ev:?}");
    assert!(ev[0].1);
    let edge = ev[0].0;
    let z: Vec<Step> = steps(&b).into_iter().filter(|s| s.axis == 2).collect();
    let before: Vec<&Step> = z.iter().filter(|s| s.cycle <= edge).collect();
    let after: Vec<&Step> = z.iter().filter(|s| s.cycle > edge).collect();
    let n = before.len();
    assert!(n >= 2);
    let period = before[n - 1].cycle - before[n - 2].cycle;
    assert!(after.len() <= 1, "{} steps after the probe edge", after.len());
    if let Some(s) = after.first() {
        assert!(s.cycle - edge <= period, "last step {} cycles after the edge, period {period}", s.cycle - edge);
    }
    let last = z.last().unwrap().cycle;
    println!(
        "probe edge at cycle {edge}; step period there {period} cycles ({:.0} us); last step {} cycles after the edge; {} step(s) after it",
        period as f64 * 1e6 / HZ as f64,
        last as i64 - edge as i64,
        after.len()
    );
    // Nothing more moves, and PRB is the carriage's position (exact), within a step of -5.
    b.run_seconds(0.5).unwrap();
    assert_eq!(steps(&b).iter().filter(|s| s.axis == 2).count(), z.len());
    let pos = vm(&b).positions_mm()[2];
    assert!((pos + 5.0).abs() <= 0.01 + 1e-9, "stopped at {pos}");
    // (`Settings::BENCH` runs 7 axes: PRB and MPos list them all.)
    assert!(r.contains(&format!("[PRB:0.000,0.000,{pos:.3},")) && r.contains(":1]\r\nok"), "{r}");
    let s = status(&mut b);
    assert!(s.starts_with("<Idle|") && s.contains(&format!("MPos:0.000,0.000,{pos:.3},")) && s.contains("|Pn:P"), "{s}");
}

#[test]
fn g38_2_without_contact_alarms_and_g38_3_does_not() {
    let mut b = boot_probe(-50.0);
    let r = reply(&mut b, "G38.3 Z-1 F600");
    assert!(r.contains("[PRB:0.000,0.000,-1.000,") && r.contains(":0]\r\nok"), "{r}");
    assert!(status(&mut b).starts_with("<Idle|"));
    let r = reply(&mut b, "G38.2 Z-2 F600");
    assert!(r.contains("ALARM:5"), "{r}");
    assert!(status(&mut b).starts_with("<Alarm|"));
    assert_eq!(vm(&b).positions_mm()[2], -2.0);
}
