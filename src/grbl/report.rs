//! Grbl 1.1 reports: the banner, `?` status, `$G`, `$I`, `$#` and `$$` lines.
//!
//! Who uses it: the controller. Formats are those of Grbl 1.1's `report.c` as senders parse
//! them (UGS, CNCjs, bCNC): `\r\n` endings, positions with three decimals, feeds and speeds as
//! integers.

use crate::gcode::{Modal, Motion};
use crate::spindle::{SpindleDir, FLOOD, MIST};
use crate::protocol::{put_fixed, put_u32, Out, RX_BUFFER_LEN};
use crate::ramp::Shape;
use crate::settings::Ramped;

/// What a sender looks for after a reset.
pub const BANNER: &[u8] = b"\r\nGrbl 1.1h ['$' for help]\r\n";
/// `$` help.
pub const HELP: &[u8] = b"[HLP:$$ $# $G $I $N $x=val $X $H $RST=$ ~ ! ? ctrl-x]\r\n";
/// After a reset in alarm state.
pub const UNLOCK_HINT: &[u8] = b"[MSG:'$H'|'$X' to unlock]\r\n";
/// `$X` in alarm state.
pub const UNLOCKED: &[u8] = b"[MSG:Caution: Unlocked]\r\n";
/// Soft reset during motion (Grbl's ALARM:3, "Reset while in motion").
pub const ALARM_RESET: &[u8] = b"ALARM:3\r\n";
/// M2 / M30.
pub const PROGRAM_END: &[u8] = b"[MSG:Pgm End]\r\n";
/// `$RST=`.
pub const RESTORED: &[u8] = b"[MSG:Restoring defaults]\r\n";
/// Longest status report for `n` axes (`<Hold:1|MPos:` + 13 per axis + `|FS:1000000,0>\r\n`).
pub const fn status_len(n: usize) -> usize {
    16 + 13 * n + 20
}
/// Longest `$#` line for `n` axes.
pub const fn param_len(n: usize) -> usize {
    8 + 13 * n
}
/// Longest `$$` line.
pub const SETTING_LEN: usize = 24;

/// `<State|MPos:x,y,z|FS:feed,0>`.
pub fn status<const N: usize>(out: &mut impl Out, state: &[u8], mpos: &[f64; N], feed: f64) {
    out.put(b"<");
    out.put(state);
    out.put(b"|MPos:");
    axes(out, mpos);
    out.put(b"|FS:");
    put_fixed(out, feed, 0);
    out.put(b",0>\r\n");
}

fn axes(out: &mut impl Out, v: &[f64]) {
    for (i, x) in v.iter().enumerate() {
        if i > 0 {
            out.put(b",");
        }
        put_fixed(out, *x, 3);
    }
}

/// One `$$` line: `$N=value`.
pub fn setting(out: &mut impl Out, id: u16, value: f64, decimals: u32) {
    out.put(b"$");
    put_u32(out, id as u32);
    out.put(b"=");
    put_fixed(out, value, decimals);
    out.put(b"\r\n");
}

/// `$G`: `[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]`.
pub fn modes(out: &mut impl Out, m: &Modal) {
    out.put(match m.motion {
        Motion::Rapid => b"[GC:G0",
        Motion::Linear => b"[GC:G1",
        Motion::CwArc => b"[GC:G2",
        Motion::CcwArc => b"[GC:G3",
        Motion::Cancel => b"[GC:G80",
    });
    out.put(b" G54 G");
    put_u32(out, m.plane as u32);
    out.put(if m.inches { b" G20" } else { b" G21" });
    out.put(if m.relative { b" G91" } else { b" G90" });
    out.put(if m.inverse_time { b" G93" } else { b" G94" });
    out.put(match m.spindle_dir {
        SpindleDir::Off => b" M5",
        SpindleDir::Cw => b" M3",
        SpindleDir::Ccw => b" M4",
    });
    if m.coolant == 0 {
        out.put(b" M9");
    }
    if m.coolant & MIST != 0 {
        out.put(b" M7");
    }
    if m.coolant & FLOOD != 0 {
        out.put(b" M8");
    }
    out.put(b" T");
    put_u32(out, m.tool);
    out.put(b" F");
    put_fixed(out, m.feed, 0);
    out.put(b" S");
    put_fixed(out, m.spindle, 0);
    out.put(b"]\r\n");
}

