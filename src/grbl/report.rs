//! Grbl 1.1 reports: the banner, `?` status, `$G`, `$I`, `$#` and `$$` lines.
//!
//! Who uses it: the controller. Formats are those of Grbl 1.1's `report.c` as senders parse
//! them (UGS, CNCjs, bCNC): `\r\n` endings, positions with three decimals, feeds and speeds as
//! integers.

use crate::grbl::coords::{Offsets, G28, G30};
use crate::grbl::gcode::{Modal, Motion};
use crate::grbl::spindle::{SpindleDir, FLOOD, MIST};
use crate::grbl::protocol::RX_BUFFER_LEN;
use crate::grbl::reply::{put_fixed_after, put_u32_after, Out};
use crate::motion::moves::Overrides;
use crate::motion::ramp::Shape;
use crate::grbl::settings::Ramped;

/// What a sender looks for after a reset.
pub const BANNER: &[u8] = b"\r\nGrbl 1.1h ['$' for help]\r\n";
/// `$` help.
pub const HELP: &[u8] = b"[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]\r\n";
/// After a reset in alarm state.
pub const UNLOCK_HINT: &[u8] = b"[MSG:'$H'|'$X' to unlock]\r\n";
/// `$X` in alarm state.
pub const UNLOCKED: &[u8] = b"[MSG:Caution: Unlocked]\r\n";
/// Boot after an independent-watchdog reset (the controller starts in the alarm state).
pub const WATCHDOG_RESET: &[u8] = b"[MSG:Reset by watchdog]\r\n";
/// Alarm codes (`ALARM:N`), Grbl's numbers. Hard limit (then the critical-event message).
pub const ALARM_HARD_LIMIT: u8 = 1;
/// A G-code target outside the travel box ("Soft limit"), then Grbl's critical-event message:
/// nothing is read until Ctrl-X.
pub const ALARM_SOFT_LIMIT: u8 = 2;
/// Soft reset during motion ("Reset while in motion").
pub const ALARM_RESET: u8 = 3;
/// Probe fail: already in the state the cycle looks for.
pub const ALARM_PROBE_INITIAL: u8 = 4;
/// Probe fail: G38.2/G38.4 ended without contact.
pub const ALARM_PROBE_CONTACT: u8 = 5;
/// Reset during the homing cycle.
pub const ALARM_HOMING_RESET: u8 = 6;
/// The safety door opened during the homing cycle.
pub const ALARM_HOMING_DOOR: u8 = 7;
/// Homing: the pull-off did not clear the switch.
pub const ALARM_PULLOFF: u8 = 8;
/// Homing: the approach found no switch.
pub const ALARM_APPROACH: u8 = 9;
/// The chip check at boot failed (grblHAL's "self-test failed"): the part has too little
/// flash (`crate::grbl::chip`); nothing unlocks it.
pub const ALARM_SELF_TEST: u8 = 16;
/// Step loss with `$98=1` (grblHAL's "motor fault"), then the critical-event message: nothing
/// is read until Ctrl-X.
pub const ALARM_STEP_LOSS: u8 = 17;
/// Grbl's critical-event message, after the alarms that need a reset (1, 2, 17).
const RESET_TO_CONTINUE: &[u8] = b"[MSG:Reset to continue]\r\n";

/// Alarm `code`'s critical-event message, if it has one.
const fn alarm_tail(code: u8) -> &'static [u8] {
    match code {
        ALARM_HARD_LIMIT | ALARM_SOFT_LIMIT | ALARM_STEP_LOSS => RESET_TO_CONTINUE,
        _ => b"",
    }
}

/// Bytes [`alarm`] writes for `code`.
pub const fn alarm_len(code: u8) -> usize {
    b"ALARM:\r\n".len() + if code >= 10 { 2 } else { 1 } + alarm_tail(code).len()
}

