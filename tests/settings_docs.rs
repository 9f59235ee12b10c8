//! `docs/settings.md` and `docs/settings.csv` are what the code gives: the setting numbers and
//! defaults as `$$` prints them (on the host rig, with 3 and with 7 axes), the texts of
//! `ddastep::grbl::settings::docs`, and ranges that `$N=` really accepts. The files are
//! generated here: `UPDATE_DOCS=1 cargo test -p ddastep --target host-tuple --test settings_docs`
//! rewrites them; without it the test fails when they differ.

mod protocol_rig;

use std::collections::BTreeMap;
use std::path::PathBuf;

use ddastep::grbl::settings::docs::{docs, grouped, Doc};
use ddastep::grbl::settings::{Settings, AXIS_COUNT};
use protocol_rig::Bench;

/// The page's opening: how to set a setting, starting points for three machines, where the
/// settings live.
const INTRO: &str = r#"# Settings

Grbl's numbers: `$$` lists them, `$N=value` sets one while idle. The defaults are Grbl's own,
safe for a small gantry. This page and [settings.csv](settings.csv) (the columns of Grbl's
`doc/csv/setting_codes_en_US.csv`, for senders) are generated from the code by
`tests/settings_docs.rs`, which fails when they differ from what `$$` prints; regenerate with
`UPDATE_DOCS=1 cargo test -p ddastep --target host-tuple --test settings_docs`.

`$$` lists the axis settings (`$100`-`$136`) for the `$42` axes in use, and `$580`-`$582` last.
`$29`, `$33`, `$40`-`$42`, `$87`-`$89`, `$97`-`$99` and `$580`-`$582` are not Grbl 1.1's:
`$29` and `$33` are grblHAL's numbers for the same thing; `$87`-`$89`, `$97`-`$99` and
`$580`-`$582` are numbers neither Grbl 1.1 nor grblHAL gives a meaning (grblHAL's 80-86 and
90-96 are its spindle and position PID, 400-449 its MPG encoders, 540-579 its panel and 590-599
its button settings, 580-589 unused; it has no dual-edge, DMA or S-curve setting).

## Starting points

