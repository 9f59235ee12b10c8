//! Firmware in the loop: a move reaches its own axes' limits and the engine's cap for its
//! master, whatever the axes it does not move are set to (issue 25, item 2).

mod firmware_rig;

use ddastep::grbl::settings::Settings;
use ddastep_bench::emu::HZ;
use firmware_rig::*;

/// The case: DMA mode, `$0=0.3`, X at 100 steps/mm, 600 000 mm/min and 100 000 mm/s²,
/// Y and Z at the defaults (250 steps/mm, 500 mm/min). `$I` says 1 MHz, and X cruises there
/// with every step (it cruised at 400 kHz, 1 MHz × 100/250, when the ramp table's units were
/// the largest `$100+i` whatever the table's top).
#[test]
fn a_coarse_axis_reaches_the_dma_cap_beside_finer_idle_ones() {
    let mut s = Settings::DEFAULT;
    s.pulse_us = 0.3;
    s.steps_per_mm[0] = 100.0;
    s.max_rate[0] = 600_000.0;
    s.accel[0] = 100_000.0;
    let mut b = boot_dma(s, false);
    let info = reply(&mut b, "$I");
    assert!(info.contains("[MSG:max step rate 1000000 Hz DMA]"), "{info}");
    ok(&mut b, "G91 G1 X2000 F600000");
    // (No status polls during the move: `wait_idle` asks every 10 ms.)
    b.run_seconds(0.25).unwrap();
    wait_idle(&mut b, 1.0);
    let st = steps(&b);
    assert_eq!(net(&st), [200_000, 0, 0, 0, 0, 0, 0]);
    assert_eq!(st.len(), 200_000);
    let x: Vec<u64> = st.iter().map(|s| s.cycle).collect();
    let mid = x.len() / 2;
    let rate = 20_000.0 * HZ as f64 / (x[mid + 10_000] - x[mid - 10_000]) as f64;
    eprintln!("X cruise {rate:.0} Hz");
    assert!((rate - 1e6).abs() < 1e6 * 0.01, "cruise {rate} Hz");
    assert_eq!(b.report().overruns, 0);
}