/// `ALARM:N`, then `[MSG:Reset to continue]` for the critical events (one copy of the text
/// for every alarm).
#[inline(never)]
pub fn alarm(out: &mut impl Out, code: u8) {
    put_u32_after(out, b"ALARM:", code as u32);
    out.put(b"\r\n");
    out.put(alarm_tail(code));
}
/// M2 / M30.
pub const PROGRAM_END: &[u8] = b"[MSG:Pgm End]\r\n";
/// `$RST=`.
pub const RESTORED: &[u8] = b"[MSG:Restoring defaults]\r\n";
/// `$C` on.
pub const CHECK_ON: &[u8] = b"[MSG:Enabled]\r\n";
/// `$C` off (a reset follows).
pub const CHECK_OFF: &[u8] = b"[MSG:Disabled]\r\n";
/// `$SLP`.
pub const SLEEPING: &[u8] = b"[MSG:Sleeping]\r\n";
/// Longest status report for `n` axes: `<Hold:1|WPos:` + 13 per axis + `|Bf:15,128` +
/// `Pn:` bit of the probe input (bits 0–2: the X, Y, Z limits).
pub const PIN_PROBE: u8 = 0x80;
/// `Pn:` bit of the safety door input (`D`, after the limits as in Grbl).
pub const PIN_DOOR: u8 = 0x08;

/// `|FS:1000000,1000000` + `|Pn:PXYZD` + `|WCO:` + 13 per axis + `|Ov:100,100,100|A:SFM` +
/// `|Enc:` + two numbers of at most 17 and 16 characters (`put_fixed`'s 10^15 cap) + `>\r\n`.
pub const fn status_len(n: usize) -> usize {
    124 + 26 * n
}
/// Longest `$#` line for `n` axes.
pub const fn param_len(n: usize) -> usize {
    8 + 13 * n
}
/// Longest `$$` line.
pub const SETTING_LEN: usize = 24;

/// One status report's fields.
#[derive(Clone, Copy, Debug)]
pub struct Status<'a> {
    pub state: &'a [u8],
    /// Machine or work position (per `$10`), one value per axis in use.
    pub pos: &'a [f32],
    /// `pos` is the machine position.
    pub mpos: bool,
    /// `Bf:` planner blocks free, RX bytes free (when `$10` asks for it).
    pub bf: Option<(u32, u32)>,
    /// Current feed, mm/min.
    pub feed: f32,
    /// Spindle speed in force (0 when off; at most `$30`).
    pub speed: f32,
    /// `A:` accessories, shown with `Ov:`: spindle CW (`S`) or CCW (`C`), flood (`F`), mist (`M`).
    pub acc: &'a [u8],
    /// `Pn:` input pins active (bit i = axis i's limit), shown when not 0.
    pub pins: u8,
    /// `WCO:` when due.
    pub wco: Option<&'a [f32]>,
    /// `Ov:` when due.
    pub ov: Option<Overrides>,
    /// `Enc:` encoder position (mm) and speed (mm/min), when an encoder is on.
    pub enc: Option<(f32, f32)>,
}

/// `<State|MPos:x,y,z|Bf:15,128|FS:feed,speed|Pn:XZ|WCO:x,y,z|Ov:100,100,100|A:SF|Enc:p,v>`.
pub fn status(out: &mut impl Out, s: &Status) {
    out.put(b"<");
    out.put(s.state);
    out.put(if s.mpos { b"|MPos:" } else { b"|WPos:" });
    axes(out, s.pos);
    if let Some((blocks, rx)) = s.bf {
        put_u32_after(out, b"|Bf:", blocks);
        put_u32_after(out, b",", rx);
    }
    put_fixed_after(out, b"|FS:", s.feed, 0);
    put_fixed_after(out, b",", s.speed, 0);
    if s.pins != 0 {
        out.put(b"|Pn:");
        if s.pins & PIN_PROBE != 0 {
            out.put(b"P");
        }
        for (i, &letter) in b"XYZD".iter().enumerate() {
            if s.pins & 1 << i != 0 {
                out.put(&[letter]);
            }
        }
    }
    if let Some(w) = s.wco {
        out.put(b"|WCO:");
        axes(out, w);
    }
    if let Some(o) = s.ov {
        put_u32_after(out, b"|Ov:", o.feed as u32);
        put_u32_after(out, b",", o.rapid as u32);
        put_u32_after(out, b",", o.spindle as u32);
        if !s.acc.is_empty() {
            out.put(b"|A:");
            out.put(s.acc);
        }
    }
    if let Some((pos, speed)) = s.enc {
        put_fixed_after(out, b"|Enc:", pos, 3);
        put_fixed_after(out, b",", speed, 0);
    }
    out.put(b">\r\n");
}

