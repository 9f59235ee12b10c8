//! DMA burst mode: the buffers the engine fills for DMA carry the same edges at the same times
//! as the interrupt engine, for random chains of moves, pulse widths, holds and buffer
//! geometries; and the buffer geometry keeps the latency within 1 ms.

mod common;

use common::Rig;
use ddastep::motion::burst::{Layout, HALF_MAX};
use ddastep::motion::engine::IDLE_TICKS;
use ddastep::motion::moves::Move;
use ddastep::motion::shared::State;
use ddastep::grbl::settings::Settings;
use proptest::prelude::*;

/// One update event as the pins see it: time (ticks) and the BSRR word.
type Event = (u64, u32);

/// What the idle loop and the user do between real ticks (never inside a split period: the
/// two engines split long periods differently, so only their real ticks line up): the feeder
/// is serviced, and a feed hold goes on before real tick `on` and off `len` real ticks later.
struct Driver {
    hold: Option<(u64, u64)>,
    ticks: u64,
    held_ticks: u64,
    events: Vec<Event>,
    t: u64,
    preload: u16,
}

impl Driver {
    fn new(hold: Option<(u64, u64)>) -> Self {
        // The timer starts as the firmware starts it: the idle period preloaded.
        Driver { hold, ticks: 0, held_ticks: 0, events: Vec::new(), t: 0, preload: (IDLE_TICKS - 1) as u16 }
    }

    /// Before a real tick.
    fn between(&mut self, shared: &ddastep::motion::shared::Shared<3>, feeder: &mut ddastep::planning::feeder::Feeder<'static, 3>) {
        if let Some((on, len)) = self.hold {
            let held = self.ticks >= on && self.held_ticks < len;
            if held {
                self.held_ticks += 1;
            }
            shared.set_hold(held);
        }
        feeder.service();
        self.ticks += 1;
    }

    /// An update event storing `word`, then preloading `period`.
    fn event(&mut self, word: u32, period: u16) {
        self.events.push((self.t, word));
        self.t += u64::from(self.preload) + 1;
        self.preload = period;
    }

