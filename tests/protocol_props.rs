//! Properties of the Grbl front end: garbage never panics and never touches moves already
//! queued; numbers read as `str::parse` reads them; settings survive their flash image.

mod protocol_rig;

use ddastep::grbl::gcode::parse_number;
use ddastep::error::Error;
use ddastep::motion::ramp::Shape;
use ddastep::grbl::settings::{Settings, SETTINGS_LEN};
use proptest::prelude::*;
use protocol_rig::Bench;

/// Bytes that break parsers: junk tokens, odd numbers, comments, line ends, raw bytes.
fn garbage() -> impl Strategy<Value = Vec<u8>> {
    let token = prop_oneof![
        any::<u8>().prop_map(|b| vec![b]),
        Just(b"\n".to_vec()),
        Just(b"\r\n".to_vec()),
        Just(vec![0u8]),
        Just(vec![0xFFu8]),
        Just(b"NaN".to_vec()),
        Just(b"1e999".to_vec()),
        Just(b"--5".to_vec()),
        Just(b"X".to_vec()),
        Just(b"G1".to_vec()),
        Just(b"G0X".to_vec()),
        Just(b"F".to_vec()),
        Just(b"$".to_vec()),
        Just(b"=".to_vec()),
        Just(b"(".to_vec()),
        Just(b")".to_vec()),
        Just(b";".to_vec()),
        Just(b".".to_vec()),
        Just(b"G92X".to_vec()),
        Just(b"G4P".to_vec()),
        Just(b"$100=".to_vec()),
        Just(b"$RST=$".to_vec()),
        Just(b"M18".to_vec()),
        (1usize..60).prop_map(|n| vec![b'9'; n]),
        (1usize..200).prop_map(|n| vec![b'A'; n]),
        "[-+]?[0-9]{0,20}(\\.[0-9]{0,25})?".prop_map(String::into_bytes),
    ];
    prop::collection::vec(token, 0..60).prop_map(|v| v.concat())
}

/// A valid relative move, in steps at 1 step/mm, and its line.
fn valid_move() -> impl Strategy<Value = ([i64; 3], String)> {
    prop::array::uniform3(-400i64..400).prop_filter("moves", |d| d.iter().any(|&x| x != 0)).prop_map(|d| {
        (d, format!("G91 G1 X{} Y{} Z{} F30000\n", d[0], d[1], d[2]))
    })
}