/// `[MSG:Step loss X 12]`: the axis and how far the motor is behind, steps (negative: ahead).
pub fn step_loss(out: &mut impl Out, axis: usize, steps: f32) {
    values(out, [b"[MSG:Step loss ", axis_letter(axis), b" "], &[(steps, 0)], b"]\r\n");
}

/// `$ENC`: `[ENC:X,10.000,9.960,4]`: axis, commanded and measured position (mm, machine),
/// commanded − measured steps.
pub fn encoder(out: &mut impl Out, axis: usize, commanded_mm: f32, measured_mm: f32, steps: f32) {
    values(out, [b"[ENC:", axis_letter(axis), b","], &[(commanded_mm, 3), (measured_mm, 3), (steps, 0)], b"]\r\n");
}

/// The letter of axis `i` (X Y Z A B C U).
fn axis_letter(i: usize) -> &'static [u8] {
    b"XYZABCU".get(i..=i).unwrap_or_default()
}

/// `head`, then `(value, decimals)` separated by commas, then `tail`: one copy of the writes
/// for the encoder's two lines.
#[inline(never)]
fn values(out: &mut impl Out, head: [&[u8]; 3], values: &[(f32, u32)], tail: &[u8]) {
    for part in head {
        out.put(part);
    }
    for (i, &(v, d)) in values.iter().enumerate() {
        put_fixed_after(out, if i > 0 { b"," } else { b"" }, v, d);
    }
    out.put(tail);
}

fn axes(out: &mut impl Out, v: &[f32]) {
    for (i, x) in v.iter().enumerate() {
        put_fixed_after(out, if i > 0 { b"," } else { b"" }, *x, 3);
    }
}

/// One `$$` line: `$N=value`.
pub fn setting(out: &mut impl Out, id: u16, value: f32, decimals: u32) {
    put_u32_after(out, b"$", id as u32);
    put_fixed_after(out, b"=", value, decimals);
    out.put(b"\r\n");
}

/// `$G`: `[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]`.
#[inline(never)]
pub fn modes(out: &mut impl Out, m: &Modal) {
    out.put(b"[GC:G");
    match m.motion {
        Motion::Rapid => out.put(b"0"),
        Motion::Linear => out.put(b"1"),
        Motion::CwArc => out.put(b"2"),
        Motion::CcwArc => out.put(b"3"),
        Motion::Cancel => out.put(b"80"),
        Motion::Probe(k) => {
            put_u32_after(out, b"38.", if (2..=4).contains(&k) { k as u32 } else { 5 });
        }
    }
    put_u32_after(out, b" G", 54 + m.coord as u32);
    put_u32_after(out, b" G", m.plane as u32);
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
    put_u32_after(out, b" T", m.tool);
    put_fixed_after(out, b" F", m.feed, 0);
    put_fixed_after(out, b" S", m.spindle, 0);
    out.put(b"]\r\n");
}

