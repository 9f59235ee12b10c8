//! Settings: Grbl's `$N=` rules, the flash image, and the profile derived for the engine.

use ddastep::error::Error;
use ddastep::motion::ramp::RampSlot;
use ddastep::grbl::settings::{crc32, Change, Settings, RAMP_SHAPE, SETTINGS_LEN};

#[test]
fn defaults_survive_flash_and_bad_images_fall_back() {
    let mut s = Settings::DEFAULT;
    s.set(100, 80.5, 3).unwrap();
    s.set(RAMP_SHAPE, 1.0, 3).unwrap();
    s.set(4, 1.0, 3).unwrap();
    let b = s.to_bytes();
    assert_eq!(Settings::decode(&b), Some(s));
    let mut flipped = b;
    flipped[30] ^= 1;
    assert_eq!(Settings::decode(&flipped), None);
    assert_eq!(Settings::from_bytes(&flipped), Settings::DEFAULT);
    assert_eq!(Settings::from_bytes(&[0xFF; SETTINGS_LEN]), Settings::DEFAULT);
    assert_eq!(Settings::from_bytes(&b[..10]), Settings::DEFAULT);
    assert!(Settings::DEFAULT.is_valid());
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
}

#[test]
fn set_follows_grbl_rules() {
    let mut s = Settings::BENCH;
    assert_eq!(s.set(0, 0.15, 3), Err(Error::StepPulseMin));
    assert_eq!(s.set(100, -1.0, 3), Err(Error::NegativeValue));
    assert_eq!(s.set(103, 10.0, 3), Err(Error::InvalidStatement));
    assert_eq!(s.set(103, 10.0, 4), Ok(Change::Profile));
    assert_eq!(s.set(2, 5.7, 3), Ok(Change::Pins));
    assert_eq!(s.step_invert, 5);
    assert_eq!(s.set(2, 256.0, 3), Err(Error::InvalidStatement));
    assert_eq!(s.set(20, 1.0, 3), Err(Error::SoftLimitNeedsHoming));
    assert_eq!(s.set(20, 0.0, 3), Ok(Change::Shell)); // stored (issue 13)
    assert_eq!(s.set(21, 1.0, 3), Ok(Change::Shell)); // hard limits (issue 13)
    assert!(s.hard_limits);
    assert_eq!(s.set(7, 0.0, 3), Err(Error::InvalidStatement));
    assert_eq!(s.set(RAMP_SHAPE, 2.0, 3), Err(Error::InvalidStatement));
    // `$582` Flexible: 1..=12.
    assert_eq!(s.set(582, 0.0, 3), Err(Error::InvalidStatement));
    assert_eq!(s.set(582, 13.0, 3), Err(Error::InvalidStatement));
    assert_eq!(s.set(582, 12.0, 3), Ok(Change::Profile));
    assert_eq!(s.get(582, 3), Some((12.0, 0)));
    assert_eq!(s.set(110, f32::NAN, 3), Err(Error::BadNumberFormat));
}

#[test]
fn ids_cover_every_gettable_setting_once() {
    let s = Settings::DEFAULT;
    let ids: heapless::Vec<u16, 64> = Settings::ids(3).collect();
    // ours: $29, $33, $40, $41, $42 and $10's mask; the encoder's $87-$89, $97-$99; $580-$582
    assert_eq!(ids.len(), 7 + 14 + 6 + 6 + 3 + 12);
    assert!(ids.windows(2).all(|w| w[0] < w[1]), "{ids:?}");
    assert!(ids.iter().all(|&id| s.get(id, 3).is_some()));
    assert_eq!(s.get(133, 3), None);
    assert_eq!(Settings::ids(7).count(), 7 + 14 + 6 + 6 + 3 + 28);
}

#[test]
fn encoder_settings_follow_the_table() {
    let mut s = Settings::DEFAULT;
    assert_eq!(s.set(87, 4.0, 7), Err(Error::InvalidStatement)); // only 3 axes in use
    assert_eq!(s.set(87, 1.0, 7), Ok(Change::Shell));
    assert_eq!(s.set(88, 0.0, 3), Err(Error::InvalidStatement));
    assert_eq!(s.set(88, 64.5, 3), Err(Error::InvalidStatement));
    assert_eq!(s.set(88, -1.0, 3), Err(Error::NegativeValue));
    assert_eq!(s.set(88, 0.25, 3), Ok(Change::Shell));
    assert_eq!(s.set(89, 2.0, 3), Err(Error::InvalidStatement));
    assert_eq!(s.set(97, 12.9, 3), Ok(Change::Shell));
    assert_eq!(s.set(99, 1000.5, 3), Err(Error::InvalidStatement));
    assert_eq!(s.set(90, 1.0, 3), Err(Error::InvalidStatement)); // grblHAL's PID: not ours
    assert_eq!((s.get(88, 3), s.get(97, 3)), (Some((0.25, 3)), Some((12.0, 0))));
    assert_eq!(Settings::decode(&s.to_bytes()), Some(s));
}

