//! G-code words, numbers and modal state against Grbl 1.1's rules and error codes.

use ddastep::grbl::gcode::{parse, parse_number, Modal, Motion};
use ddastep::error::Error;

fn num(s: &str) -> Result<f32, Error> {
    let mut i = 0;
    let v = parse_number(s.as_bytes(), &mut i)?;
    assert_eq!(i, s.len(), "{s}");
    Ok(v)
}

#[test]
fn numbers_match_std_and_refuse_junk() {
    for s in ["0", "-0.5", "+12.25", "123456.789", ".5", "5.", "0.000001", "999999999999999", "1.10000000000000000000"] {
        assert_eq!(num(s), Ok(s.parse::<f32>().unwrap()), "{s}");
    }
    for s in ["", "-", "--5", ".", "+.", "1000000000000000", "0.0000000000000000000001234"] {
        assert_eq!(num(s), Err(Error::BadNumberFormat), "{s}");
    }
    let mut i = 0;
    assert_eq!(parse_number(b"1.2.3", &mut i), Ok(1.2));
    assert_eq!(i, 3);
}

#[test]
fn words_follow_grbl_error_codes() {
    let e = |s: &str| parse::<3>(s.as_bytes()).err();
    assert_eq!(e("G1X10F100"), None);
    assert_eq!(e("1"), Some(Error::ExpectedCommandLetter));
    assert_eq!(e("XNAN"), Some(Error::BadNumberFormat));
    assert_eq!(e("X1E999"), Some(Error::UnsupportedCommand));
    assert_eq!(e("G0G1"), Some(Error::AxisCommandConflict)); // as Grbl: both use the axes
    assert_eq!(e("G0G80"), Some(Error::ModalGroupViolation));
    assert_eq!(e("G20G21"), Some(Error::ModalGroupViolation));
    assert_eq!(e("X1X2"), Some(Error::WordRepeated));
    assert_eq!(e("F-1"), Some(Error::NegativeValue));
    assert_eq!(e("G1.5"), Some(Error::CommandValueNotInteger));
    assert_eq!(e("G38.2X1"), None);
    assert_eq!(e("G38.1X1"), Some(Error::UnsupportedCommand));
    assert_eq!(e("G38X1"), Some(Error::UnsupportedCommand));
    assert_eq!(e("G2X1I1"), None);
    assert_eq!(e("G91.1"), None);
    assert_eq!(e("A1"), Some(Error::UnsupportedCommand));
    assert_eq!(parse::<4>(b"A1").err(), None);
    assert_eq!(e("M6"), Some(Error::UnsupportedCommand));
    assert_eq!(e("G92G1X0"), Some(Error::AxisCommandConflict));
    assert_eq!(e("G1G92X0"), Some(Error::AxisCommandConflict));
    assert_eq!(e("G4G92"), Some(Error::ModalGroupViolation));
}

#[test]
fn modal_state_follows_grbl() {
    let pos = [1.0, 2.0, 3.0];
    let run = |m: &Modal, s: &str| m.interpret::<3>(&parse::<3>(s.as_bytes()).unwrap(), &pos);
    let m = Modal::RESET;
    assert_eq!(run(&m, "G1X5").err(), Some(Error::UndefinedFeedRate));
    assert_eq!(run(&m, "G1").unwrap().1.motion, None); // no axis words: just the mode
    let (m2, fx) = run(&m, "G20G91G1X1F10").unwrap();
    assert_eq!(fx.motion, Some(([26.4, 2.0, 3.0], false)));
    assert_eq!((m2.feed, m2.relative, m2.inches), (254.0, true, true));
    assert_eq!(run(&m, "G80X1").err(), Some(Error::AxisWordsExist));
    assert_eq!(run(&m, "G4").err(), Some(Error::ValueWordMissing));
    assert_eq!(run(&m, "G4P1.5").unwrap().1.dwell_ms, Some(1500));
    assert_eq!(run(&m, "G0X1P1").err(), Some(Error::UnusedWords));
    assert_eq!(run(&m, "G92").err(), Some(Error::NoAxisWords));
    assert_eq!(run(&m, "G92Y7").unwrap().1.g92, Some([0.0, -5.0, 0.0])); // Y reads 7 at 2
    assert_eq!(run(&m, "X1000001").err(), Some(Error::InvalidTarget));
    assert_eq!(run(&m, "N10000001").err(), Some(Error::InvalidLineNumber));
    let (m3, _) = run(&m2, "M30").unwrap();
    assert_eq!((m3.motion, m3.relative, m3.feed), (Motion::Linear, false, 254.0));
    assert_eq!(run(&m, "F300").unwrap().0.feed, 300.0);
}