Steps/mm = motor steps × microsteps / mm per turn; check your drivers' microstep switches.
Driver timing (`$0`, `$29`, `$2`, `$4`) per driver: [wiring.md](wiring.md#drivers).

| machine | steps/mm `$100–102` | max rate `$110–112` mm/min | accel `$120–122` mm/s² | travel `$130–132` mm | notes |
|---|---|---|---|---|---|
| 3018 router (T8 lead screw 8 mm/turn, 1/32 step) | 800, 800, 800 | 1000, 1000, 600 | 30, 30, 30 | 300, 180, 45 | TB6600-style drivers: `$0=3` (default) |
| belt-driven laser (GT2 belt, 20-tooth pulley = 40 mm/turn, 1/16 step) | 80, 80, 250 | 6000, 6000, 500 | 1000, 1000, 10 | 400, 400, 10 | A4988/DRV8825: `$0=2`; no Z motor needed |
| lead-screw plotter (8 mm/turn, 1/16 step) | 400, 400, 400 | 3000, 3000, 1000 | 200, 200, 100 | 300, 200, 20 | pen lift on Z |

## Where they live

Settings, the coordinate systems (G54–G59, G28, G30), the two `$N` startup lines and the `$I=`
string form one image with a sequence number and a CRC-32, kept A/B in the last two 1 KiB flash
pages (62 K and 63 K; memory.x ends the program at 62 KiB). A save (only with the machine at
rest: the flash write stalls the CPU) erases the page *not* holding the newest valid image,
writes there and reads it back; a power cut at any moment leaves the previous image intact, and
changing a setting never loses the coordinates (nor the reverse).
`tests/protocol_coords_props.rs` cuts a save at every byte. Settings images of earlier firmware
(single page, format 1; formats 3 and 4, before the encoder and homing settings) are not read:
the first boot of this version starts from the defaults.

How the settings limit a move's speed and acceleration, and the step-rate caps that `$0`,
`$580` and `$581` set: [internals.md](internals.md#how-a-moves-speed-is-limited).

## The settings
"#;

// the repository root
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

// `$N=value` lines of a `$$` reply
fn dollars(reply: &str) -> Vec<(u16, String)> {
    reply
        .lines()
        .filter_map(|l| l.strip_prefix('$')?.split_once('='))
        .map(|(n, v)| (n.parse().unwrap(), v.trim().to_string()))
        .collect()
}

/// Every setting's default as `$$` prints it: the 3-axis defaults, and the 4th to 7th axes'
/// from `$$` after `$42=7`.
fn defaults() -> BTreeMap<u16, String> {
    let mut b = Bench::<7>::new(Settings::DEFAULT);
    let mut out: BTreeMap<u16, String> = dollars(&b.line("$$")).into_iter().collect();
    assert!(b.line(&format!("${AXIS_COUNT}=7")).contains("ok"));
    for (id, v) in dollars(&b.line("$$")) {
        out.entry(id).or_insert(v);
    }
    out
}

// 100000 -> "100 000"; 0.2 -> "0.2"
fn number(v: f32) -> String {
    if v == v.trunc() && v.abs() < 1e9 {
        grouped(&(v as i64).to_string())
    } else {
        let s = format!("{v:.7}");
        s.trim_end_matches('0').to_string()
    }
}

// the accepted range, as the page writes it
fn range(d: &Doc) -> String {
    match d.range {
        (lo, hi) if lo == hi => format!("fixed at {}", number(lo)),
        _ if d.unit == "boolean" => "0 or 1".into(),
        (lo, hi) => format!("{} – {}", number(lo), number(hi)),
    }
}

// Markdown to the CSV's plain text: links keep their words, code spans lose their backticks
fn plain(md: &str) -> String {
    let mut out = String::new();
    let mut rest = md;
    while let Some(i) = rest.find('[') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        match (after.find("]("), after.find(')')) {
            (Some(j), Some(k)) if j < k => {
                out.push_str(&after[..j]);
                rest = &after[k + 1..];
            }
            _ => {
                out.push('[');
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out.replace('`', "")
}

// the two files, from the code
fn generate() -> (String, String) {
    let defaults = defaults();
    let docs: Vec<Doc> = docs().collect();
    let documented: Vec<u16> = docs.iter().map(|d| d.id).collect();
    let listed: Vec<u16> = defaults.keys().copied().collect();
    assert_eq!(documented, listed, "docs entries vs the settings `$$` lists (3 and 7 axes)");
    let mut md = String::from(INTRO);
    let mut csv = String::from("\"$-Code\",\" Setting\",\" Units\",\" Setting Description\"\n");
    for d in &docs {
        let default = &defaults[&d.id];
        md.push_str(&format!(
            "\n### ${} – {}\n\n{}\n\n- unit: {}; default: `{}`; range: {}\n- Grbl: {}\n",
            d.id,
            d.name,
            d.text,
            d.unit,
            default,
            range(d),
            d.grbl
        ));
        let q = |s: &str| format!("\"{}\"", s.replace('"', "\"\""));
        csv.push_str(&format!("{},{},{},{}\n", q(&d.id.to_string()), q(&d.name), q(d.unit), q(&plain(d.text))));
    }
    (md, csv)
}

#[test]
fn settings_md_and_csv_match_the_code() {
    let (md, csv) = generate();
    let docs = root().join("docs");
    if std::env::var_os("UPDATE_DOCS").is_some() {
        std::fs::write(docs.join("settings.md"), &md).unwrap();
        std::fs::write(docs.join("settings.csv"), &csv).unwrap();
    }
    for (name, want) in [("settings.md", &md), ("settings.csv", &csv)] {
        let have = std::fs::read_to_string(docs.join(name)).unwrap_or_default();
        assert!(have == *want, "docs/{name} differs from the code: regenerate with UPDATE_DOCS=1 (tests/settings_docs.rs)");
    }
}

#[test]
fn every_documented_range_is_what_set_accepts() {
    for d in docs() {
        // 7 axes, homing on (soft limits need it)
        let mut s = Settings::DEFAULT;
        s.set(AXIS_COUNT, 7.0, 7).unwrap();
        s.set(22, 1.0, 7).unwrap();
        let (lo, hi) = d.range;
        let set = |v: f32| s.clone().set(d.id, v, 7);
        assert!(set(lo).is_ok(), "${} = {lo} (its documented lowest) refused", d.id);
        assert!(set(hi).is_ok(), "${} = {hi} (its documented highest) refused", d.id);
        if d.unit != "boolean" || lo == hi {
            // past the top: one more for whole numbers, a little more for the others
            let above = if hi == hi.trunc() && hi < 1e7 { hi + 1.0 } else { hi * 1.01 };
            assert!(set(above).is_err(), "${} = {above} accepted, above its documented {hi}", d.id);
        }
        if lo > 0.0 {
            // well below (`$88` rounds to its fixed point, 1/65 536: half of it still counts)
            assert!(set(lo * 0.4).is_err(), "${} = {} accepted, below its documented {lo}", d.id, lo * 0.4);
        }
    }
}