/// `$I`: version, options (no compile-time options; queue moves; RX bytes) and our limits:
/// the fastest master rate the timing allows and the ramp the table holds. Moves asking for
/// more than the ramp's top cruise at the top.
pub fn build_info(out: &mut impl Out, queue_moves: usize, r: &Ramped) {
    out.put(b"[VER:1.1h.ddastep:]\r\n[OPT:,");
    put_u32(out, queue_moves as u32);
    out.put(b",");
    put_u32(out, RX_BUFFER_LEN as u32);
    out.put(b"]\r\n[MSG:max step rate ");
    put_u32(out, r.max_rate_hz);
    out.put(b" Hz]\r\n[MSG:ramp ");
    put_u32(out, r.cfg.v0);
    out.put(b"-");
    put_u32(out, r.cfg.vmax);
    out.put(b" Hz ");
    put_u32(out, r.cfg.accel);
    out.put(match r.cfg.shape {
        Shape::Trapezoid => b" Hz/s trapezoid",
        Shape::SCurve => b" Hz/s S-curve",
    });
    out.put(if r.table_limited { b" (table-limited)]\r\n" } else { b"]\r\n" });
}

/// Names of the `$#` lines; every offset is zero (no work offsets: G92 moves the machine
/// position itself).
const PARAMS: [&[u8]; 10] = [
    b"[G54:", b"[G55:", b"[G56:", b"[G57:", b"[G58:", b"[G59:", b"[G28:", b"[G30:", b"[G92:", b"[TLO:",
];
/// Lines `$#` prints.
pub const PARAM_LINES: usize = PARAMS.len() + 1;

/// Line `i` of `$#`.
pub fn param<const N: usize>(out: &mut impl Out, i: usize) {
    match PARAMS.get(i) {
        Some(name) => {
            out.put(name);
            if i + 1 == PARAMS.len() {
                put_fixed(out, 0.0, 3);
            } else {
                axes(out, &[0.0; N]);
            }
            out.put(b"]\r\n");
        }
        None => {
            out.put(b"[PRB:");
            axes(out, &[0.0; N]);
            out.put(b":0]\r\n");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ramp::RampConfig;

    type Buf = heapless::Vec<u8, 512>;

    fn text(f: impl FnOnce(&mut Buf)) -> heapless::String<512> {
        let mut b = Buf::new();
        f(&mut b);
        heapless::String::from_utf8(b).unwrap()
    }

    #[test]
    fn formats_match_grbl() {
        assert_eq!(text(|o| status(o, b"Idle", &[0.0; 3], 0.0)), "<Idle|MPos:0.000,0.000,0.000|FS:0,0>\r\n");
        assert_eq!(text(|o| status(o, b"Run", &[-1.2345, 0.0005, 12.0], 2999.6)), "<Run|MPos:-1.235,0.001,12.000|FS:3000,0>\r\n");
        assert_eq!(text(|o| modes(o, &Modal::RESET)), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\n");
        assert_eq!(text(|o| setting(o, 110, 36000.0, 3)), "$110=36000.000\r\n");
        assert_eq!(text(|o| param::<3>(o, 9)), "[TLO:0.000]\r\n");
        assert_eq!(text(|o| param::<3>(o, 10)), "[PRB:0.000,0.000,0.000:0]\r\n");
        let r = Ramped {
            cfg: RampConfig { v0: 1000, vmax: 60_000, accel: 1_000_000, shape: Shape::Trapezoid },
            max_rate_hz: 166_666,
            table_limited: false,
        };
        let info = text(|o| build_info(o, 15, &r));
        assert_eq!(
            info,
            "[VER:1.1h.ddastep:]\r\n[OPT:,15,128]\r\n[MSG:max step rate 166666 Hz]\r\n\
             [MSG:ramp 1000-60000 Hz 1000000 Hz/s trapezoid]\r\n"
        );
        assert!(info.len() <= crate::protocol::REPLY_ROOM);
    }

    #[test]
    fn worst_case_lines_fit_their_budgets() {
        let far = [-1_000_000.0; 7];
        assert!(text(|o| status(o, b"Hold:1", &far, 999_999.0)).len() <= status_len(7));
        assert!(text(|o| param::<7>(o, 0)).len() <= param_len(7));
        assert!(text(|o| setting(o, 139, 100_000_000.0, 3)).len() <= SETTING_LEN);
    }
}
