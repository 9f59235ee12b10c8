//! Random valid G-code programs end exactly at round(target × steps/mm) on every axis, however
//! the targets were reached (G90/G91, G20/G21, G0/G1, many small moves).

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
        // The targets in f32, as the library (and Grbl) reads and adds them: the nearest f32 to
        // each word, times the unit, added to the position. (In f64 when the library was: at
        // exact decimal ties, k + ½ steps, the two round either way in about 1 % of cases, and
        // f64 itself differs from the exact decimal in as many.)
        let mut mm = [0.0f32; 3];
        for blk in &blocks {
            let mut line = format!(
                "{} {} {}",
                if blk.inches { "G20" } else { "G21" },
                if blk.relative { "G91" } else { "G90" },
                if blk.rapid { "G0" } else { "G1" },
            );
            let unit: f32 = if blk.inches { 25.4 } else { 1.0 };
            for (i, w) in blk.words.iter().enumerate() {
                if let Some(t) = w {
                    let text = num(*t);
                    line += &format!(" {}{}", ['X', 'Y', 'Z'][i], text);
                    let v: f32 = text.parse().unwrap();
                    mm[i] = if blk.relative { mm[i] + v * unit } else { v * unit };
                }
            }
            line += &format!(" F{}", blk.feed);
            let reply = b.line(&line);
            prop_assert_eq!(reply, "ok\r\n", "{}", line);
        }
        // Many tiny relative moves: sub-step pieces must add up, not round away.
        for _ in 0..nudges {
            b.line("G21 G91 G1 X0.003 Y-0.007 F3000");
            mm[0] += 0.003;
            mm[1] += -0.007;
        }
        b.run_to_idle(600_000);
        let want: [i64; 3] = std::array::from_fn(|i| (mm[i] * spm[i]).round() as i64);
        prop_assert_eq!(b.shared.positions().map(i64::from), want);
    }
}
