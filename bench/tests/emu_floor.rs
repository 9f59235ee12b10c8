//! The step handler's floor (bench/src/emu/floor.rs) is a working step handler: one step per
//! update event at TIM2's rate, the rising store first, pulses of the compare's 0.5 µs, its
//! self-timing counting every entry; so its cycles are those of real work.

use ddastep_bench::emu::floor::{program, Parts, VARIANTS};
use ddastep_bench::emu::{Board, HZ};

#[test]
fn the_floor_handler_steps_once_per_update_with_full_pulses() {
    for sram in [true, false] {
        for parts in [Parts { timing: true, fall: true }, Parts { timing: false, fall: true }] {
            let mut b = Board::from_elf_bytes(&program(parts, sram, 250_000).unwrap()).unwrap();
            b.run_for(HZ / 100).unwrap();
            let r = b.report();
            let x = &r.axes.0[0].1;
            // 10 ms at 250 kHz: 2500 updates (the first comes one period after the start).
            assert!(r.step_isr.entries.abs_diff(2500) <= 1, "{parts:?}: {} entries", r.step_isr.entries);
            assert!(x.rising_edges.abs_diff(2500) <= 1, "{parts:?}: {} steps", x.rising_edges);
            assert!((x.max_rate_hz - 250_000.0).abs() < 250.0, "{parts:?}: {} Hz", x.max_rate_hz);
            let high = x.min_high_ns.unwrap();
            assert!((500.0..1000.0).contains(&high), "{parts:?}: high {high} ns");
            assert_eq!(r.overruns, 0);
            // The rising store comes first: within the entry (and its flash refill) and a few loads.
            assert!(r.step_isr.bsrr_offset_max_cycles.unwrap() < 50, "{:?}", r.step_isr);
        }
    }
}

#[test]
fn each_part_of_the_floor_handler_costs_cycles() {
    // Every part left out makes the handler shorter; SRAM beats flash (no wait states).
    let c = |i: usize, sram| ddastep_bench::emu::floor::cycles(VARIANTS[i].1, sram).unwrap();
    let (all, untimed, no_fall, neither) = (c(0, true), c(1, true), c(2, true), c(3, true));
    assert!(untimed < all && no_fall < all && neither < untimed && neither < no_fall, "{all} {untimed} {no_fall} {neither}");
    assert!(all < c(0, false), "SRAM {all}");
}