/// `$I`: version, options (no compile-time options; queue moves; RX bytes) and our limits:
/// the fastest master rate the timing allows and the ramp the table holds. Moves asking for
/// more than the ramp's top cruise at the top.
pub fn build_info(out: &mut impl Out, info: &[u8], queue_moves: usize, r: &Ramped) {
    out.put(b"[VER:1.1h.ddastep:");
    out.put(info);
    // Grbl's build-option letters for what we have, in its order: variable spindle, M7 mist,
    // single-axis homing (`$HX`), the safety door input. No line numbers (`N`).
    put_u32_after(out, b"]\r\n[OPT:VMH+,", queue_moves as u32);
    put_u32_after(out, b",", RX_BUFFER_LEN as u32);
    put_u32_after(out, b"]\r\n[MSG:max step rate ", r.max_rate_hz);
    out.put(b" Hz");
    if r.dual {
        out.put(b" dual-edge");
    }
    if r.dma {
        out.put(b" DMA");
    }
    if r.junction_hz != 0 {
        put_u32_after(out, b"]\r\n[MSG:max junction rate ", r.junction_hz);
        out.put(b" Hz");
    }
    put_u32_after(out, b"]\r\n[MSG:ramp ", r.cfg.v0);
    put_u32_after(out, b"-", r.cfg.vmax);
    put_u32_after(out, b" Hz ", r.cfg.accel);
    out.put(match r.cfg.shape {
        Shape::Trapezoid => b" Hz/s trapezoid",
        Shape::SCurve => b" Hz/s S-curve per move (table at a/k)",
    });
    out.put(if r.table_limited { b" (table-limited)]\r\n" } else { b"]\r\n" });
}

/// Longest [`step_time`] line.
pub const STEP_TIME_LEN: usize =
    b"[MSG:step fill 4294967295/4294967295.0/4294967295 cycles min/mean/max, load 100.0 % peak 100.0 %, late 4294967295]\r\n".len();

/// `$I`'s step-interrupt line: the firmware's own DWT timing of the step path since the last
/// `$I` (`steptime`): body cycles min/mean/max, average and peak 1 ms load.
pub fn step_time(out: &mut impl Out, t: &crate::steptime::StepTimeReport, dma: bool) {
    // (DMA burst mode: the step path is the fill of one buffer half per entry.)
    put_u32_after(out, if dma { b"[MSG:step fill " as &[u8] } else { b"[MSG:step isr " }, t.min);
    put_fixed_after(out, b"/", t.mean, 1);
    put_u32_after(out, b"/", t.max);
    put_fixed_after(out, b" cycles min/mean/max, load ", t.load * 100.0, 1);
    put_fixed_after(out, b" % peak ", t.peak_load * 100.0, 1);
    if dma {
        // Fills that ended after DMA had entered their half (0 unless the fill fell behind).
        put_u32_after(out, b" %, late ", t.late);
        out.put(b"]\r\n");
    } else {
        out.put(b" %]\r\n");
    }
}

/// Lines `$#` prints: G54..G59, G28, G30, G92, TLO, PRB.
pub const PARAM_LINES: usize = 11;
// (`param`'s G-number table follows the stored positions' order.)
const _: () = assert!(G28 == 6 && G30 == 7);

