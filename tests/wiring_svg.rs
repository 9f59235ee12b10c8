//! `docs/wiring.svg`, the Blue Pill pin map picture in docs/wiring.md, is drawn from
//! `ddastep::board`: this test draws it and fails when the committed file differs.
//! `UPDATE_DOCS=1 cargo test -p ddastep --target host-tuple --test wiring_svg` rewrites it.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use ddastep::board::*;
use ddastep::AXIS_NAMES;

/// The Blue Pill's two pin rows seen from the components' side, USB socket on the left, SWD
/// header on the right: the row along the top edge, then the one along the bottom edge.
const TOP_ROW: [&str; 20] =
    ["B12", "B13", "B14", "B15", "A8", "A9", "A10", "A11", "A12", "A15", "B3", "B4", "B5", "B6", "B7", "B8", "B9", "5V", "G", "3V3"];
const BOTTOM_ROW: [&str; 20] =
    ["G", "G", "3V3", "R", "B11", "B10", "B1", "B0", "A7", "A6", "A5", "A4", "A3", "A2", "A1", "A0", "C15", "C14", "C13", "VB"];

/// What a pin is for: its label and its group (the colour).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Group {
    Motion,
    Input,
    Spindle,
    Serial,
    Other,
}

impl Group {
    fn colour(self) -> &'static str {
        match self {
            Group::Motion => "#1f77b4",
            Group::Input => "#2ca02c",
            Group::Spindle => "#d62728",
            Group::Serial => "#9467bd",
            Group::Other => "#7f7f7f",
        }
    }

    fn legend(self) -> &'static str {
        match self {
            Group::Motion => "step, direction, enable (outputs)",
            Group::Input => "switches and encoder (inputs, pulled up)",
            Group::Spindle => "spindle, laser, coolant (outputs)",
            Group::Serial => "serial to the sender, USB (kept free)",
            Group::Other => "LED, power",
        }
    }
}

/// Each used pin's label, from `ddastep::board` (USART1 and USB are the STM32F103's fixed pins).
fn labels() -> BTreeMap<String, Vec<(String, Group)>> {
    let mut m: BTreeMap<String, Vec<(String, Group)>> = BTreeMap::new();
    let mut add = |port: char, pin: u8, label: String, g: Group| m.entry(format!("{port}{pin}")).or_default().push((label, g));
    for (i, axis) in AXIS_NAMES.iter().enumerate() {
        add('B', STEP_PINS[i], format!("{axis} STEP"), Group::Motion);
        add('B', DIR_PINS[i], format!("{axis} DIR"), Group::Motion);
        add('A', LIMIT_PINS[i], format!("{axis} limit"), Group::Input);
    }
    add('B', ENABLE_PIN, "EN (all drivers)".into(), Group::Motion);
    add('A', SPINDLE_PWM_PIN, "spindle/laser PWM".into(), Group::Spindle);
    add('A', SPINDLE_ENABLE_PIN, "spindle enable".into(), Group::Spindle);
    add('A', SPINDLE_DIR_PIN, "spindle dir".into(), Group::Spindle);
    add('A', COOLANT_FLOOD_PIN, "flood".into(), Group::Spindle);
    add('A', COOLANT_MIST_PIN, "mist".into(), Group::Spindle);
    add('A', ENCODER_PINS[0], "encoder A".into(), Group::Input);
    add('A', ENCODER_PINS[1], "encoder B".into(), Group::Input);
    add('C', PROBE_PIN, "probe".into(), Group::Input);
    add('C', DOOR_PIN, "door".into(), Group::Input);
    add('C', LED_PIN, "LED".into(), Group::Other);
    add('A', 9, "TX to adapter RX".into(), Group::Serial);
    add('A', 10, "RX from adapter TX".into(), Group::Serial);
    add('A', 11, "USB D-".into(), Group::Serial);
    add('A', 12, "USB D+".into(), Group::Serial);
    m
}