#[test]
fn profile_is_in_path_units_at_twice_the_fastest_accel() {
    // The seed paper's bench (100 steps/mm), not Grbl's defaults.
    let mut s = Settings::BENCH;
    s.set(121, 500.0, 3).unwrap(); // Y: slow, but the table serves the fastest axis
    s.set(112, 60_000.0, 3).unwrap(); // Z: 1000 mm/s
    s.set(120, 1.0, 3).unwrap();
    s.set(120, 10_000.0, 3).unwrap();
    let t = s.timing();
    let floor = 2 * 216 + ddastep::motion::timing::STORE_LATENCY_TICKS;
    assert_eq!((t.pulse_ticks, t.dir_setup_ticks, t.min_period_ticks), (216, 360, floor));
    let cfg = s.ramp_config(3, &t);
    // Rate = path speed × 100 steps/mm; top √(600² + 600² + 1000²) mm/s; 2 × 10 000 mm/s².
    assert_eq!((cfg.v0, cfg.vmax, cfg.accel), (1000, 131_148, 2_000_000));
    assert_eq!(s.per_mm(3), 100.0);
    // Slow on every axis: 130 kHz at 100 000 /s² needs 1.3 s, more than the table holds.
    for id in [120, 121, 122] {
        s.set(id, 500.0, 3).unwrap();
    }
    let wanted = s.ramp_config(3, &t);
    assert_eq!((wanted.vmax, wanted.accel), (131_148, 100_000));
    static SLOT: RampSlot = RampSlot::new();
    let mut g = SLOT.try_write().unwrap();
    let r = s.build_profile(3, &mut g);
    assert_eq!(g.ramp.config(), r.cfg);
    // Whatever the table's length: the built ramp fits in it and reaches its top there, and
    // it either lowers the top to what fits (said by `table_limited`) or keeps the top and
    // steepens the table (each move walks it at its own, smaller fraction).
    let len = ddastep::motion::ramp::RAMP_LEN as u32;
    assert!(g.ramp.len() as u32 <= len, "{}", g.ramp.len());
    if r.cfg.vmax < wanted.vmax {
        assert!(r.table_limited);
        assert_eq!(g.ramp.len() as u32, len);
        assert_eq!(r.cfg.accel, wanted.accel);
        assert_eq!(r.cfg.vmax, 1000 + 100_000 * len / 1000 - 1);
    } else {
        assert_eq!(r.cfg.vmax, wanted.vmax);
        assert!(r.cfg.accel > wanted.accel && (r.cfg.vmax - r.cfg.v0) as u64 * 1000 <= r.cfg.accel as u64 * len as u64);
    }
    // Main's timing model: 3 µs pulses, twice that plus the store latency.
    assert_eq!(r.max_rate_hz, 72_000_000 / floor);
    // The bench's own settings fit: 52 ms to √3 × 600 mm/s, then the entry at the top itself.
    let r = Settings::BENCH.build_profile(3, &mut g);
    assert!(!r.table_limited);
    assert_eq!((r.cfg.vmax, g.ramp.len()), (103_923, 53));
    assert_eq!(g.ramp.periods()[52], ddastep::motion::ramp::period_of_hz(103_923));
}