/// Line `i` of `$#` (machine millimetres; `[PRB:…:1]` after a probe made contact).
pub fn param<const N: usize>(out: &mut impl Out, i: usize, off: &Offsets<N>, axes_used: usize) {
    let n = axes_used.min(N);
    let (g, v): (u32, [f32; N]) = match i {
        // G54..G59, G28, G30: the stored positions in that order.
        0..=G30 => ([54, 55, 56, 57, 58, 59, 28, 30][i], off.stored.get(i)),
        8 => (92, off.g92),
        9 => {
            put_fixed_after(out, b"[TLO:", off.tlo, 3);
            out.put(b"]\r\n");
            return;
        }
        _ => {
            out.put(b"[PRB:");
            axes(out, off.prb.get(..n).unwrap_or_default());
            out.put(if off.prb_ok { b":1]\r\n" } else { b":0]\r\n" });
            return;
        }
    };
    put_u32_after(out, b"[G", g);
    out.put(b":");
    axes(out, v.get(..n).unwrap_or_default());
    out.put(b"]\r\n");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::ramp::RampConfig;

    type Buf = heapless::Vec<u8, 512>;

    fn text(f: impl FnOnce(&mut Buf)) -> heapless::String<512> {
        let mut b = Buf::new();
        f(&mut b);
        heapless::String::from_utf8(b).unwrap()
    }

    #[test]
    fn formats_match_grbl() {
        let st = Status { state: b"Idle", pos: &[0.0; 3], mpos: true, bf: None, feed: 0.0, speed: 0.0, acc: b"", pins: 0, wco: None, ov: None, enc: None };
        assert_eq!(text(|o| status(o, &st)), "<Idle|MPos:0.000,0.000,0.000|FS:0,0>\r\n");
        let st = Status { state: b"Run", pos: &[-1.2345, 0.0005, 12.0], feed: 2999.6, ..st };
        assert_eq!(text(|o| status(o, &st)), "<Run|MPos:-1.235,0.001,12.000|FS:3000,0>\r\n");
        let st = Status { mpos: false, bf: Some((15, 128)), wco: Some(&[1.0, 2.0, 3.0]), ov: Some(Overrides::NONE), ..st };
        assert_eq!(
            text(|o| status(o, &st)),
            "<Run|WPos:-1.235,0.001,12.000|Bf:15,128|FS:3000,0|WCO:1.000,2.000,3.000|Ov:100,100,100>\r\n"
        );
        let st = Status { enc: Some((-0.0625, 1234.4)), wco: None, ov: None, bf: None, ..st };
        assert_eq!(text(|o| status(o, &st)), "<Run|WPos:-1.235,0.001,12.000|FS:3000,0|Enc:-0.063,1234>\r\n");
        assert_eq!(text(|o| step_loss(o, 0, 37.25)), "[MSG:Step loss X 37]\r\n");
        assert_eq!(text(|o| encoder(o, 6, 10.0, 9.96, -4.0)), "[ENC:U,10.000,9.960,-4]\r\n");
        assert_eq!(text(|o| modes(o, &Modal::RESET)), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\n");
        assert_eq!(text(|o| setting(o, 110, 36000.0, 3)), "$110=36000.000\r\n");
        let off = Offsets::<3>::default();
        assert_eq!(text(|o| param::<3>(o, 0, &off, 3)), "[G54:0.000,0.000,0.000]\r\n");
        assert_eq!(text(|o| param::<3>(o, 7, &off, 3)), "[G30:0.000,0.000,0.000]\r\n");
        assert_eq!(text(|o| param::<3>(o, 5, &off, 3)), "[G59:0.000,0.000,0.000]\r\n");
        assert_eq!(text(|o| param::<3>(o, 6, &off, 3)), "[G28:0.000,0.000,0.000]\r\n");
        assert_eq!(text(|o| param::<3>(o, 8, &off, 3)), "[G92:0.000,0.000,0.000]\r\n");
        assert_eq!(text(|o| param::<3>(o, 9, &off, 3)), "[TLO:0.000]\r\n");
        assert_eq!(text(|o| param::<3>(o, 10, &off, 2)), "[PRB:0.000,0.000:0]\r\n");
        let r = Ramped {
            cfg: RampConfig { v0: 1000, vmax: 60_000, accel: 1_000_000, shape: Shape::Trapezoid },
            max_rate_hz: 166_666,
            table_limited: false,
            dual: false,
            dma: false,
            junction_hz: 0,
        };
        let info = text(|o| build_info(o, b"", 15, &r));
        assert_eq!(
            info,
            "[VER:1.1h.ddastep:]\r\n[OPT:VMH+,15,128]\r\n[MSG:max step rate 166666 Hz]\r\n\
             [MSG:ramp 1000-60000 Hz 1000000 Hz/s trapezoid]\r\n"
        );
        assert!(info.len() <= crate::grbl::reply::REPLY_ROOM);
        let t = crate::steptime::StepTimeReport { entries: 9, min: 190, mean: 191.44, max: 1402, load: 0.0812, peak_load: 0.156, late: 2 };
        assert_eq!(text(|o| step_time(o, &t, false)), "[MSG:step isr 190/191.4/1402 cycles min/mean/max, load 8.1 % peak 15.6 %]\r\n");
        assert_eq!(text(|o| step_time(o, &t, true)), "[MSG:step fill 190/191.4/1402 cycles min/mean/max, load 8.1 % peak 15.6 %, late 2]\r\n");
        let worst = crate::steptime::StepTimeReport { entries: 1, min: u32::MAX, mean: u32::MAX as f32, max: u32::MAX, load: 1.0, peak_load: 1.0, late: u32::MAX };
        let dual = text(|o| build_info(o, b"", 15, &Ramped { dual: true, ..r }));
        assert!(dual.contains("[MSG:max step rate 166666 Hz dual-edge]\r\n"), "{dual}");
        let dma = text(|o| build_info(o, b"", 15, &Ramped { dma: true, junction_hz: 300_000, ..r }));
        assert!(dma.contains("[MSG:max step rate 166666 Hz DMA]\r\n[MSG:max junction rate 300000 Hz]\r\n"), "{dma}");
        let r = Ramped { table_limited: true, dual: true, dma: true, junction_hz: 1_000_000, ..r };
        let all = text(|o| {
            build_info(o, &[b'x'; crate::grbl::store::TEXT_LEN], 15, &r);
            let info_len = o.len();
            step_time(o, &worst, true);
            assert!(o.len() <= STEP_TIME_LEN + info_len, "step time line");
            o.put(b"ok\r\n");
        });
        assert!(all.len() <= crate::grbl::reply::REPLY_ROOM, "{}", all.len());
    }

    #[test]
    fn modes_name_every_motion() {
        let cases = [
            (Motion::Rapid, "G0"), (Motion::Linear, "G1"), (Motion::CwArc, "G2"), (Motion::CcwArc, "G3"),
            (Motion::Cancel, "G80"), (Motion::Probe(2), "G38.2"), (Motion::Probe(3), "G38.3"),
            (Motion::Probe(4), "G38.4"), (Motion::Probe(5), "G38.5"),
        ];
        for (motion, g) in cases {
            let line = text(|o| modes(o, &Modal { motion, ..Modal::RESET }));
            let rest = line.strip_prefix("[GC:").and_then(|l| l.strip_prefix(g));
            assert_eq!(rest, Some(" G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\n"), "{line}");
        }
        let r = Ramped {
            cfg: RampConfig { v0: 1, vmax: 2, accel: 3, shape: Shape::SCurve },
            max_rate_hz: 4,
            table_limited: true,
            dual: true,
            dma: true,
            junction_hz: 5,
        };
        let all = text(|o| build_info(o, b"i", 5, &r));
        assert!(all.ends_with("[MSG:max step rate 4 Hz dual-edge DMA]\r\n[MSG:max junction rate 5 Hz]\r\n[MSG:ramp 1-2 Hz 3 Hz/s S-curve per move (table at a/k) (table-limited)]\r\n"), "{all}");
    }

    #[test]
    fn alarms_are_grbls_lines() {
        assert_eq!(text(|o| alarm(o, ALARM_RESET)), "ALARM:3\r\n");
        assert_eq!(text(|o| alarm(o, ALARM_SOFT_LIMIT)), "ALARM:2\r\n[MSG:Reset to continue]\r\n");
        assert_eq!(text(|o| alarm(o, ALARM_STEP_LOSS)), "ALARM:17\r\n[MSG:Reset to continue]\r\n");
        for code in 1..=20 {
            assert_eq!(text(|o| alarm(o, code)).len(), alarm_len(code), "ALARM:{code}");
        }
    }

    #[test]
    fn worst_case_lines_fit_their_budgets() {
        let far = [-1_000_000.0; 7];
        let ov = Some(Overrides { feed: 200, rapid: 100, spindle: 200 });
        let st = Status {
            state: b"Hold:1",
            pos: &far,
            mpos: false,
            bf: Some((16, 128)),
            feed: 999_999.0,
            speed: 1e6,
            acc: b"SFM",
            pins: 7,
            wco: Some(&far),
            ov,
            enc: Some((-999_999_999_999.999, -999_999_999_999_999.0)),
        };
        assert!(text(|o| status(o, &st)).len() <= status_len(7));
        let mut off = Offsets::<7>::default();
        off.g92 = far;
        assert!(text(|o| param::<7>(o, 8, &off, 7)).len() <= param_len(7));
        assert!(text(|o| setting(o, 139, 100_000_000.0, 3)).len() <= SETTING_LEN);
    }
}