// a pin's label text and colour: the accessory first where an accessory takes an axis's
// limit input (wiring.md: the 4th to 7th axes' limit pins), power pins by name
fn describe(name: &str, labels: &BTreeMap<String, Vec<(String, Group)>>) -> (String, &'static str) {
    match labels.get(name) {
        Some(uses) => {
            let mut uses = uses.clone();
            uses.sort_by_key(|(_, g)| if *g == Group::Spindle { 0 } else { 1 });
            let text = uses.iter().map(|(l, _)| l.as_str()).collect::<Vec<_>>().join(" / ");
            (text, uses[0].1.colour())
        }
        None => match name {
            "5V" | "3V3" | "G" | "VB" => (if name == "G" { "GND".into() } else { name.into() }, Group::Other.colour()),
            "R" => ("reset".into(), Group::Other.colour()),
            _ => ("free".into(), "#bbbbbb"),
        },
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// The picture: the board, each header pin with its pin name and, at an angle, its use.
fn svg() -> String {
    let labels = labels();
    let (pitch, x0, w, h) = (36.0, 60.0, 980.0, 580.0);
    let (board_top, board_bottom) = (200.0, 350.0);
    let mut s = String::new();
    writeln!(s, r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#).unwrap();
    writeln!(s, r##"<rect width="{w}" height="{h}" fill="#ffffff"/>"##).unwrap();
    writeln!(s, r##"<text x="{x0}" y="24" font-size="16" font-weight="bold">ddastep on a Blue Pill (STM32F103C8), components up, USB left; drawn from ddastep::board</text>"##).unwrap();
    // the board, the USB socket, the SWD header
    writeln!(s, r##"<rect x="{}" y="{board_top}" width="{}" height="{}" rx="6" fill="#1d4e89" stroke="#0b2545"/>"##, x0 - 30.0, 20.0 * pitch + 40.0, board_bottom - board_top).unwrap();
    writeln!(s, r##"<rect x="{}" y="{}" width="34" height="44" fill="#c0c0c0" stroke="#555"/><text x="{}" y="{}" fill="#ffffff">USB</text>"##, x0 - 44.0, (board_top + board_bottom) / 2.0 - 22.0, x0, (board_top + board_bottom) / 2.0 + 4.0).unwrap();
    let swd_x = x0 + 20.0 * pitch + 10.0;
    writeln!(s, r##"<text x="{}" y="{}" fill="#ffffff" text-anchor="end">SWD: 3V3 DIO(PA13) DCLK(PA14) GND</text>"##, swd_x - 8.0, (board_top + board_bottom) / 2.0 + 4.0).unwrap();
    writeln!(s, r##"<text x="{}" y="{}" fill="#ffffff">STM32F103C8   BOOT0/BOOT1 jumpers (PB2 = BOOT1, not on the header)</text>"##, x0 + 4.0 * pitch, (board_top + board_bottom) / 2.0 - 16.0).unwrap();
    for (row, y, up) in [(&TOP_ROW, board_top + 14.0, true), (&BOTTOM_ROW, board_bottom - 14.0, false)] {
        for (i, name) in row.iter().enumerate() {
            let x = x0 + i as f64 * pitch;
            let (text, colour) = describe(name, &labels);
            writeln!(s, r##"<circle cx="{x}" cy="{y}" r="6" fill="#e8c547" stroke="#333"/>"##).unwrap();
            let (ny, ly, anchor) = if up { (y + 22.0, y - 16.0, "start") } else { (y - 14.0, y + 18.0, "end") };
            writeln!(s, r##"<text x="{x}" y="{ny}" fill="#ffffff" font-size="10" text-anchor="middle">{}</text>"##, esc(name)).unwrap();
            writeln!(s, r##"<text x="{x}" y="{ly}" fill="{colour}" text-anchor="{anchor}" transform="rotate(-60 {x} {ly})">{}</text>"##, esc(&text)).unwrap();
        }
    }
    // legend
    let mut y = 520.0;
    for (i, g) in [Group::Motion, Group::Input, Group::Spindle, Group::Serial, Group::Other].into_iter().enumerate() {
        let x = x0 + (i % 3) as f64 * 280.0;
        if i == 3 {
            y += 20.0;
        }
        writeln!(s, r##"<rect x="{x}" y="{}" width="12" height="12" fill="{}"/><text x="{}" y="{y}">{}</text>"##, y - 10.0, g.colour(), x + 18.0, esc(g.legend())).unwrap();
    }
    writeln!(s, r##"<text x="{x0}" y="{}">Axis A's, B's, C's and U's limit inputs carry mist, flood, spindle dir and spindle PWM unless those axes are wired.</text>"##, y + 26.0).unwrap();
    s.push_str("</svg>\n");
    s
}

#[test]
fn wiring_svg_matches_the_pin_map() {
    let want = svg();
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/wiring.svg");
    if std::env::var_os("UPDATE_DOCS").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(have == want, "docs/wiring.svg differs from ddastep::board: regenerate with UPDATE_DOCS=1 (tests/wiring_svg.rs)");
}

#[test]
fn every_pin_the_firmware_uses_is_on_the_header_and_drawn() {
    let drawn: Vec<&str> = TOP_ROW.iter().chain(&BOTTOM_ROW).copied().collect();
    for pin in labels().keys() {
        assert!(drawn.contains(&pin.as_str()), "{pin} is used but not on the drawn header");
    }
    // every pin ddastep uses is labelled in the picture
    let svg = svg();
    for (i, axis) in AXIS_NAMES.iter().enumerate() {
        assert!(svg.contains(&format!("{axis} STEP")) && svg.contains(&format!("{axis} DIR")), "axis {i}");
    }
}

#[test]
fn the_pin_tables_in_wiring_md_match_the_pin_map() {
    let md = std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/wiring.md")).unwrap();
    for (i, axis) in AXIS_NAMES.iter().enumerate() {
        // U's limit input is the spindle PWM pin (board.rs), shown as such
        let limit = if LIMIT_PINS[i] == SPINDLE_PWM_PIN { format!("(PA{}: spindle PWM)", LIMIT_PINS[i]) } else { format!("PA{}", LIMIT_PINS[i]) };
        let row = format!("| {axis} | PB{} | PB{} | {limit} |", STEP_PINS[i], DIR_PINS[i]);
        assert!(md.contains(&row), "wiring.md lacks {row}");
    }
    for (signal, pin) in [
        ("EN (all drivers", format!("PB{ENABLE_PIN}")),
        ("spindle / laser PWM", format!("PA{SPINDLE_PWM_PIN}")),
        ("spindle enable", format!("PA{SPINDLE_ENABLE_PIN}")),
        ("spindle direction", format!("PA{SPINDLE_DIR_PIN}")),
        ("flood coolant M8 / mist coolant M7", format!("PA{COOLANT_FLOOD_PIN} / PA{COOLANT_MIST_PIN}")),
        ("LED heartbeat", format!("PC{LED_PIN}")),
        ("probe (input", format!("PC{PROBE_PIN}")),
        ("safety door (input", format!("PC{DOOR_PIN}")),
        ("quadrature encoder A / B", format!("PA{} / PA{}", ENCODER_PINS[0], ENCODER_PINS[1])),
    ] {
        let line = md.lines().find(|l| l.starts_with(&format!("| {signal}"))).unwrap_or_else(|| panic!("wiring.md has no row for {signal}"));
        assert!(line.trim_end().ends_with(&format!("| {pin} |")), "{signal}: wiring.md says {line}, board.rs {pin}");
    }
}