#[test]
fn short_pulses_raise_the_rate_limit() {
    use ddastep::motion::timing::{
        HANDLER_BASE_TICKS as BASE, HANDLER_FALL_TICKS as FALL, HANDLER_GAP_TICKS as GAP, HANDLER_LONG_TICKS as LONG,
        HANDLER_PER_SLAVE_TICKS as SLAVE, HANDLER_TAIL_TICKS as TAIL, STORE_LATENCY_TICKS as LAT,
    };
    let mut s = Settings::BENCH;
    // Period floor: 2 × pulse + the store latency; the step handler's mean cost (CPU ≤ 95 %);
    // a pulse's low time after its end; and a long tick's compare check before the next
    // period's compare event (bench/RESULTS.md measures all three).
    s.set(0, 2.0, 3).unwrap();
    // Long pulses: the low time after a falling edge at the longest handler's end binds.
    assert!(FALL + 144 > (2 * 144 + LAT).max(BASE));
    assert_eq!(s.timing().max_rate_hz(), 72_000_000 / (FALL + 144));
    assert_eq!(s.timing().max_rate_for(2), 72_000_000 / (FALL + 2 * SLAVE + 144));
    assert_eq!(s.timing().max_rate_for(6), 72_000_000 / (BASE + 6 * SLAVE).max(FALL + 6 * SLAVE + 144).max(LONG + 6 * SLAVE - 144 - LAT - TAIL));
    // Twice the pulse binds only where the low time's rule is shorter (no such pulse now:
    // a pulse longer than the fall time binds through the low time first).
    s.set(0, 10.0, 3).unwrap();
    assert_eq!(s.timing().max_rate_hz(), 72_000_000 / (FALL + 720).max(2 * 720 + LAT));
    s.set(0, 1.0, 3).unwrap();
    // 1 µs: the low time binds still (a long tick is a move change, the ramp work runs
    // elsewhere: its compare check comes in time).
    assert!(FALL + 72 > (2 * 72 + LAT).max(BASE).max(LONG - 72 - LAT - TAIL));
    assert_eq!(s.timing().max_rate_hz(), 72_000_000 / (FALL + 72));
    assert_eq!(s.timing().max_rate_for(6), 72_000_000 / (BASE + 6 * SLAVE).max(FALL + 6 * SLAVE + 72));
    // 0.5 µs: within the gap back-to-back handlers keep between a falling and the next rising
    // store (no low-time room of its own): the handler's cost is the limit; shorter pulses gain
    // nothing more.
    s.set(0, 0.5, 3).unwrap();
    assert!(36 <= GAP && 72 > GAP && BASE < FALL + 36);
    assert_eq!(s.timing().max_rate_hz(), 72_000_000 / BASE);
    s.set(0, 0.2, 3).unwrap();
    assert_eq!(s.timing().max_rate_hz(), 72_000_000 / BASE);
    assert!(s.set(0, 0.1, 3).is_err());
}

#[test]
fn dual_edge_is_a_pin_setting_with_its_own_rate_rule() {
    use ddastep::grbl::settings::DUAL_EDGE;
    use ddastep::motion::timing::{DUAL_BASE_TICKS as BASE, DUAL_LONG_TICKS as LONG, HANDLER_PER_SLAVE_TICKS as SLAVE, STORE_JITTER_TICKS as JIT};
    let mut s = Settings::BENCH;
    assert_eq!(s.get(DUAL_EDGE, 3), Some((0.0, 0)));
    // Like `$2`: the engine's pin map changes, so the step output is rebuilt at rest.
    assert_eq!(s.set(DUAL_EDGE, 1.0, 3), Ok(Change::Pins));
    assert!(s.dual_edge && s.timing().dual);
    assert_eq!(s.get(DUAL_EDGE, 3), Some((1.0, 0)));
    assert_eq!(s.set(DUAL_EDGE, f32::NAN, 3), Err(Error::BadNumberFormat));
    assert_eq!(s.set(DUAL_EDGE, -1.0, 3), Err(Error::NegativeValue));
    // Stored as a flag bit next to `$4`-`$21`: an image from before `$580` (bit clear) loads as
    // single-edge, the image with it round-trips.
    let b = s.to_bytes();
    assert_eq!(Settings::decode(&b), Some(s));
    s.dual_edge = false;
    assert_eq!(Settings::decode(&s.to_bytes()).map(|d| d.dual_edge), Some(false));
    // One event per step: the handler's cost binds, not twice the pulse, up to the pulse where
    // two toggles a long tick brings closer bind (half of the long tick's term plus the pulse);
    // above the full-pulse cap where the pulse binds full pulses (from 2 µs; at 0.5 µs both are
    // the handler's cost).
    for (pulse, slaves) in [(0.2, 0u32), (0.5, 0), (0.5, 2), (2.0, 0), (2.0, 6), (3.0, 0), (3.0, 6)] {
        let mut d = Settings { dual_edge: true, ..Settings::BENCH };
        d.set(0, pulse, 3).unwrap();
        let t = d.timing();
        let want = (BASE + SLAVE * slaves).max((LONG + SLAVE * slaves + t.pulse_ticks).div_ceil(2)).max(t.pulse_ticks + JIT);
        assert_eq!(t.min_period_for(slaves), want, "{pulse} µs, {slaves} slaves");
        d.dual_edge = false;
        let full = d.timing();
        if pulse >= 2.0 {
            assert!(t.max_rate_for(slaves) > full.max_rate_for(slaves), "{pulse} µs, {slaves} slaves");
        }
    }
    // (Full pulses from 2 µs are bound by the pulse, dual-edge ones by the handler's cost.)
    let mut d = Settings::BENCH;
    d.set(0, 2.0, 3).unwrap();
    assert!(d.timing().max_rate_hz() < Settings { dual_edge: true, ..d }.timing().max_rate_hz());
    // A pulse longer than the handler's cost sets the period: toggles of a pin ≥ pulse apart.
    let mut d = Settings { dual_edge: true, ..Settings::BENCH };
    d.set(0, 10.0, 3).unwrap();
    assert_eq!(d.timing().min_period_for(0), 720 + JIT);
    assert!(720 + JIT > (LONG + 720).div_ceil(2));
}

