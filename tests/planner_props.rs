//! Random valid G-code programs end exactly at round(target × steps/mm) on every axis, however
//! the targets were reached (G90/G91, G20/G21, G0/G1, many small moves): from the decimal as
//! written where the library has it exactly, halves away from zero (Grbl's `lround`).

#[path = "protocol_rig/mod.rs"]
mod protocol_rig;

use ddastep::grbl::settings::Settings;
use proptest::prelude::*;
use protocol_rig::Bench;

#[derive(Clone, Debug)]
struct Block {
    relative: bool,
    inches: bool,
    rapid: bool,
    /// Thousandths of the unit per axis (None: axis word absent).
    words: [Option<i32>; 3],
    feed: u32,
}

fn block() -> impl Strategy<Value = Block> {
    (any::<bool>(), prop::bool::weighted(0.2), any::<bool>(), prop::array::uniform3(prop::option::of(-20_000i32..20_000)), 300u32..30_000)
        .prop_map(|(relative, inches, rapid, words, feed)| Block { relative, inches, rapid, words, feed })
}

/// `1.234` / `-0.005` from thousandths.
fn num(t: i32) -> String {
    format!("{}{}.{:03}", if t < 0 { "-" } else { "" }, t.unsigned_abs() / 1000, t.unsigned_abs() % 1000)
}

/// `(t / 1000 unit + start mm) × spm`, rounded half away from zero, exactly (unit: 1 mm, or
/// 25.4 = 254/10 mm; `spm` = m · 2^e as its f32 is).
fn exact_steps(t: i32, inches: bool, start: i64, spm: f32) -> i64 {
    // mm = num / 10^f.
    let (num, f) = if inches { (t as i128 * 254 + start as i128 * 10_000, 4) } else { (t as i128 + start as i128 * 1000, 3) };
    let (m, e) = ((spm.to_bits() & 0x7f_ffff | 1 << 23) as i128, (spm.to_bits() >> 23) as i32 - 150);
    let (p, d) = (num * m, 10i128.pow(f) << -e);
    let n = (p.abs() + d / 2) / d;
    (if p < 0 { -n } else { n }) as i64
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn programs_end_at_rounded_targets(
        spm in prop::array::uniform3(prop_oneof![Just(100.0f32), Just(80.123f32), Just(3.3f32), Just(250.0f32)]),
        blocks in prop::collection::vec(block(), 1..12),
        nudges in 0usize..40,
    ) {
        let mut b = Bench::<3>::new(Settings::BENCH);
        for (i, s) in spm.iter().enumerate() {
            b.line(&format!("$10{i}={s}"));
        }
        b.run_ms(2);
        // The targets as the library plans them: the position in f32 (the nearest f32 to each
        // word, times the unit, added to the position under G91, as Grbl), and the step target
        // exactly from the decimal (`exact_steps`) where the library has it exactly: G90 (no
        // offsets here), and G91 from a whole-millimetre position; from the f32 target
        // elsewhere (Grbl's f32 rounding, and the step position kept when it does not change).
        let mut mm = [0.0f32; 3];
        let mut steps = [0i64; 3];
        let mut apply = |i: usize, t: i32, inches: bool, relative: bool, mm: &mut [f32; 3]| {
            let unit: f32 = if inches { 25.4 } else { 1.0 };
            let v: f32 = num(t).parse().unwrap();
            let target = if relative { mm[i] + v * unit } else { v * unit };
            let whole = mm[i] == mm[i].trunc() && mm[i].abs() < 16_777_216.0;
            steps[i] = if !relative || whole {
                let start = if relative { mm[i] as i64 } else { 0 };
                exact_steps(t, inches, start, spm[i])
            } else if target == mm[i] {
                steps[i]
            } else {
                (target * spm[i]).round() as i64
            };
            mm[i] = target;
        };
        for blk in &blocks {
            let mut line = format!(
                "{} {} {}",
                if blk.inches { "G20" } else { "G21" },
                if blk.relative { "G91" } else { "G90" },
                if blk.rapid { "G0" } else { "G1" },
            );
            for (i, w) in blk.words.iter().enumerate() {
                if let Some(t) = w {
                    line += &format!(" {}{}", ['X', 'Y', 'Z'][i], num(*t));
                    apply(i, *t, blk.inches, blk.relative, &mut mm);
                }
            }
            line += &format!(" F{}", blk.feed);
            let reply = b.line(&line);
            prop_assert_eq!(reply, "ok\r\n", "{}", line);
        }
        // Many tiny relative moves: sub-step pieces must add up, not round away.
        for _ in 0..nudges {
            b.line("G21 G91 G1 X0.003 Y-0.007 F3000");
            apply(0, 3, false, true, &mut mm);
            apply(1, -7, false, true, &mut mm);
        }
        b.run_to_idle(600_000);
        let want = steps;
        prop_assert_eq!(b.shared.positions().map(i64::from), want);
    }
}
