//! Step targets at half-step ties, as Grbl 1.1h rounds them: from the decimal as written times
//! steps/mm, halves away from zero (`lround`). `Y4.595` at 100 steps/mm is 459.5 steps: 460
//! (the nearest `f32` to 4.595, 4.594999790…, gave 459). Also G53, G20 inches, whole-millimetre
//! offsets and G91 from a whole-millimetre position, against exact rational arithmetic.

mod protocol_rig;

use ddastep::grbl::settings::Settings;
use proptest::prelude::*;
use protocol_rig::Bench;

/// A rig with the position report in machine coordinates.
fn bench() -> Bench<3> {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    assert_eq!(b.line("$10=1"), "ok\r\n");
    b
}

/// Runs one line to its end; the engine's and the carriage's step counts.
fn run(b: &mut Bench<3>, line: &str) -> ([i32; 3], [i64; 3]) {
    assert_eq!(b.line(line), "ok\r\n", "{line}");
    b.run_to_idle(60_000);
    b.run_ms(2);
    (b.shared.positions(), b.carriage)
}

#[test]
fn y4_595_moves_460_steps_as_grbl() {
    let mut b = bench();
    let (pos, carriage) = run(&mut b, "G90 G1 Y4.595 F1000");
    assert_eq!(pos[1], 460);
    assert_eq!(carriage[1], 460);
    let s = b.status();
    assert!(s.contains("MPos:0.000,4.600,0.000"), "{s}");
    // The same target again moves nothing; a line that names no Y keeps it.
    assert_eq!(run(&mut b, "G1 Y4.595").0[1], 460);
    assert_eq!(run(&mut b, "G1 X1").0, [100, 460, 0]);
}

#[test]
fn x95_815_moves_9582_steps_as_grbl() {
    let mut b = bench();
    // (The nearest f32 times 100 in f32 is exactly 9581.5 here, so f32 rounding got this one
    // right by chance; X2058.005 is 205800.49… steps in f32.)
    for (line, want) in [("G90 G0 X95.815", 9582), ("G0 X2058.005", 205_801), ("G0 X-95.815", -9582), ("G0 X-2058.005", -205_801)] {
        let (pos, carriage) = run(&mut b, line);
        assert_eq!((pos[0], carriage[0]), (want, want as i64), "{line}");
    }
}

#[test]
fn offsets_inches_and_jogs_at_ties() {
    let mut b = bench();
    // A whole-millimetre work offset: the word plus the offset, exactly.
    b.line("G10 L2 P1 X10 Y-3");
    assert_eq!(run(&mut b, "G90 G0 X4.595 Y4.595").0[..2], [1460, 160]);
    // G53: machine coordinates, the word itself.
    assert_eq!(run(&mut b, "G53 G0 X4.595").0[0], 460);
    // G91 from a whole-millimetre position.
    b.line("G10 L2 P1 X0 Y0");
    run(&mut b, "G90 G0 X1 Y0");
    assert_eq!(run(&mut b, "G91 G0 X4.595").0[0], 560);
    // Inches: 0.025 in = 0.635 mm = 63.5 steps.
    assert_eq!(run(&mut b, "G20 G90 G0 X0.025").0[0], 64);
    assert_eq!(run(&mut b, "G20 G90 G0 X-0.025").0[0], -64);
    // A jog to a tie.
    b.line("G21");
    assert_eq!(run(&mut b, "$J=G90 Z4.595 F600").0[2], 460);
}

/// How the target is written.
#[derive(Clone, Copy, Debug)]
enum Mode {
    /// `G90 G21` with no offsets.
    Absolute,
    /// `G53`.
    Machine,
    /// `G90 G20`: the word in inches.
    Inches,
    /// `G90 G21` with a whole-millimetre G54 offset on the axis (`G10 L2 P1`).
    Offset(i32),
    /// `G91 G21` from a whole-millimetre position.
    Relative(i32),
}

/// `round(num / den)`, halves away from zero.
fn round_half_away(num: i128, den: i128) -> i128 {
    let (q, r) = (num.abs() / den, num.abs() % den);
    let n = q + (2 * r >= den) as i128;
    if num < 0 {
        -n
    } else {
        n
    }
}

/// The decimal `sig / 10^frac` as text.
fn text(sig: i64, frac: u32) -> String {
    let m = sig.unsigned_abs();
    let p = 10u64.pow(frac);
    let sign = if sig < 0 { "-" } else { "" };
    if frac == 0 {
        format!("{sign}{m}")
    } else {
        format!("{sign}{}.{:0w$}", m / p, m % p, w = frac as usize)
    }
}