#[test]
fn dma_burst_is_a_pin_flag_whose_cap_is_the_fill_cost() {
    use ddastep::grbl::settings::DMA_BURST;
    use ddastep::motion::timing::{DMA_BASE_TICKS, DMA_DUAL_BASE_TICKS, DMA_DUAL_PER_SLAVE_TICKS, DMA_FLOOR_TICKS, DMA_LANE_TICKS, DMA_MARGIN_TICKS, DMA_PER_SLAVE_TICKS};
    let mut s = Settings::BENCH;
    assert_eq!(s.get(DMA_BURST, 3), Some((0.0, 0)));
    // Like `$580`: the step output changes how it is built, so it is rebuilt at rest.
    assert_eq!(s.set(DMA_BURST, 1.0, 3), Ok(Change::Pins));
    assert!(s.dma_burst && s.timing().dma && !s.timing().dual);
    assert_eq!(s.set(DMA_BURST, f32::NAN, 3), Err(Error::BadNumberFormat));
    // Its own flag bit: the image round-trips, and one without it loads as interrupt mode.
    assert_eq!(Settings::decode(&s.to_bytes()), Some(s));
    let off = Settings { dma_burst: false, ..s };
    assert_eq!(Settings::decode(&off.to_bytes()).map(|d| d.dma_burst), Some(false));
    // The fill's cost binds at short pulses; from there the pulse and low time (plus the
    // stores' latency margin each) bind; dual-edge needs one margin-padded pulse per step.
    // DMA mode is faster than interrupt mode for every case here.
    for (pulse, slaves) in [(0.2, 0u32), (0.5, 0), (0.5, 6), (2.0, 0), (3.0, 2), (10.0, 6)] {
        for dual in [false, true] {
            let mut d = Settings { dma_burst: true, dual_edge: dual, ..Settings::BENCH };
            d.set(0, pulse, 3).unwrap();
            let t = d.timing();
            // One axis has the fill's lane of its own, in either edge mode.
            let cpu = match (dual, slaves) {
                (_, 0) => DMA_LANE_TICKS,
                (true, _) => DMA_DUAL_BASE_TICKS + DMA_DUAL_PER_SLAVE_TICKS * slaves,
                (false, _) => DMA_BASE_TICKS + DMA_PER_SLAVE_TICKS * slaves,
            };
            let pulses = if dual { t.pulse_ticks + DMA_MARGIN_TICKS } else { 2 * (t.pulse_ticks + DMA_MARGIN_TICKS) };
            assert_eq!(t.min_period_for(slaves), cpu.max(pulses).max(DMA_FLOOR_TICKS), "{pulse} µs, {slaves} slaves, dual {dual}");
            let irq = Settings { dma_burst: false, ..d }.timing();
            assert!(t.max_rate_for(slaves) > irq.max_rate_for(slaves), "{pulse} µs, {slaves} slaves, dual {dual}");
        }
    }
    // `$I` names the mode with its cap.
    let r = ddastep::grbl::settings::Ramped::wanted(&s, 3);
    assert!(r.dma && r.max_rate_hz == s.timing().max_rate_hz());
}

#[test]
fn an_image_from_before_582_loads_with_the_default_flexible() {
    // `$582` sits in byte 153 (after `$32`'s), which images from before it left clear.
    let s = Settings { flexible: 9, ..Settings::DEFAULT };
    let mut b = s.to_bytes();
    assert_eq!(b[153], 9);
    b[153] = 0;
    let crc = crc32(&b[..SETTINGS_LEN - 4]);
    b[SETTINGS_LEN - 4..].copy_from_slice(&crc.to_le_bytes());
    assert_eq!(Settings::decode(&b), Some(Settings { flexible: 4, ..s }));
}