/// 1 step/mm, 60 kHz, 10⁶ steps/s², drivers always on: junk moves stay short to simulate.
fn fast_settings() -> Settings {
    Settings {
        idle_delay_ms: 255,
        steps_per_mm: [1.0; 7],
        max_rate: [3_600_000.0; 7],
        accel: [1_000_000.0; 7],
        ..Settings::BENCH
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn garbage_never_panics_nor_touches_queued_moves(
        moves in prop::collection::vec(valid_move(), 1..6),
        junk in garbage(),
    ) {
        let mut b = Bench::<3>::new(fast_settings());
        b.run_ms(3); // drivers enabled and settled; from here the engine only runs when ticked
        let mut want = [0i64; 3];
        for (d, line) in &moves {
            for &c in line.as_bytes() {
                prop_assert!(b.ctl.byte(c, &mut b.tx));
            }
            for i in 0..3 {
                want[i] += d[i];
            }
        }
        prop_assert_eq!(b.take().matches("ok\r\n").count(), moves.len());
        // Junk straight into the controller (also the bytes the shell would filter out),
        // until a line is held.
        for &c in &junk {
            if !b.ctl.byte(c, &mut b.tx) {
                break;
            }
            b.drain();
        }
        // The queued moves run exactly as accepted (the feeder hands them over at each poll,
        // as the firmware's idle loop does every millisecond).
        let k = moves.len() as u32;
        let mut updates = 0u64;
        while b.shared.moves_done() < k {
            b.timer.update(&mut b.engine);
            updates += 1;
            if b.shared.moves_done() < k && b.timer.now() / 72_000 > b.now_ms as u64 {
                b.now_ms += 1;
                b.ctl.poll(b.now_ms, &mut b.tx);
                b.drain();
            }
            prop_assert!(updates < 10_000_000);
        }
        prop_assert_eq!(b.shared.positions().map(i64::from), want);
        // Whatever the junk queued runs too, and the controller agrees with the engine.
        if b.ctl.busy() {
            b.byte(0x18);
        }
        b.run_to_idle(600_000);
        prop_assert_eq!(b.shared.positions().map(i64::from), b.ctl.planned_steps());
    }

    #[test]
    fn numbers_read_exactly_like_std(int in 0u64..1_000_000_000, frac in 0u32..1_000_000, digits in 0usize..7, neg: bool) {
        let f = format!("{:06}", frac);
        let s = format!("{}{}.{}", if neg { "-" } else { "" }, int, &f[..digits]);
        let mut i = 0;
        prop_assert_eq!(parse_number(s.as_bytes(), &mut i), Ok(s.parse::<f32>().unwrap()));
        prop_assert_eq!(i, s.len());
    }

    #[test]
    fn numbers_never_panic(s in "[-+.0-9]{0,40}") {
        let mut i = 0;
        match parse_number(s.as_bytes(), &mut i) {
            Ok(v) => {
                prop_assert!(v.is_finite() && v.abs() < 1e15);
                prop_assert_eq!(v, s[..i].parse::<f32>().unwrap());
            }
            Err(e) => prop_assert_eq!(e, Error::BadNumberFormat),
        }
    }

    #[test]
    fn settings_round_trip_through_flash(
        pulse in 1.0f32..100.0,
        dir in 0.0f32..1000.0,
        idle: u8, step_inv: u8, dir_inv: u8, flags in 0u8..=255, scurve: bool, flexible in 1u8..=12,
        start in 1u32..=1_000_000,
        arc_tol in 1e-4f32..1000.0,
        spindle in (0.0f32..1e6, 0.0f32..1e6, any::<bool>(), 1u32..=100_000),
        axes in prop::array::uniform4(prop::array::uniform7(0.001f32..1e5)),
        flip in 0usize..SETTINGS_LEN, bit in 0u8..8,
        mask in 0u8..4, count in 3u8..=7,
        home in (any::<u8>(), 0.001f32..1e5, 0.001f32..1e5, 0u32..=65_535, 0.0f32..1e6),
        enc in (0u8..=7, 0.001f32..64.0, any::<bool>(), 0u32..=1_000_000, any::<bool>(), 0.0f32..1000.0),
    ) {
        let mut encoder = ddastep::encoder::EncoderSettings::DEFAULT;
        let values = [enc.0 % (count + 1)].map(f32::from).into_iter()
            .chain([enc.1, enc.2 as u8 as f32, enc.3 as f32, enc.4 as u8 as f32, enc.5]);
        for (id, v) in ddastep::encoder::IDS.into_iter().zip(values) {
            encoder.set(id, v, count as usize).unwrap();
        }
        let s = Settings {
            pulse_us: pulse,
            idle_delay_ms: idle,
            step_invert: step_inv,
            dir_invert: dir_inv,
            enable_invert: flags & 1 != 0,
            limit_invert: flags & 2 != 0,
            probe_invert: flags & 4 != 0,
            // `$20` only with `$22` (else the image is not a valid one).
            soft_limits: flags & 24 == 24,
            homing: flags & 16 != 0,
            hard_limits: flags & 32 != 0,
            dual_edge: flags & 64 != 0,
            dma_burst: flags & 128 != 0,
            homing_dir: home.0,
            homing_feed: home.1,
            homing_seek: home.2,
            homing_debounce_ms: home.3,
            homing_pulloff: home.4,
            arc_tolerance: arc_tol,
            spindle_max: spindle.0,
            spindle_min: spindle.1,
            laser_mode: spindle.2,
            spindle_pwm_hz: spindle.3,
            dir_setup_us: dir,
            ramp_start_hz: start,
            shape: if scurve { Shape::SCurve } else { Shape::Trapezoid },
            steps_per_mm: axes[0],
            max_rate: axes[1],
            accel: axes[2],
            max_travel: axes[3].map(|v| v * 10.0),
            status_mask: mask,
            axes: count,
            encoder,
            flexible,
        };
        prop_assert!(s.is_valid());
        let mut image = s.to_bytes();
        prop_assert_eq!(Settings::decode(&image), Some(s));
        image[flip] ^= 1 << bit;
        prop_assert_eq!(Settings::decode(&image), None);
        prop_assert_eq!(Settings::from_bytes(&image), Settings::DEFAULT);
    }

    #[test]
    fn any_flash_bytes_decode_without_panic(image in prop::collection::vec(any::<u8>(), 0..200)) {
        if let Some(s) = Settings::decode(&image) {
            prop_assert!(s.is_valid());
        }
    }
}