/// Steps/mm as a decimal string, with the decimals that tie at half a step (sig, frac).
const TIE_SPM: [(&str, i64, u32); 7] =
    [("100", 5, 3), ("80", 625, 5), ("250", 2, 3), ("200", 25, 4), ("400", 125, 5), ("12.5", 4, 2), ("5", 1, 1)];

fn spm_and_value() -> impl Strategy<Value = (String, i64, u32)> {
    prop_oneof![
        // Ties: (2k + 1) half steps.
        (0..TIE_SPM.len(), -2_000_000i64..2_000_000).prop_map(|(i, k)| {
            let (spm, sig, frac) = TIE_SPM[i];
            (spm.to_string(), (2 * k + 1) * sig, frac)
        }),
        // Any steps/mm in $100's range and any decimal with up to 6 fraction digits that keeps
        // the target within about ±2^31 steps (a few beyond it).
        (-3.0f64..5.0, 0u32..=6, -1.0f64..1.0).prop_map(|(lg, frac, u)| {
            let spm = format!("{}", 10f64.powf(lg) as f32);
            let limit = (2_147_483_647.0 * 1.05 / spm.parse::<f64>().unwrap()).min(990_000.0);
            let sig = (u * limit * 10f64.powi(frac as i32)).round() as i64;
            (spm, sig, frac)
        }),
    ]
}

fn mode() -> impl Strategy<Value = Mode> {
    prop_oneof![
        2 => Just(Mode::Absolute),
        1 => Just(Mode::Machine),
        1 => Just(Mode::Inches),
        1 => (-500i32..500).prop_map(Mode::Offset),
        1 => (-500i32..500).prop_map(Mode::Relative),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// Random decimals (up to 6 fraction digits) and steps/mm: the planned step target is the
    /// exact product rounded half away from zero, or `error:33` beyond ±(2^31 − 1) steps.
    #[test]
    fn step_targets_are_the_exact_decimal_rounded_as_grbl(
        (spm, sig, frac) in spm_and_value(),
        mode in mode(),
        axis in 0usize..3,
    ) {
        let name = ['X', 'Y', 'Z'][axis];
        let mut b = Bench::<3>::new(Settings::BENCH);
        b.take();
        prop_assert_eq!(b.line(&format!("$10{axis}={spm}")), "ok\r\n");
        // Check mode: the planner follows the lines, nothing moves.
        b.line("$C");
        b.take();
        // The exact target in mm as num / 10^f.
        let (mut num, mut f) = (sig as i128, frac);
        let line = match mode {
            Mode::Absolute => format!("G90 G21 G0 {name}{}", text(sig, frac)),
            Mode::Machine => format!("G53 G21 G0 {name}{}", text(sig, frac)),
            Mode::Inches => {
                // The word in inches (within ±1e6 mm), 25.4 = 254/10 mm each; exact while the
                // word × 254 stays within 12 significant digits (below 2^40): 9 digits.
                let w = sig / 26 % 4_000_000_000;
                num = w as i128 * 254;
                f += 1;
                format!("G90 G20 G0 {name}{}", text(w, frac))
            }
            Mode::Offset(o) => {
                prop_assert_eq!(b.line(&format!("G10 L2 P1 {name}{o}")), "ok\r\n");
                num += o as i128 * 10i128.pow(f);
                format!("G90 G21 G0 {name}{}", text(sig, frac))
            }
            Mode::Relative(o) => {
                prop_assert_eq!(b.line(&format!("G90 G21 G0 {name}{o}")), "ok\r\n");
                num += o as i128 * 10i128.pow(f);
                format!("G91 G21 G0 {name}{}", text(sig, frac))
            }
        };
        let before = b.ctl.planned_steps()[axis];
        let reply = b.line(&line);
        // steps/mm exactly: m · 2^e.
        let s: f32 = spm.parse().unwrap();
        let (m, e) = ((s.to_bits() & 0x7f_ffff | 1 << 23) as i128, (s.to_bits() >> 23) as i32 - 150);
        prop_assert!(e < 0);
        let want = round_half_away(num * m, 10i128.pow(f) << -e);
        if want.abs() < 1 << 31 {
            prop_assert_eq!(reply, "ok\r\n", "{}", line);
            prop_assert_eq!(b.ctl.planned_steps()[axis] as i128, want, "{} at {} steps/mm", line, spm);
        } else {
            prop_assert_eq!(reply, "error:33\r\n", "{}", line);
            prop_assert_eq!(b.ctl.planned_steps()[axis], before);
        }
    }
}