    fn done(&self, shared: &ddastep::motion::shared::Shared<3>, feeder: &ddastep::planning::feeder::Feeder<'static, 3>) -> bool {
        feeder.pending() == 0
            && shared.state() == State::Idle
            && self.hold.is_none_or(|(_, len)| self.held_ticks >= len)
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Identical edges: the burst's entries, played out as DMA does (entry k's word at update
    /// event k, its period preloaded there), give the interrupt engine's update events with a
    /// nonzero word at the same times, with the same words; the extra entries are fillers
    /// (word 0) that split periods longer than the entry limit. Counts are exact in both.
    #[test]
    fn burst_buffers_carry_the_interrupt_engines_edges(
            moves in prop::collection::vec(prop::array::uniform3(-1500i64..1500), 1..10),
            cruise in 1_000u32..200_000, pulse_us in 0.2f32..20.0, half in 2usize..=HALF_MAX,
            hold in prop::option::of((0u64..3_000, 1u64..40))) {
        let mut s = Settings::BENCH;
        s.accel = [200_000.0; ddastep::MAX_AXES];
        s.pulse_us = pulse_us;
        let timing = s.timing();
        let mut a = Rig::<3>::with_settings(&s);
        let mut b = Rig::<3>::with_settings(&s);
        let mut want = [0i64; 3];
        for m in &moves {
            if Move::new(*m, cruise).is_ok() {
                a.push(*m, cruise);
                b.push(*m, cruise);
                for i in 0..3 { want[i] += m[i]; }
            }
        }
        // The interrupt engine, tick by tick (one more update after it is idle: the last word).
        let mut da = Driver::new(hold);
        let mut finished = false;
        for _ in 0..50_000_000u64 {
            if !a.engine.filler_next() {
                da.between(a.shared, &mut a.feeder);
            }
            let w = a.engine.word();
            let p = a.engine.tick();
            da.event(w, p);
            if finished {
                break;
            }
            finished = da.done(a.shared, &a.feeder);
        }
        prop_assert!(finished, "interrupt engine finished");
        prop_assert_eq!(a.shared.positions().map(i64::from), want);

        // The burst engine, one half at a time as the DMA interrupt fills it.
        let layout = Layout::for_pulse(timing.pulse_ticks);
        let mut r = b.into_burst(layout.max_tick);
        let mut words = vec![0u32; 2 * half];
        let mut periods = vec![0u16; 2 * half];
        let mut db = Driver::new(hold);
        let (mut fillers, mut k, mut finished, mut after) = (0u64, 0, false, 0);
        // (Until one half after the engine is done: the last word comes at the next event.)
        while after < 2 && db.t <= da.t + 4 * 65_536 {
            after += u32::from(finished);
            let h = (k % 2) * half;
            for i in h..h + half {
                if !r.burst.filler_next() {
                    db.between(r.shared, &mut r.feeder);
                }
                r.burst.fill(&mut words[i..i + 1], &mut periods[i..i + 1]);
                prop_assert!(u32::from(periods[i]) < layout.max_tick, "entry within the limit");
                if words[i] == 0 { fillers += 1; }
                db.event(words[i], periods[i]);
                finished |= db.done(r.shared, &r.feeder);
            }
            k += 1;
        }
        prop_assert!(finished, "burst engine finished");
        let nonzero = |ev: &[Event]| ev.iter().copied().filter(|e| e.1 != 0).collect::<Vec<_>>();
        let (ea, eb) = (nonzero(&da.events), nonzero(&db.events));
        if ea != eb {
            let i = ea.iter().zip(&eb).position(|(x, y)| x != y).unwrap_or(ea.len().min(eb.len()));
            let lo = i.saturating_sub(3);
            eprintln!("first difference at {i} of {}/{}: interrupt {:?} burst {:?}", ea.len(), eb.len(),
                &ea[lo..(i + 3).min(ea.len())], &eb[lo..(i + 3).min(eb.len())]);
        }
        prop_assert_eq!(ea.len(), eb.len(), "as many edges ({} fillers)", fillers);
        for (x, y) in ea.iter().zip(&eb) {
            prop_assert_eq!(x, y);
        }
        prop_assert_eq!(r.shared.positions().map(i64::from), want);
        prop_assert_eq!(r.shared.moves_done(), a.shared.moves_done());
        prop_assert_eq!(r.burst.step_off(), r.pins.step_off);
    }

    /// The fill's fast path (runs of fillers and plain steps) gives the same entries as whole
    /// ticks for every entry, with the feeder serviced and
    /// a hold switched between halves in both; 1 to 7 axes, single- and dual-edge.
    #[test]
    fn the_fast_path_fills_like_whole_ticks(
            moves in prop::collection::vec(prop::array::uniform7(-1500i64..1500), 1..10),
            axes in 1usize..=7, cruise in 1_000u32..400_000, pulse_us in 0.2f32..5.0, half in 2usize..=HALF_MAX,
            dual: bool, hold in prop::option::of((0u64..300, 1u64..40))) {
        let mut s = Settings::BENCH;
        s.accel = [300_000.0; ddastep::MAX_AXES];
        s.pulse_us = pulse_us;
        s.dual_edge = dual;
        s.dma_burst = true;
        let timing = s.timing();
        let layout = Layout::for_pulse(if dual { 0 } else { timing.pulse_ticks });
        let mut rigs = [Rig::<7>::with_settings(&s), Rig::<7>::with_settings(&s)].map(|r| r.into_burst(layout.max_tick));
        let mut want = [0i64; 7];
        for m in &moves {
            let mut m = *m;
            m[axes..].fill(0);
            if Move::new(m, cruise).is_ok() {
                for r in &mut rigs { r.feeder.push(Move::new(m, cruise).unwrap()).unwrap(); }
                for i in 0..7 { want[i] += m[i]; }
            }
        }
        let mut out = [Vec::new(), Vec::new()];
        for (k, r) in rigs.iter_mut().enumerate() {
            let mut words = vec![0u32; half];
            let mut periods = vec![0u16; half];
            let mut done_at = None;
            for h in 0..200_000u64 {
                if let Some((on, len)) = hold {
                    r.shared.set_hold(h >= on && h < on + len);
                }
                r.feeder.service();
                r.burst.set_quick(k == 0);
                r.burst.fill(&mut words, &mut periods);
                out[k].extend(words.iter().copied().zip(periods.iter().copied()));
                let idle = r.feeder.pending() == 0 && r.shared.state() == State::Idle
                    && hold.is_none_or(|(on, len)| h >= on + len);
                if idle && done_at.is_none() {
                    done_at = Some(h);
                }
                if done_at.is_some_and(|d| h > d + 1) {
                    break;
                }
            }
            prop_assert!(done_at.is_some(), "rig {} finished", k);
            prop_assert_eq!(r.shared.positions().map(i64::from), want);
        }
        prop_assert_eq!(out[0].len(), out[1].len());
        if let Some(i) = out[0].iter().zip(&out[1]).position(|(a, b)| a != b) {
            prop_assert!(false, "entry {} differs: whole halves {:?}, single entries {:?}", i,
                &out[0][i..(i + 4).min(out[0].len())], &out[1][i..(i + 4).min(out[1].len())]);
        }
    }

    /// The geometry for every pulse width `$0` allows (0.2–100 µs, plus the margin the compare
    /// event adds): two halves hold at most 1 ms, each half at least 2 entries, and a split
    /// period's first piece (at least half the longest entry) always holds the falling edge.
    #[test]
    fn layout_keeps_latency_within_its_horizon(fall in 0u32..=7_300) {
        let l = Layout::for_pulse(fall);
        // 1.33 ms: two halves of 32 entries of at most 1500 ticks.
        prop_assert!(l.latency_ticks() <= ddastep::motion::burst::HORIZON_TICKS);
        prop_assert!(ddastep::motion::burst::HORIZON_TICKS <= ddastep::TICKS_PER_MS * 4 / 3);
        prop_assert!((2..=HALF_MAX).contains(&l.half));
        prop_assert!(l.max_tick / 2 > fall);
        prop_assert!(l.max_tick <= ddastep::motion::engine::MAX_TICK);
    }
}
